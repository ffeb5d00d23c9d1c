#!/usr/bin/env bash
# Writes the committed seed corpora tests/fuzz/corpus/<target>/ from what the repository's
# tests use: the files of tests/data, the protocol tests' sample messages encoded, whole client
# sessions as datagram and ring-operation sequences (far_fuzz_make_seeds, built from
# make_seeds.cc), and the daemon configurations of tests/server/daemon_config_test.cc.
#   bash tests/fuzz/make_corpus.sh [build folder, default build/fuzz]
# bvh_reference's seeds (small scenes: a crossing, a coplanar overlap, a corner carried through
# rotated poses far from the origin and at a tiny scale, a distance query on refit trees) are
# written below as bytes.
# It overwrites the seeds it writes and deletes nothing: the inputs a long run added (named by
# their SHA-1, such as daemon_datagram's) stay. Seeds are named after what they hold; keep the
# total small (well under 1 MB). Inputs that once crashed a target
# (tests/fuzz/regressions/<target>/, each also a unit test) are seeds too.
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build/fuzz}
out=tests/fuzz/corpus
data=tests/data/scenes/example

cmake --build "$build" --target far_fuzz_make_seeds >/dev/null
mkdir -p "$out"/{obj_reader,ply_reader,stl_reader,scene_reader,daemon_config,bvh_reference}
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

# Seeds of bvh_reference (layout at the top of bvh_reference_fuzzer.cc), as hex bytes.
bvh_seed() {
  printf '%b' "$(echo "$2" | sed 's/ //g; s/\([0-9a-f][0-9a-f]\)/\\x\1/g')" >"$out/bvh_reference/$1"
}
#        flags e d n | per object: v t pose quaternion translation | corners (kind xyz) | triangle
bvh_seed crossing_at_grid_points \
  "00 00 00 00  00 00 01 00000000 000000 00000000 00100000 00001000 000102 \
                00 00 01 00000000 000000 000404f8 00060408 00040608 000102"
bvh_seed coplanar_overlap \
  "00 00 00 00  00 00 01 00000000 000000 00000000 00100000 00001000 000102 \
                00 00 01 00000000 000000 00040400 00140400 00041400 000102"
bvh_seed corner_carried_through_rotated_poses_at_1e6 \
  "20 00 00 00  00 00 00 0a03fc07 010203 00000000 00100000 00001000 000102 \
                00 00 00 05fe0901 000000 80       00080810 00f80810 000102"
bvh_seed corner_carried_through_rotated_poses_near_2^-256 \
  "00 be 00 00  00 00 00 0a03fc07 010203 00000000 00100000 00001000 000102 \
                00 00 00 05fe0901 000000 80       00080810 00f80810 000102"
bvh_seed distance_refit_three_objects \
  "03 02 08 01  00 00 01 00000000 000000 00000000 00100000 00001000 000102 \
                00 00 01 00000000 000001 00000000 00100000 00001000 000102 \
                00 00 00 01010000 000000 000000f8 000800f8 000008f8 000102"

for dir in tests/fuzz/regressions/*/; do
  target=$(basename "$dir")
  for file in "$dir"*; do cp "$file" "$out/$target/regression_$(basename "$file")"; done
done

echo "$(find "$out" -type f | wc -l) seeds, $(find "$out" -type f -printf '%s\n' | awk '{s += $1} END {print s}') bytes"
