#!/usr/bin/env bash
# far-daemon with no EGL driver: exit status 1 and a message that names every attempt.
set -u
output=$(__EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent.json "$1" --lcm-url memq:// 2>&1)
status=$?
echo "$output"
[ "$status" -eq 1 ] || { echo "FAIL: exit status $status, expected 1"; exit 1; }
for expected in "no OpenGL 4.5 core context could be made; tried:" "EGL device platform" "surfaceless platform"; do
  grep -qF "$expected" <<<"$output" || { echo "FAIL: message lacks '$expected'"; exit 1; }
done
echo "PASS"
