#!/usr/bin/env bash
# Regenerates the committed seed corpora tests/fuzz/corpus/<target>/ from what the repository's
# tests use: the files of tests/data, the protocol tests' sample messages encoded, whole client
# sessions as datagram and ring-operation sequences (far_fuzz_make_seeds, built from
# make_seeds.cc), and the daemon configurations of tests/server/daemon_config_test.cc.
#   bash tests/fuzz/make_corpus.sh [build folder, default build/fuzz]
# Seeds are named after what they hold; keep the total small (well under 1 MB). Inputs that once
# crashed a target (tests/fuzz/regressions/<target>/, each also a unit test) are seeds too.
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build/fuzz}
out=tests/fuzz/corpus
data=tests/data/scenes/example

cmake --build "$build" --target far_fuzz_make_seeds >/dev/null
rm -rf "$out"
mkdir -p "$out"/{obj_reader,ply_reader,stl_reader,scene_reader,daemon_config}
"$build"/tests/fuzz/far_fuzz_make_seeds "$out"

cp "$data"/*.obj "$out"/obj_reader/
cp "$data"/*.ply "$out"/ply_reader/
cp "$data"/*.stl "$out"/stl_reader/
cp "$data"/scene.json "$out"/scene_reader/example_scene.json
cat >"$out"/scene_reader/minimal_scene.json <<'JSON'
{"format": "far-scene/1", "objects": [{"id": 0, "mesh": "chip.stl"}]}
JSON

# The configurations daemon_config_test.cc reads (good and bad), one per file.
configs=(
  '{"max_resolution": 512, "gl_platform": "surfaceless", "max_sessions": 3, "log_level": "debug", "lcm_url": "memq://"}'
  '{"name": "gpu-1", "socket_path": "/run/far/gpu-1.sock", "gpu": 0, "max_sessions_per_user": 2, "max_opens_per_second_per_user": 5}'
  '{"ring_bytes": 1048576, "reply_bytes": 65536, "max_requests_per_second": 100.5, "max_queued_per_session": 2, "step_deadline_ms": 1000, "heavy_step_ms": 20, "exact_threads": 2}'
  '{"max_triangles_per_session": 1000, "max_vertices_per_session": 3000, "max_objects_per_session": 10, "max_triangles_total": 5000, "max_vertices_total": 15000, "max_reply_pairs": 100, "gl_platform": "device"}'
  '{"max_sesions": 3}'
  '{"ring_bytes": 100000}'
  '{"max_triangles_per_session": 9223372036854775807, "max_requests_per_second": 1e300}'
  '[1, 2]'
  '{}'
)
for i in "${!configs[@]}"; do printf '%s\n' "${configs[$i]}" >"$out/daemon_config/config_$i.json"; done

for dir in tests/fuzz/regressions/*/; do
  target=$(basename "$dir")
  for file in "$dir"*; do cp "$file" "$out/$target/regression_$(basename "$file")"; done
done

echo "$(find "$out" -type f | wc -l) seeds, $(find "$out" -type f -printf '%s\n' | awk '{s += $1} END {print s}') bytes"
