#!/usr/bin/env bash
# One light session on a large scene beside light sessions that fill the cores, with and
# without the setup allowance (docs/daemon.md, "One-off work is not a step's cost"): the large
# scene's first step builds its hierarchies (hundreds of ms of CPU), its later steps take a few
# ms. Judged on its whole first step, it is demoted for good. The two daemons alternate, ROUNDS
# times each; prints one table row per run. Run it in a network namespace:
#   deploy/netns-run.sh bench/daemon/setup_allowance_study.sh [ROUNDS] [BUILD_DIR]
set -euo pipefail
rounds=${1:-3}
build=${2:-build/release}
client="$build/tools/far-client/far-client"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The large scene: two Stanford bunnies of 180,026 triangles each, one static, one moving
# through it (about 3,000 contacts a step); the light ones: the paper's falling leaves.
"$client" make-scene --kind bunnies --subdivision 7 --frames 40 "$work/large/scene.json" >/dev/null
"$client" make-scene --kind leaves --frames 40 "$work/light/scene.json" >/dev/null

# The first value of "key" in a far-client load --json report: the "overall" block's.
field() { awk -v key="\"$2\":" '$1 == key { gsub(",", "", $2); print $2; exit }' "$1"; }

echo "| round | setup_allowance_ms | large scene: steps/s | p50 ms | p99 ms | demoted | 4 light sessions: steps/s each (mean) |"
echo "| --: | --: | --: | --: | --: | --- | --: |"
for round in $(seq "$rounds"); do
  for allowance in 0 1000; do
    run="$work/run-$round-$allowance"
    mkdir -p "$run"
    echo "{\"setup_allowance_ms\": $allowance}" >"$run/far.json"
    "$build/server/far-daemon" --socket "$run/far.sock" --config "$run/far.json" \
      --log-level info >"$run/daemon.log" 2>&1 &
    daemon=$!
    "$client" --socket "$run/far.sock" --connect-timeout 20s ping >/dev/null
    "$client" --socket "$run/far.sock" load --clients 4 --steps 0 --seconds 12 --method bvh \
      --scene "$work/light/scene.json" --json >"$run/light.json" &
    light=$!
    sleep 1
    "$client" --socket "$run/far.sock" load --clients 1 --steps 0 --seconds 10 --method bvh \
      --scene "$work/large/scene.json" --json >"$run/large.json"
    wait "$light"
    kill "$daemon"
    wait "$daemon" || true
    demoted=no
    if grep -q "event=session_demoted" "$run/daemon.log"; then
      demoted="yes ($(grep -o 'step_ms=[0-9.]* step=[a-z]*' "$run/daemon.log" | head -1))"
    fi
    printf '| %s | %s | %.1f | %.1f | %.1f | %s | %.1f |\n' "$round" "$allowance" \
      "$(field "$run/large.json" steps_per_s)" "$(field "$run/large.json" p50_ms)" \
      "$(field "$run/large.json" p99_ms)" "$demoted" \
      "$(awk -v s="$(field "$run/light.json" steps_per_s)" 'BEGIN { print s / 4 }')"
  done
done
