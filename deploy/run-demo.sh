#!/usr/bin/env bash
# The main job, from a fresh Debian 12 machine: installs what it needs, builds far-daemon and
# far-client, starts the daemon on the embedded default (Mesa llvmpipe through EGL when there
# is no GPU) and runs a demo through it with several simulator clients at once:
#   - two "tree with falling leaves" simulators (a static tree, deformable leaves sending new
#     vertices every step, and a rigid vase that falls and breaks into fragments: objects
#     removed and added), each in its own session;
#   - a load client with three more sessions of rigid objects moving by poses.
# Everything LCM sends stays inside a private network namespace (deploy/netns-run.sh).
#   bash deploy/run-demo.sh [--frames N] [--leaves N] [--resolution N]
set -euo pipefail
cd "$(dirname "$0")/.."
frames=20
leaves=30
resolution=512
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) frames=$2; shift 2 ;;
    --leaves) leaves=$2; shift 2 ;;
    --resolution) resolution=$2; shift 2 ;;
    *) echo "usage: $0 [--frames N] [--leaves N] [--resolution N]" >&2; exit 2 ;;
  esac
done

bash deploy/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release --target far-daemon far-client -j "$(nproc)"

export FAR_BIN=build/release FAR_FRAMES=$frames FAR_LEAVES=$leaves FAR_RESOLUTION=$resolution
exec deploy/netns-run.sh bash -c '
  set -euo pipefail
  work=$(mktemp -d)
  # A daemon of its own (its own socket), whatever else runs on this machine.
  "$FAR_BIN/server/far-daemon" --socket "$work/far.sock" --log-level info >"$work/daemon.log" 2>&1 &
  daemon=$!
  trap "kill $daemon 2>/dev/null || true; rm -rf $work" EXIT
  far_client() { "$FAR_BIN/client/far-client" --socket "$work/far.sock" "$@"; }
  far_client --connect-timeout 20s ping
  far_client make-scene "$work/demo/scene.json" --leaves "$FAR_LEAVES" --frames "$FAR_FRAMES"

  echo "== three simulators at once: two tree-and-leaves scenes (one with distance queries) and a load client"
  far_client play "$work/demo/scene.json" --resolution "$FAR_RESOLUTION" \
      | sed "s/^/[leaves-1] /" &
  a=$!
  far_client play "$work/demo/scene.json" --resolution "$FAR_RESOLUTION" --distance 0.05 \
      | sed "s/^/[leaves-2 D=0.05] /" &
  b=$!
  far_client load --clients 3 --steps 15 --resolution 256 | sed "s/^/[load] /" &
  c=$!
  wait $a $b $c

  echo "== daemon status"
  far_client status
  kill -TERM $daemon
  wait $daemon
  echo "== daemon log (last lines)"
  tail -n 8 "$work/daemon.log"
'
