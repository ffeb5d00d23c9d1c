#!/usr/bin/env bash
# far-daemon --gl-platform device means a GPU: on a machine without one it must exit with status
# 1 and a message that says no GPU was found and lists what it tried (Mesa's software device
# among them), never serve on llvmpipe. Where a hardware EGL device exists the daemon starts on
# it; then this check cannot be made and is skipped (exit 77), after checking that the renderer
# it started on is not a software one.
set -u
daemon=$1
log=$(mktemp)
trap 'rm -f "$log"' EXIT
timeout 60 "$daemon" --gl-platform device --lcm-url memq:// --log-level info >"$log" 2>&1 &
pid=$!
for _ in $(seq 300); do
  grep -q daemon_ready "$log" && break
  kill -0 "$pid" 2>/dev/null || break
  sleep 0.1
done
if grep -q daemon_ready "$log"; then
  kill "$pid" 2>/dev/null
  wait "$pid" 2>/dev/null
  cat "$log"
  renderer=$(sed -n '/event=daemon_ready/ s/.* gl_renderer="\([^"]*\)".*/\1/p' "$log")
  if grep -Eqi 'llvmpipe|softpipe|swrast' <<<"$renderer"; then
    echo "FAIL: --gl-platform device started on a software renderer: $renderer"
    exit 1
  fi
  echo "SKIP: a hardware EGL device exists ($renderer); the no-GPU error cannot be checked here"
  exit 77
fi
wait "$pid"
status=$?
cat "$log"
[ "$status" -eq 1 ] || { echo "FAIL: exit status $status, expected 1"; exit 1; }
for expected in "no GPU found through the EGL device platform" "tried:"; do
  grep -qF "$expected" "$log" || { echo "FAIL: message lacks '$expected'"; exit 1; }
done
# Mesa offers its software rasterizer as an EGL device: it must be listed as tried, not used.
if grep -qF "EGL_MESA_device_software" "$log"; then
  grep -qF "not a GPU" "$log" || { echo "FAIL: the software device is not said to be no GPU"; exit 1; }
fi
echo "PASS"
