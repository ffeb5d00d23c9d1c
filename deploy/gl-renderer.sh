#!/usr/bin/env bash
# Prints the GL_RENDERER far-daemon gets on an EGL platform, read from its daemon_ready log line
# (an in-process LCM URL: no network needed); the daemon's own output goes to stderr. When the
# daemon made no GL context it prints nothing and exits with the daemon's own nonzero status
# (1 when the daemon did not stop by itself, or stopped with 0). Used by gpu-run.sh and by the
# ctest checks of the device platform.
#   deploy/gl-renderer.sh PLATFORM DAEMON_COMMAND...   (PLATFORM: device, surfaceless, auto)
#   deploy/gl-renderer.sh surfaceless env LD_LIBRARY_PATH=bundle/lib bundle/bin/far-daemon
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: $0 PLATFORM DAEMON_COMMAND..." >&2; exit 2; }
platform=$1
shift
log=$(mktemp)
trap 'rm -f "$log"' EXIT
# A name of its own (so its own socket): a daemon already serving, or another check started
# beside this one (ctest -j), holds the default name's socket.
"$@" --name "glr-$$" --lcm-url memq:// --gl-platform "$platform" --log-level info >"$log" 2>&1 &
pid=$!
for _ in $(seq 300); do
  grep -q event=daemon_ready "$log" && break
  kill -0 "$pid" 2>/dev/null || break
  sleep 0.1
done
status=0
if grep -q event=daemon_ready "$log" || kill -0 "$pid" 2>/dev/null; then
  kill "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  status=1
else
  wait "$pid" || status=$?
  [ "$status" -ne 0 ] || status=1
fi
cat "$log" >&2
# event=daemon_ready name=... socket=... gl_renderer="..." ...: the field, wherever it is.
renderer=$(sed -n '/event=daemon_ready/ s/.* gl_renderer="\([^"]*\)".*/\1/p' "$log")
[ -n "$renderer" ] || exit "$status"
echo "$renderer"
