#!/usr/bin/env bash
# far-daemon's time from exec to its daemon_ready line, with auto's GPU cost measured at start
# (--gpu-cost-cache off) and read from a cache file a first start wrote (docs/daemon.md, "The
# GPU cost at start-up"): the two interleaved, REPS each, then each one's median, min and max
# (bench/RESULTS.md, "The daemon's start").
#   bash bench/daemon/start_time_study.sh [BUILD_DIR] [REPS]
#   bash bench/daemon/start_time_study.sh build/release 5
# On the default renderer (llvmpipe without a GPU), in a private network namespace
# (deploy/netns-run.sh): no datagram leaves loopback.
set -euo pipefail
cd "$(dirname "$0")/../.."
if [ "${FAR_IN_NETNS:-}" != 1 ]; then exec deploy/netns-run.sh bash "$0" "$@"; fi
daemon=${1:-build/release}/server/far-daemon
reps=${2:-5}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Starts the daemon with `--gpu-cost-cache $1`, prints the ms until daemon_ready and stops it.
ready_ms() {
  local start end pid
  start=$(date +%s%N)
  "$daemon" --socket "$work/far.sock" --gpu-cost-cache "$1" >"$work/log" 2>&1 &
  pid=$!
  until grep -q event=daemon_ready "$work/log"; do
    kill -0 "$pid" 2>/dev/null || { cat "$work/log" >&2; exit 1; }
    sleep 0.005
  done
  end=$(date +%s%N)
  kill "$pid"
  wait "$pid" || true
  echo $(((end - start) / 1000000))
}

ready_ms "$work/costs.json" >/dev/null  # writes the cache
declare -A times
for rep in $(seq "$reps"); do
  # The order alternates every repetition.
  order="off cached"
  [ $((rep % 2)) = 1 ] || order="cached off"
  for mode in $order; do
    cache=off
    [ "$mode" = off ] || cache=$work/costs.json
    times[$mode]+="$(ready_ms "$cache") "
  done
done
echo "| gpu cost | ms to daemon_ready, median [min-max] | runs |"
echo "|---|--:|--:|"
for mode in off cached; do
  # shellcheck disable=SC2086 # the times are a list
  sorted=$(printf '%s\n' ${times[$mode]} | sort -n)
  n=$(wc -l <<<"$sorted")
  echo "| $([ "$mode" = off ] && echo "measured (off)" || echo cached) | $(sed -n "$(((n + 1) / 2))p" <<<"$sorted") [$(head -1 <<<"$sorted")-$(tail -1 <<<"$sorted")] | $n |"
done
