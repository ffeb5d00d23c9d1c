#!/usr/bin/env bash
# A light GL session beside a heavy one: how long the light one waits for the GL lock
# (docs/daemon.md, "Sessions and the GL driver"). Per run, a fresh far-daemon; one client steps
# `far` at 256^2 on a random soup for 5 s alone, then for 8 s while a second client steps `far`
# at 2048^2 on two Stanford bunnies of 180,026 triangles each (about 0.6 s a step on llvmpipe).
# The daemon binaries given alternate, ROUNDS times each; one table row per run. Run it in a
# network namespace:
#   deploy/netns-run.sh bench/daemon/gl_lock_study.sh ROUNDS DAEMON...   (FAR_CLIENT: the far-client to use)
#   e.g. cp build/release/server/far-daemon /tmp/before   (then rebuild the change)
#        deploy/netns-run.sh bench/daemon/gl_lock_study.sh 4 /tmp/before build/release/server/far-daemon
set -euo pipefail
if [[ $# -lt 2 ]]; then
  sed -n '2,10p' "$0" >&2
  exit 2
fi
rounds=$1
shift
client=${FAR_CLIENT:-build/release/tools/far-client/far-client}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$client" make-scene --kind bunnies --subdivision 7 --frames 40 "$work/heavy/scene.json" >/dev/null

# The first value of "key" in a far-client load --json report: the "overall" block's.
field() { awk -v key="\"$2\":" '$1 == key { gsub(",", "", $2); print $2; exit }' "$1"; }
row() { printf '%.1f | %.1f | %.1f' "$(field "$1" steps_per_s)" "$(field "$1" p50_ms)" "$(field "$1" p99_ms)"; }

echo "| round | daemon | light alone: steps/s | p50 ms | p99 ms | light beside heavy: steps/s | p50 ms | p99 ms | heavy: steps/s |"
echo "| --: | --- | --: | --: | --: | --: | --: | --: | --: |"
for round in $(seq "$rounds"); do
  for daemon in "$@"; do
    run="$work/run-$round-$(basename "$daemon")-$RANDOM"
    mkdir -p "$run"
    "$daemon" --socket "$run/far.sock" --log-level warn >"$run/daemon.log" 2>&1 &
    pid=$!
    far() { "$client" --socket "$run/far.sock" "$@"; }
    far --connect-timeout 20s ping >/dev/null
    far load --clients 1 --steps 0 --seconds 5 --method far --resolution 256 --json >"$run/alone.json"
    far load --clients 1 --steps 0 --seconds 14 --method far --resolution 2048 \
      --scene "$work/heavy/scene.json" --json >"$run/heavy.json" &
    heavy=$!
    sleep 3
    far load --clients 1 --steps 0 --seconds 8 --method far --resolution 256 --json >"$run/beside.json"
    wait "$heavy"
    kill "$pid"
    wait "$pid" || true
    printf '| %s | %s | %s | %s | %.2f |\n' "$round" "$daemon" "$(row "$run/alone.json")" \
      "$(row "$run/beside.json")" "$(field "$run/heavy.json" steps_per_s)"
  done
done
