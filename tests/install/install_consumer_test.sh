#!/usr/bin/env bash
# Installs far into a temporary prefix and builds the example simulator against it with
# find_package(far COMPONENTS client), as a user project would, then checks what it links:
#  - the client component must configure without FCL (its package is disabled) or GL/EGL;
#  - linked with --no-as-needed (every library named on the link line stays in the binary),
#    the simulator must not depend on epoxy, EGL, GL, FCL or FCL's own dependencies.
set -euo pipefail
build_dir=$1
source_dir=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build_dir" --prefix "$work/prefix" >/dev/null
cmake -S "$source_dir/client/examples/simulator" -B "$work/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_PREFIX_PATH="$work/prefix" \
      -DCMAKE_DISABLE_FIND_PACKAGE_fcl=ON \
      -DCMAKE_EXE_LINKER_FLAGS="-Wl,--no-as-needed" >/dev/null
cmake --build "$work/build" >/dev/null
test -x "$work/build/simulator"
libraries=$(ldd "$work/build/simulator")
if grep -Ei 'lib(epoxy|EGL|GL|GLX|OpenGL|fcl|ccd|octomap)[.-]' <<<"$libraries"; then
  echo "the example simulator links GL or FCL (above); a far::client user must link neither" >&2
  exit 1
fi
echo "find_package(far COMPONENTS client) consumer built without GL or FCL: $work/build/simulator"
