// Converts the npm package `bunny` (Stanford bunny, positions/cells JSON) into bench/data/bunny.obj.
// Usage: cd /tmp && npm pack bunny && tar xzf bunny-1.0.1.tgz &&
//        node /path/to/bench/data/make_bunny_obj.js /tmp/package > bench/data/bunny.obj
"use strict";
const path = require("path");
const bunny = require(path.resolve(process.argv[2] || "package"));
const lines = [
  "# Stanford bunny (Stanford 3D Scanning Repository), from the npm package bunny@1.0.1",
  "# (license field: Public Domain); converted by bench/data/make_bunny_obj.js.",
  `# ${bunny.positions.length} vertices, ${bunny.cells.length} triangles.`,
];
for (const p of bunny.positions) lines.push(`v ${p[0]} ${p[1]} ${p[2]}`);
for (const c of bunny.cells) lines.push(`f ${c[0] + 1} ${c[1] + 1} ${c[2] + 1}`);
process.stdout.write(lines.join("\n") + "\n");
