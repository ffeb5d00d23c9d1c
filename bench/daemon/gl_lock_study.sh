#!/usr/bin/env bash
# A light GL session beside a heavy one: how long the light one waits for the GL lock
# (docs/daemon.md, "Sessions and the GL driver"). Per run, a fresh far-daemon; one client steps
# `far` at 256^2 on a random soup for 5 s alone, then for 8 s while a second client steps a heavy
# scene on the GL path; then (LIGHT_CPU=1) a light CPU client (`bvh`, a random soup, a new
# session: its first step makes a GL context too) for 8 s beside the same heavy client. The
# daemon binaries given alternate, ROUNDS times each; one table row per run. Run it in a network
# namespace:
#   deploy/netns-run.sh bench/daemon/gl_lock_study.sh ROUNDS DAEMON...   (FAR_CLIENT: the far-client to use)
#   e.g. cp build/release/server/far-daemon /tmp/before   (then rebuild the change)
#        deploy/netns-run.sh bench/daemon/gl_lock_study.sh 4 /tmp/before build/release/server/far-daemon
# The heavy client, by default `far` at 2048^2 on two Stanford bunnies of 180,026 triangles each
# (about 0.6 s a step on llvmpipe), is set by HEAVY_KIND (bunnies, or scaling: far-client
# make-scene's ScalingScene of HEAVY_TRIANGLES) and HEAVY_ARGS (far-client load's flags), e.g.
#   HEAVY_KIND=scaling HEAVY_TRIANGLES=200000 HEAVY_ARGS='--method far --resolution 1024' LIGHT_CPU=1
set -euo pipefail
if [[ $# -lt 2 ]]; then
  sed -n '2,17p' "$0" >&2
  exit 2
fi
rounds=$1
shift
client=${FAR_CLIENT:-build/release/tools/far-client/far-client}
heavy_kind=${HEAVY_KIND:-bunnies}
heavy_args=${HEAVY_ARGS:---method far --resolution 2048}
light_cpu=${LIGHT_CPU:-0}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
if [[ $heavy_kind == scaling ]]; then
  "$client" make-scene --kind scaling --triangles "${HEAVY_TRIANGLES:-200000}" --frames 1 \
    "$work/heavy/scene.json" >/dev/null
else
  "$client" make-scene --kind bunnies --subdivision 7 --frames 40 "$work/heavy/scene.json" >/dev/null
fi

# The first value of "key" in a far-client load --json report: the "overall" block's.
field() { awk -v key="\"$2\":" '$1 == key { gsub(",", "", $2); print $2; exit }' "$1"; }
row() {
  printf '%.1f | %.1f | %.1f | %.1f' "$(field "$1" steps_per_s)" "$(field "$1" p50_ms)" \
    "$(field "$1" p99_ms)" "$(field "$1" max_ms)"
}

cpu_header='' cpu_rule=''
if [[ $light_cpu == 1 ]]; then
  cpu_header=' light CPU beside heavy: steps/s | p50 ms | p99 ms | max ms |'
  cpu_rule=' --: | --: | --: | --: |'
fi
echo "# heavy: $heavy_kind ${HEAVY_TRIANGLES:-} $heavy_args; $(nproc) cores; $(date -u '+%Y-%m-%d %H:%M UTC'); load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "| round | daemon | light alone: steps/s | p50 ms | p99 ms | max ms | light beside heavy: steps/s | p50 ms | p99 ms | max ms |$cpu_header heavy: steps/s | heavy: errors |"
echo "| --: | --- | --: | --: | --: | --: | --: | --: | --: | --: |$cpu_rule --: | --: |"
for round in $(seq "$rounds"); do
  for daemon in "$@"; do
    run="$work/run-$round-$(basename "$daemon")-$RANDOM"
    mkdir -p "$run"
    "$daemon" --socket "$run/far.sock" --log-level warn >"$run/daemon.log" 2>&1 &
    pid=$!
    far() { "$client" --socket "$run/far.sock" "$@"; }
    far --connect-timeout 20s ping >/dev/null
    far load --clients 1 --steps 0 --seconds 5 --method far --resolution 256 --json >"$run/alone.json"
    heavy_seconds=14
    [[ $light_cpu == 1 ]] && heavy_seconds=22
    # shellcheck disable=SC2086  # heavy_args: several flags
    far load --clients 1 --steps 0 --seconds "$heavy_seconds" $heavy_args \
      --scene "$work/heavy/scene.json" --json >"$run/heavy.json" &
    heavy=$!
    sleep 3
    far load --clients 1 --steps 0 --seconds 8 --method far --resolution 256 --json >"$run/beside.json"
    cpu_row=''
    if [[ $light_cpu == 1 ]]; then
      far load --clients 1 --steps 0 --seconds 8 --method bvh --json >"$run/cpu.json"
      cpu_row=" $(row "$run/cpu.json") |"
    fi
    wait "$heavy"
    kill "$pid"
    wait "$pid" || true
    printf '| %s | %s | %s | %s |%s %.2f | %s |\n' "$round" "$daemon" "$(row "$run/alone.json")" \
      "$(row "$run/beside.json")" "$cpu_row" "$(field "$run/heavy.json" steps_per_s)" \
      "$(field "$run/heavy.json" errors)"
  done
done
