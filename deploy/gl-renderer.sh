#!/usr/bin/env bash
# Prints the GL_RENDERER far-daemon gets on an EGL platform, read from its daemon_ready log line
# (an in-process LCM URL: no network needed); the daemon's own output goes to stderr. Exits 1
# when the daemon made no GL context. Used by gpu-run.sh; ctest runs it on the build's daemon.
#   deploy/gl-renderer.sh PLATFORM DAEMON_COMMAND...   (PLATFORM: device, surfaceless, auto)
#   deploy/gl-renderer.sh surfaceless env LD_LIBRARY_PATH=bundle/lib bundle/bin/far-daemon
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: $0 PLATFORM DAEMON_COMMAND..." >&2; exit 2; }
platform=$1
shift
log=$(mktemp)
trap 'rm -f "$log"' EXIT
"$@" --lcm-url memq:// --gl-platform "$platform" --log-level info >"$log" 2>&1 &
pid=$!
for _ in $(seq 300); do
  grep -q event=daemon_ready "$log" && break
  kill -0 "$pid" 2>/dev/null || break
  sleep 0.1
done
kill "$pid" 2>/dev/null || true
wait "$pid" 2>/dev/null || true
cat "$log" >&2
# event=daemon_ready name=... socket=... gl_renderer="..." ...: the field, wherever it is.
renderer=$(sed -n '/event=daemon_ready/ s/.* gl_renderer="\([^"]*\)".*/\1/p' "$log")
[ -n "$renderer" ] || exit 1
echo "$renderer"
