#!/usr/bin/env bash
# Writes the committed seed corpora tests/fuzz/corpus/<target>/ from what the repository's
# tests use: the files of tests/data, the protocol tests' sample messages encoded, whole client
# sessions as datagram and ring-operation sequences (far_fuzz_make_seeds, built from
# make_seeds.cc), and the daemon configurations of tests/server/daemon_config_test.cc.
#   bash tests/fuzz/make_corpus.sh [build folder, default build/fuzz]
# bvh_reference's seeds (small scenes: a crossing, a coplanar overlap, a corner carried through
# rotated poses far from the origin and at a tiny scale, a distance query on refit trees) and
# cpu_methods' (a few steps of updates) are written below as bytes.
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
mkdir -p "$out"/{obj_reader,ply_reader,stl_reader,scene_reader,daemon_config,bvh_reference,cpu_methods,gl_methods,gpu_method}
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
  '{"name": "gpu-0", "gpu_id": "GPU-6f0e2b1c", "serves_gpus": ["0", "0000:3b:00.0"]}'
  '{"max_sesions": 3}'
  '{"ring_bytes": 100000}'
  '{"max_triangles_per_session": 9223372036854775807, "max_requests_per_second": 1e300}'
  '[1, 2]'
  '{}'
)
for i in "${!configs[@]}"; do printf '%s\n' "${configs[$i]}" >"$out/daemon_config/config_$i.json"; done

# hex_seed TARGET NAME HEX: writes the bytes HEX (spaces ignored) as seed NAME of TARGET.
hex_seed() {
  printf '%b' "$(echo "$3" | sed 's/ //g; s/\([0-9a-f][0-9a-f]\)/\\x\1/g')" >"$out/$1/$2"
}

# Seeds of bvh_reference (layout at the top of bvh_reference_fuzzer.cc).
#        flags e d n | per object: v t pose quaternion translation | corners (kind xyz) | triangle
hex_seed bvh_reference crossing_at_grid_points \
  "00 00 00 00  00 00 01 00000000 000000 00000000 00100000 00001000 000102 \
                00 00 01 00000000 000000 000404f8 00060408 00040608 000102"
hex_seed bvh_reference coplanar_overlap \
  "00 00 00 00  00 00 01 00000000 000000 00000000 00100000 00001000 000102 \
                00 00 01 00000000 000000 00040400 00140400 00041400 000102"
hex_seed bvh_reference corner_carried_through_rotated_poses_at_1e6 \
  "20 00 00 00  00 00 00 0a03fc07 010203 00000000 00100000 00001000 000102 \
                00 00 00 05fe0901 000000 80       00080810 00f80810 000102"
hex_seed bvh_reference corner_carried_through_rotated_poses_near_2^-256 \
  "00 be 00 00  00 00 00 0a03fc07 010203 00000000 00100000 00001000 000102 \
                00 00 00 05fe0901 000000 80       00080810 00f80810 000102"
hex_seed bvh_reference distance_refit_three_objects \
  "03 02 08 01  00 00 01 00000000 000000 00000000 00100000 00001000 000102 \
                00 00 01 00000000 000001 00000000 00100000 00001000 000102 \
                00 00 00 01010000 000000 000000f8 000800f8 000008f8 000102"

# Seeds of cpu_methods (layout at the top of cpu_methods_fuzzer.cc).
#        flags e d n | per object: motion v t quaternion translation | corners | triangle
#        | per later step, per object: change and its pose or corners
hex_seed cpu_methods static_and_rigid_crossing_then_moved_and_readded \
  "06 00 00 00  00 00 00 00000000 000000 000000 100000 001000 000102 \
                01 00 00 00000000 000000 0404f8 040408 080408 000102 \
                00 01 0a03fc07 010203  03 00  00 02"
hex_seed cpu_methods deformable_and_rigid_distance_near_2^-256 \
  "03 be 10 00  02 00 00 00000000 000000 000000 100000 001000 000102 \
                01 00 00 05fe0901 000001 000000 100000 001000 000102 \
                02 000001 100001 001001  01 00000000 000002"

# Seeds of gl_methods: a culling byte, a resolution byte and a sub-object byte (layout at the
# top of gl_methods_fuzzer.cc), then a cpu_methods scene.
#        culling res k | flags e d n | per object: ... as cpu_methods
hex_seed gl_methods far_id_buffer_depth16_static_and_rigid_crossing \
  "00 03 00  06 00 00 00  00 00 00 00000000 000000 000000 100000 001000 000102 \
                          01 00 00 00000000 000000 0404f8 040408 080408 000102 \
                          00 01 0a03fc07 010203  03 00  00 02"
hex_seed gl_methods far_exact_offset_queries_depth24_distance_near_2^-256 \
  "07 02 01  03 be 10 00  02 00 00 00000000 000000 000000 100000 001000 000102 \
                          01 00 00 05fe0901 000001 000000 100000 001000 000102 \
                          02 000001 100001 001001  01 00000000 000002"
hex_seed gl_methods far_depth32f_shifted_1e6_static_and_rigid_crossing \
  "48 05 03  06 00 00 00  00 00 00 00000000 000000 000000 100000 001000 000102 \
                          01 00 00 00000000 000000 0404f8 040408 080408 000102 \
                          00 01 0a03fc07 010203  03 00  00 02"
# Points at the origin on a tilted object whose unused vertices reach 2 units away: the
# object's float margin dwarfed the view (fixed in gpu_culler.cc, ProjectionHoldingMargins).
hex_seed gl_methods far_tilted_points_beside_unused_vertices \
  "00 00 00  01 01 00 00  00 03 06 f1090200 000000 000000 000000 000000 000010 000000 1000cd \
                          000102 020000 040101 000000 000000 020000 000000 \
                          00 00 00 00000000 000000 000000 000000 000000 000102"

# Seeds of gpu_method: a shift byte (layout at the top of gpu_method_fuzzer.cc), then a
# cpu_methods scene.
hex_seed gpu_method static_and_rigid_crossing \
  "00  06 00 00 00  00 00 00 00000000 000000 000000 100000 001000 000102 \
                    01 00 00 00000000 000000 0404f8 040408 080408 000102 \
                    00 01 0a03fc07 010203  03 00  00 02"
hex_seed gpu_method distance_near_2^-256 \
  "00  03 be 10 00  02 00 00 00000000 000000 000000 100000 001000 000102 \
                    01 00 00 05fe0901 000001 000000 100000 001000 000102 \
                    02 000001 100001 001001  01 00000000 000002"
hex_seed gpu_method shifted_1e7_static_and_rigid_crossing \
  "07  06 00 00 00  00 00 00 00000000 000000 000000 100000 001000 000102 \
                    01 00 00 00000000 000000 0404f8 040408 080408 000102 \
                    00 01 0a03fc07 010203  03 00  00 02"

for dir in tests/fuzz/regressions/*/; do
  target=$(basename "$dir")
  for file in "$dir"*; do cp "$file" "$out/$target/regression_$(basename "$file")"; done
done

echo "$(find "$out" -type f | wc -l) seeds, $(find "$out" -type f -printf '%s\n' | awk '{s += $1} END {print s}') bytes"
