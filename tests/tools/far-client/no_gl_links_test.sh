#!/usr/bin/env bash
# far-client runs on a host without GL, EGL or FCL: ldd of the built binary (every library the
# loader would map, the whole closure) shows none of them. The build refuses such a link too
# (far_forbid_links in tools/CMakeLists.txt); this checks what was actually linked.
#   no_gl_links_test.sh FAR_CLIENT
set -u
binary=${1:?usage: $0 FAR_CLIENT}
[ -x "$binary" ] || { echo "FAIL: $binary is not an executable"; exit 1; }
libraries=$(ldd "$binary") || { echo "FAIL: ldd $binary failed"; exit 1; }
echo "$libraries"
forbidden='^[[:space:]]*(libEGL|libGL|libGLX|libGLES|libOpenGL|libGLdispatch|libepoxy|libfcl|libgbm)[.-]'
if found=$(grep -E "$forbidden" <<<"$libraries"); then
  echo "FAIL: far-client loads GL, EGL or FCL:"
  echo "$found"
  exit 1
fi
# The check can fail: the same pattern finds them in a binary that does load them.
if [ -n "${2:-}" ] && ! ldd "$2" | grep -qE "$forbidden"; then
  echo "FAIL: the pattern finds nothing in $2, which links GL (the check would pass anything)"
  exit 1
fi
echo "PASS: no GL, EGL or FCL library in far-client's ldd"
