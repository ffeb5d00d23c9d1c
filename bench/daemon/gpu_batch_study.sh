#!/usr/bin/env bash
# The gpu method's steps of many clients with far-daemon --gpu-batch true (every session's GPU
# work from one thread and context, the steps that wait issued together) against false (each
# session on its own context, in turns under the GL lock): two daemons, the runs interleaved
# (the order alternates every repetition), each far-client load run's steps/s, latencies and the
# daemon's CPU per step, then each setting's median, min and max as a markdown table
# (bench/RESULTS.md, "Many sessions, one GPU").
#   bash bench/daemon/gpu_batch_study.sh [BUILD_DIR] [REPS] [SECONDS] [CLIENTS]
#   bash bench/daemon/gpu_batch_study.sh build/release 5 6 16
# FAR_LOAD_ARGS gives far-client load flags (default: --scene of the far-client make-scene kind
# FAR_SCENE_KIND, default leaves: the paper's 42K triangles); FAR_DAEMON_ARGS adds daemon flags to both daemons. The daemons run
# on their default renderer (llvmpipe without a GPU) in a private network namespace
# (deploy/netns-run.sh): no datagram leaves loopback.
set -euo pipefail
cd "$(dirname "$0")/../.."
if [ "${FAR_IN_NETNS:-}" != 1 ]; then exec deploy/netns-run.sh bash "$0" "$@"; fi
build=${1:-build/release}
reps=${2:-5}
seconds=${3:-6}
clients=${4:-16}
daemon=$build/server/far-daemon
client=$build/tools/far-client/far-client
work=$(mktemp -d)
pids=()
trap 'kill "${pids[@]}" 2>/dev/null; wait 2>/dev/null; rm -rf "$work"' EXIT
load_args=${FAR_LOAD_ARGS:-}
if [ -z "$load_args" ]; then
  "$client" make-scene --kind "${FAR_SCENE_KIND:-leaves}" --frames 200 "$work/scene.json" >/dev/null
  load_args="--scene $work/scene.json"
fi
for batch in true false; do
  # shellcheck disable=SC2086
  "$daemon" --name "batch-$batch" --socket "$work/$batch.sock" --gpu-batch "$batch" --log-level warn \
    --metrics-file "$work/$batch.prom" --metrics-interval-s 0.5 ${FAR_DAEMON_ARGS:-} >"$work/$batch.log" 2>&1 &
  pids+=($!)
  eval "pid_$batch=$!"
done
for batch in true false; do
  for _ in $(seq 300); do "$client" --socket "$work/$batch.sock" ping >"$work/ping" 2>&1 && break; sleep 0.1; done
  # A warm-up run: the sessions' setup (kernels, the driver's self-check) is not measured.
  # shellcheck disable=SC2086
  "$client" --socket "$work/$batch.sock" load --clients 2 --seconds 1 --method gpu $load_args >/dev/null
done
echo "nproc $(nproc); $(cat "$work/ping")"
tick=$(getconf CLK_TCK)
daemon_cpu() { awk '{print $14 + $15}' "/proc/$1/stat"; }
for ((r = 0; r < reps; r++)); do
  order=(true false)
  [ $((r % 2)) -eq 1 ] && order=(false true)
  for batch in "${order[@]}"; do
    pid_var=pid_$batch
    pid=${!pid_var}
    d0=$(daemon_cpu "$pid")
    # shellcheck disable=SC2086
    "$client" --socket "$work/$batch.sock" load --clients "$clients" --seconds "$seconds" \
      --method gpu $load_args --json >"$work/out.json"
    d1=$(daemon_cpu "$pid")
    /usr/bin/python3 - "$batch" "$work/out.json" "$d0" "$d1" "$tick" >>"$work/runs" <<'EOF'
import json, sys
batch, out, d0, d1, tick = sys.argv[1:]
o = json.load(open(out))["overall"]
steps = max(o["steps"], 1)
print(batch, o["steps_per_s"], o["p50_ms"], o["p99_ms"],
      (float(d1) - float(d0)) / float(tick) * 1e3 / steps, o["errors"])
EOF
    tail -1 "$work/runs" | awk '{printf "rep %d gpu_batch %s: %.0f steps/s (p50 %.2f ms, p99 %.2f ms; daemon CPU per step %.2f ms; errors %d)\n", '"$r"', $1, $2, $3, $4, $5, $6}'
  done
done
sleep 1  # the metrics file's next rewrite
/usr/bin/python3 - "$work/runs" "$clients" "$work/true.prom" <<'EOF'
import re, statistics, sys
runs = {}
for line in open(sys.argv[1]):
    b, sps, p50, p99, cpu, err = line.split()
    runs.setdefault(b, []).append((float(sps), float(p50), float(p99), float(cpu), int(err)))
print(f"\n| --gpu-batch | clients | steps/s median [min-max] | p50 ms | p99 ms | daemon CPU ms/step | errors |")
print("|---|--:|--:|--:|--:|--:|--:|")
for b in ("true", "false"):
    rows = runs[b]
    sps = [r[0] for r in rows]
    med = lambda k: statistics.median(r[k] for r in rows)
    print(f"| {b} | {sys.argv[2]} | {statistics.median(sps):.0f} [{min(sps):.0f}-{max(sps):.0f}] | "
          f"{med(1):.2f} | {med(2):.2f} | {med(3):.2f} | {sum(r[4] for r in rows)} |")
if "true" in runs and "false" in runs:
    t = statistics.median(r[0] for r in runs["true"])
    f = statistics.median(r[0] for r in runs["false"])
    print(f"\nbatched / in turns: {t / f:.2f}x")
metrics = open(sys.argv[3]).read()
count = lambda name: float(re.search(name + r"\{[^}]*\} (\S+)", metrics).group(1))
steps, batches = count("far_gpu_batched_steps_total"), count("far_gpu_batches_total")
print(f"--gpu-batch true: {steps:.0f} steps in {batches:.0f} batches, {steps / max(batches, 1):.2f} steps a batch")
EOF
