#!/usr/bin/env bash
# Installs far into a temporary prefix and builds the example simulator against it with
# find_package(far): the package works for a user project.
set -euo pipefail
build_dir=$1
source_dir=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build_dir" --prefix "$work/prefix" >/dev/null
cmake -S "$source_dir/client/examples/simulator" -B "$work/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_PREFIX_PATH="$work/prefix" >/dev/null
cmake --build "$work/build" >/dev/null
test -x "$work/build/simulator"
echo "find_package(far) consumer built: $work/build/simulator"
