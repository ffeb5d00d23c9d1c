#!/usr/bin/env bash
# deploy/gl-renderer.sh on the surfaceless platform (a GL context on any machine, llvmpipe where
# there is no GPU) prints the renderer the daemon reports, and only that; on a platform that
# makes no context it exits 1 and prints nothing on stdout.
set -u
script=$1
daemon=$2
renderer=$(bash "$script" surfaceless "$daemon" --gpu-cost-cache off 2>/dev/null)
status=$?
if [ "$status" -ne 0 ] || [ -z "$renderer" ]; then
  echo "FAIL: gl-renderer.sh surfaceless exited $status with renderer '$renderer'; daemon output:"
  bash "$script" surfaceless "$daemon" --gpu-cost-cache off
  exit 1
fi
if [ "$(wc -l <<<"$renderer")" -ne 1 ] || grep -q '[="]' <<<"$renderer"; then
  echo "FAIL: not one renderer name: '$renderer'"
  exit 1
fi
echo "renderer: $renderer"
out=$(__EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent.json bash "$script" surfaceless "$daemon" --gpu-cost-cache off 2>/dev/null)
status=$?
if [ "$status" -ne 1 ] || [ -n "$out" ]; then
  echo "FAIL: without an EGL vendor: exit $status (expected 1), stdout '$out' (expected none)"
  exit 1
fi
echo "PASS"
