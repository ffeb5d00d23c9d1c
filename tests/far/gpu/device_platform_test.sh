#!/usr/bin/env bash
# far-daemon --gl-platform device means a GPU: on a machine without one it must exit with status
# 1 and a message that says no GPU was found and lists what it tried (Mesa's software device
# among them), never serve on llvmpipe. Where a hardware EGL device exists the daemon starts on
# it; then this check cannot be made and is skipped (exit 77), after checking that the renderer
# it started on is not a software one. The daemon is started and read by deploy/gl-renderer.sh.
set -u
script=$1
daemon=$2
log=$(mktemp)
trap 'rm -f "$log"' EXIT
renderer=$(bash "$script" device "$daemon" --gpu-cost-cache off 2>"$log")
status=$?
cat "$log"
if [ "$status" -eq 0 ]; then
  if grep -Eqi 'llvmpipe|softpipe|swrast' <<<"$renderer"; then
    echo "FAIL: --gl-platform device started on a software renderer: $renderer"
    exit 1
  fi
  echo "SKIP: a hardware EGL device exists ($renderer); the no-GPU error cannot be checked here"
  exit 77
fi
[ "$status" -eq 1 ] || { echo "FAIL: exit status $status, expected 1"; exit 1; }
for expected in "no GPU found through the EGL device platform" "tried:"; do
  grep -qF "$expected" "$log" || { echo "FAIL: message lacks '$expected'"; exit 1; }
done
# Mesa offers its software rasterizer as an EGL device: it must be listed as tried, not used.
if grep -qF "EGL_MESA_device_software" "$log"; then
  grep -qF "not a GPU" "$log" || { echo "FAIL: the software device is not said to be no GPU"; exit 1; }
fi
echo "PASS"
