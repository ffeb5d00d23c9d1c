#!/usr/bin/env bash
# The main job, from a fresh Debian 12 machine: installs what it needs, builds far-daemon,
# far-client and far-snapshot, starts the daemon on the embedded default (Mesa llvmpipe through EGL when there
# is no GPU) and runs a demo through it with several simulator clients at once:
#   - two "tree with falling leaves" simulators (a static tree, deformable leaves sending new
#     vertices every step, and a rigid vase that falls and breaks into fragments: objects
#     removed and added), each in its own session; the first lists every step's contacts by
#     object ("leaf-12 touches tree (16 triangle pairs)"), both say when the vase breaks;
#   - a load client with three more sessions of rigid objects moving by poses.
# Every step line names the method that answered it (and, under auto, why it was chosen when
# the choice changes); the load client ends with the steps each method answered.
# Each client's lines appear as they happen, prefixed with its name. Then two pictures (PNG)
# of the scene, the step before the vase breaks and the step it breaks, with the potentially
# colliding triangles yellow and the contact triangles red (far-snapshot).
# Everything LCM sends stays inside a private network namespace (deploy/netns-run.sh).
#   bash deploy/run-demo.sh [--frames N] [--leaves N] [--resolution N] [--out DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
frames=20
leaves=30
resolution=512
out=build/demo
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) frames=$2; shift 2 ;;
    --leaves) leaves=$2; shift 2 ;;
    --resolution) resolution=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    *) echo "usage: $0 [--frames N] [--leaves N] [--resolution N] [--out DIR]" >&2; exit 2 ;;
  esac
done

bash deploy/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release --target far-daemon far-client far-snapshot -j "$(nproc)"
mkdir -p "$out"

export FAR_BIN=build/release FAR_FRAMES=$frames FAR_LEAVES=$leaves FAR_RESOLUTION=$resolution
FAR_OUT=$(cd "$out" && pwd)
export FAR_OUT
exec deploy/netns-run.sh bash -c '
  set -euo pipefail
  work=$(mktemp -d)
  # A daemon of its own (its own socket), whatever else runs on this machine.
  "$FAR_BIN/server/far-daemon" --socket "$work/far.sock" --log-level info >"$work/daemon.log" 2>&1 &
  daemon=$!
  trap "kill $daemon 2>/dev/null || true; rm -rf $work" EXIT
  far_client() { "$FAR_BIN/tools/far-client/far-client" --socket "$work/far.sock" "$@"; }
  far_snapshot() { "$FAR_BIN/tools/far-snapshot/far-snapshot" "$@"; }
  far_client --connect-timeout 20s ping
  far_client make-scene "$work/demo/scene.json" --leaves "$FAR_LEAVES" --frames "$FAR_FRAMES"

  # far-client writes each line as it is done (line-buffered stdout); tee and sed -u pass it on
  # at once, so the three clients interleave as they run.
  echo "== three simulators at once: two tree-and-leaves scenes (one listing its contacts, one with distance queries) and a load client"
  far_client play "$work/demo/scene.json" --resolution "$FAR_RESOLUTION" --contacts 2>&1 \
      | tee "$work/leaves-1.log" | sed -u "s/^/[leaves-1] /" &
  a=$!
  far_client play "$work/demo/scene.json" --resolution "$FAR_RESOLUTION" --distance 0.05 2>&1 \
      | sed -u "s/^/[leaves-2 D=0.05] /" &
  b=$!
  far_client load --clients 3 --steps 15 --resolution 256 2>&1 | sed -u "s/^/[load] /" &
  c=$!
  wait $a $b $c

  # The step at which play said the vase broke, and the one before it.
  broke=$(sed -n "s/^frame *\([0-9]*\): vase breaks.*/\1/p" "$work/leaves-1.log" | head -n 1)
  if [ -n "$broke" ]; then
    echo "== pictures of the scene before and after the vase breaks (step $((broke - 1)) and step $broke; far-snapshot runs the step in process)"
    far_snapshot "$work/demo/scene.json" --frame $((broke - 1)) --png "$FAR_OUT/demo-before-break.png"
    far_snapshot "$work/demo/scene.json" --frame "$broke" --png "$FAR_OUT/demo-after-break.png"
  fi

  echo "== daemon status"
  far_client status
  kill -TERM $daemon
  wait $daemon
  echo "== daemon log (last lines)"
  tail -n 8 "$work/daemon.log"
'
