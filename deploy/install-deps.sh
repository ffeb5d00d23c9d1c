#!/usr/bin/env bash
# Installs every Debian 12 package far needs to build, test and run, then fetches LCM's source
# package through apt (deploy/fetch-lcm-source.sh). Idempotent: packages already present are left
# alone, apt is asked only for what is missing, and the source is fetched once.
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake ninja-build pkg-config git clang-format
  # sanitizer and fuzzing builds (docs/testing.md): clang 14, its runtimes (libFuzzer, ASan,
  # UBSan, TSan: libclang-rt-14-dev) and llvm-symbolizer for readable reports (llvm)
  clang libclang-rt-dev llvm
  # geometry and math
  libeigen3-dev libgmp-dev libfcl-dev
  # headless GL: EGL + GL headers and Mesa's software rasterizer (llvmpipe). Nothing pulls
  # libgl1-mesa-dri in otherwise, and without it EGL finds no driver at all.
  libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri libepoxy-dev
  # protocol and IPC. LCM's C library is built from Debian's source package (protocol/third_party/
  # lcm: patch, glib; fetched through apt below); lcm-gen is liblcm-bin's.
  liblcm-bin libglib2.0-dev patch libboost-dev libsodium-dev
  # files (far-snapshot writes PNG through libpng), command lines, logs
  nlohmann-json3-dev libpng-dev libcli11-dev libspdlog-dev
  # the Python package `far` (client/python, docs/python.md): pybind11 and Debian's python3
  # with NumPy; pytest runs its tests
  pybind11-dev python3-dev python3-numpy python3-pytest
  # metrics in Prometheus' text format (docs/cluster.md): prometheus-cpp writes and serves them,
  # python3-prometheus-client parses them in the test
  prometheus-cpp-dev python3-prometheus-client
  # the one-node Slurm cluster test (tests/slurm/) and the offline check of the Kubernetes
  # manifests against the API schema (tests/kubernetes/)
  slurm-wlm munge python3-jsonschema python3-yaml
  # tests, benchmarks, plots
  libgtest-dev libgmock-dev libbenchmark-dev gnuplot-nox
  # private network namespaces for the LCM (udpm) tests
  iproute2 util-linux
  # the .deb (cpack): dpkg-shlibdeps for its dependencies, file for CPack to find the binaries;
  # debootstrap for the minimal Debian 12 root the package is installed on (tests/package/)
  dpkg-dev file debootstrap
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
else
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

bash "$(dirname "$0")/fetch-lcm-source.sh"
