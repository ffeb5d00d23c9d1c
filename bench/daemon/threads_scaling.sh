#!/usr/bin/env bash
# Steps/s of one process stepping N sessions from N threads (far-client load --clients N: each
# thread its own Client, session and 960-triangle soup), against one thread, with the CPU time
# per step of the daemon and of the client process. Runs are interleaved (the order of the
# thread counts rotates every repetition) and each count's median, min and max are printed as a
# markdown table (bench/RESULTS.md, "Many threads, many sessions in one process").
#   bash bench/daemon/threads_scaling.sh [BUILD_DIR] [REPS] [SECONDS] [METHOD] [COUNTS...]
#   bash bench/daemon/threads_scaling.sh build/release 5 3 bvh 1 2 4 8
# The daemon runs on its default renderer (llvmpipe without a GPU), in a private network
# namespace (deploy/netns-run.sh): no datagram leaves loopback. FAR_DAEMON_ARGS adds daemon flags
# (FAR_DAEMON_ARGS="--threads 1": one thread per step, no CPU pool); FAR_LOAD_ARGS adds
# far-client load flags (FAR_LOAD_ARGS="--scene S": each thread steps scene S, not a soup).
set -euo pipefail
cd "$(dirname "$0")/../.."
if [ "${FAR_IN_NETNS:-}" != 1 ]; then exec deploy/netns-run.sh bash "$0" "$@"; fi
build=${1:-build/release}
reps=${2:-5}
seconds=${3:-3}
method=${4:-bvh}
shift $(($# < 4 ? $# : 4))
counts=("$@")
[ ${#counts[@]} -gt 0 ] || counts=(1 2 4 8)
daemon=$build/server/far-daemon
client=$build/tools/far-client/far-client
work=$(mktemp -d)
trap 'kill "$pid" 2>/dev/null; wait "$pid" 2>/dev/null; rm -rf "$work"' EXIT
# shellcheck disable=SC2086
"$daemon" --socket "$work/far.sock" --log-level warn ${FAR_DAEMON_ARGS:-} >"$work/daemon.log" 2>&1 &
pid=$!
for _ in $(seq 200); do "$client" --socket "$work/far.sock" ping >"$work/ping" 2>&1 && break; sleep 0.1; done
echo "nproc $(nproc); $(cat "$work/ping")"
tick=$(getconf CLK_TCK)
daemon_cpu() { awk '{print $14 + $15}' "/proc/$pid/stat"; }
# A warm-up run: the first sessions' setup is not part of any measurement.
"$client" --socket "$work/far.sock" load --clients 2 --seconds 1 --method "$method" >/dev/null
for ((r = 0; r < reps; r++)); do
  n=${#counts[@]}
  for ((i = 0; i < n; i++)); do
    c=${counts[$(((i + r) % n))]}
    d0=$(daemon_cpu)
    # shellcheck disable=SC2086
    /usr/bin/time -f "%U %S" -o "$work/time" "$client" --socket "$work/far.sock" load \
      --clients "$c" --seconds "$seconds" --method "$method" ${FAR_LOAD_ARGS:-} --json >"$work/out.json"
    d1=$(daemon_cpu)
    python3 - "$c" "$work/out.json" "$work/time" "$d0" "$d1" "$tick" >>"$work/runs" <<'EOF'
import json, sys
c, out, t, d0, d1, tick = sys.argv[1:]
o = json.load(open(out))["overall"]
user, sys_ = map(float, open(t).read().split()[-2:])
steps = max(o["steps"], 1)
print(c, o["steps_per_s"], o["p50_ms"], (float(d1) - float(d0)) / float(tick) * 1e3 / steps,
      (user + sys_) * 1e3 / steps, o["errors"])
EOF
    tail -1 "$work/runs" | awk '{printf "rep %d threads %s: %.0f steps/s (p50 %.2f ms; CPU per step: daemon %.2f ms, client %.2f ms; errors %d)\n", '"$r"', $1, $2, $3, $4, $5, $6}'
  done
done
python3 - "$work/runs" <<'EOF'
import statistics, sys
runs = {}
for line in open(sys.argv[1]):
    c, sps, p50, dcpu, ccpu, err = line.split()
    runs.setdefault(int(c), []).append((float(sps), float(p50), float(dcpu), float(ccpu), int(err)))
base = statistics.median(r[0] for r in runs[min(runs)])
print()
print("| threads | steps/s median | min - max | vs 1 thread | p50 ms | daemon CPU ms/step | client CPU ms/step | errors |")
print("|--:|--:|--:|--:|--:|--:|--:|--:|")
for c in sorted(runs):
    r = runs[c]
    sps = [x[0] for x in r]
    med = statistics.median(sps)
    print(f"| {c} | {med:.0f} | {min(sps):.0f} - {max(sps):.0f} | {med / base:.2f}x | "
          f"{statistics.median(x[1] for x in r):.2f} | {statistics.median(x[2] for x in r):.2f} | "
          f"{statistics.median(x[3] for x in r):.2f} | {sum(x[4] for x in r)} |")
EOF
