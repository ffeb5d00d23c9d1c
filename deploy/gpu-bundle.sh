#!/usr/bin/env bash
# Packs what the GPU run (deploy/gpu-run.sh) needs into one folder that can be copied to an
# x86-64 machine with an NVIDIA GPU and its driver but no package registry and another
# distribution (docs/gpu.md): the release binaries (stripped copies), every shared library they
# load except glibc's and the GL driver's, the glvnd loader packages, and the study's data.
#   bash deploy/gpu-bundle.sh [--no-build] [OUT_DIR]      # OUT_DIR defaults to gpu-bundle/
# The glvnd .debs come from .gl/ in the repository root when it holds them, else from Debian's
# archive through apt-get download (amd64, whatever this machine's architecture).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

build=1
if [ "${1:-}" = "--no-build" ]; then
  build=0
  shift
fi
out=${1:-gpu-bundle}
case "$out" in /*) ;; *) out=$root/$out ;; esac
[ $# -le 1 ] || { echo "usage: $0 [--no-build] [OUT_DIR]" >&2; exit 2; }

# Binaries, by build-tree path (CMake target names in the same order for the build).
binaries=(tests/far_gpu_test tests/far_snapshot_test bench/study/far-study
  bench/study/far_culling_benchmark bench/study/far_compute_benchmark server/far-daemon
  tools/far-client/far-client tools/far-snapshot/far-snapshot)
targets=(far_gpu_test far_snapshot_test far_study far_culling_benchmark far_compute_benchmark
  far-daemon far-client far-snapshot)
glvnd_debs=(libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
# Never bundled: glibc (it must match the target's kernel interface and ld.so) and the GL
# loader and driver libraries (the loader travels as .debs; the driver is the target's own).
glibc_re='^(ld-linux.*|libc|libm|libmvec|libpthread|libdl|librt|libresolv|libutil|libanl|libnsl|libBrokenLocale|libthread_db|libnss_[a-z]*|libc_malloc_debug)\.so'
gl_re='^(libEGL|libGL|libGLX|libGLES|libOpenGL|libGLdispatch|libgbm|libglapi|libvulkan|libnvidia|libcuda|libdrm)'

if [ "$build" = 1 ]; then
  cmake --preset release >/dev/null
  cmake --build --preset release -j2 --target "${targets[@]}"
fi
for b in "${binaries[@]}"; do
  [ -x "build/release/$b" ] || { echo "gpu-bundle: build/release/$b is missing" >&2; exit 1; }
done

# Start from an empty folder, but never wipe one that is not an earlier bundle.
if [ -e "$out" ] && [ -n "$(ls -A "$out")" ] && [ ! -f "$out/MANIFEST.txt" ]; then
  echo "gpu-bundle: $out exists and is not a bundle (no MANIFEST.txt); not touching it" >&2
  exit 1
fi
rm -rf "$out"
mkdir -p "$out"/{bin,lib,lib-cxx,lib-x11,debs,glvnd,data}

for b in "${binaries[@]}"; do
  strip --strip-unneeded -o "$out/bin/$(basename "$b")" "build/release/$b"
done
cp bench/data/bunny.obj bench/study/plot_study.gp bench/study/plot_scaling.gp "$out/data/"

# Every library the dynamic loader resolves for the binaries (ldd lists the whole closure),
# under its soname. libstdc++ and libgcc_s go apart: gpu-run.sh uses them only when the
# target's own are older than what the binaries need.
declare -A seen=()
for b in "$out"/bin/*; do
  while read -r name _ path _; do
    if [ -z "$name" ] || [ -n "${seen[$name]:-}" ]; then continue; fi
    seen[$name]=1
    [[ "$name" =~ $glibc_re || "$name" =~ $gl_re || "$name" == linux-vdso* ]] && continue
    if [ "$path" = "not" ] || [ ! -f "$path" ]; then
      echo "gpu-bundle: $(basename "$b") needs $name, which is not found" >&2
      exit 1
    fi
    case "$name" in
      libstdc++.so.* | libgcc_s.so.*) cp -L "$path" "$out/lib-cxx/$name" ;;
      *) cp -L "$path" "$out/lib/$name" ;;
    esac
  done < <(ldd "$b" | awk '$2 == "=>" { print $1, $2, $3, $4 }')
done

# The glvnd loader packages: from .gl/ when it has them all, else downloaded.
have_all=1
for p in "${glvnd_debs[@]}"; do
  compgen -G ".gl/${p}_*_amd64.deb" >/dev/null || have_all=0
done
if [ "$have_all" = 1 ]; then
  for p in "${glvnd_debs[@]}"; do cp .gl/"${p}"_*_amd64.deb "$out/debs/"; done
else
  lists=$(mktemp -d)
  trap 'rm -rf "$lists"' EXIT
  mkdir -p "$lists/partial"
  apt_opts=(-q -oAPT::Architecture=amd64 -oAPT::Architectures=amd64 "-oDir::State::Lists=$lists")
  # As root, apt's download sandbox user cannot write into our folder: download as root.
  [ "$(id -u)" -ne 0 ] || apt_opts+=(-oAPT::Sandbox::User=root)
  apt-get "${apt_opts[@]}" update >/dev/null
  (cd "$out/debs" && apt-get "${apt_opts[@]}" download "${glvnd_debs[@]}" >/dev/null)
fi
# Unpacked too, for a target where dpkg -x into / is not possible (no dpkg, not root): the
# libraries under their sonames, links resolved (only plain files travel safely).
unpacked=$(mktemp -d)
for f in "$out"/debs/*.deb; do dpkg-deb -x "$f" "$unpacked"; done
for f in "$unpacked"/usr/lib/x86_64-linux-gnu/*.so.[0-9]; do cp -L "$f" "$out/glvnd/"; done
rm -rf "$unpacked"
# libepoxy loads glvnd's libGL.so.1, whose libGLX.so.0 links the X11 client libraries (no
# display is opened): they go apart, for a target that has none.
for f in "$out"/glvnd/*; do
  while read -r name _ path _; do
    [[ "$name" =~ $glibc_re || "$name" =~ $gl_re || -e "$out/lib-x11/$name" ]] && continue
    [ -f "$path" ] || { echo "gpu-bundle: ${f##*/} needs $name, which is not found" >&2; exit 1; }
    cp -L "$path" "$out/lib-x11/$name"
  done < <(LD_LIBRARY_PATH=$out/glvnd ldd "$f" | awk '$2 == "=>" { print $1, $2, $3, $4 }')
done

# What the binaries need of the target's glibc, and of libstdc++ when the target's is used.
max_version() { # prefix, files...: the highest <prefix>N.N.N a file requires
  local prefix=$1
  shift
  objdump -p "$@" 2>/dev/null | grep -o "${prefix}[0-9.]*[0-9]" | sort -uV | tail -n 1 |
    sed "s/^$prefix//"
}
needs_glibc=$(max_version GLIBC_ "$out"/bin/* "$out"/lib/* "$out"/lib-x11/* "$out"/glvnd/*)
needs_glibc_cxx=$(max_version GLIBC_ "$out"/lib-cxx/*)
needs_glibcxx=$(max_version GLIBCXX_ "$out"/bin/* "$out"/lib/*)
needs_cxxabi=$(max_version CXXABI_ "$out"/bin/* "$out"/lib/*)
cat >"$out/bundle.env" <<EOF
# Written by deploy/gpu-bundle.sh; read by deploy/gpu-run.sh.
FAR_BUNDLE_COMMIT=$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- 2>/dev/null || echo -dirty)
FAR_BUNDLE_DATE='$(date -u '+%Y-%m-%d %H:%M UTC')'
FAR_BUNDLE_BUILT_ON='$(sed -n 's/^PRETTY_NAME="\(.*\)"$/\1/p' /etc/os-release), glibc $(getconf GNU_LIBC_VERSION | cut -d' ' -f2)'
FAR_NEEDS_GLIBC=$needs_glibc
FAR_NEEDS_GLIBC_FOR_LIB_CXX=$needs_glibc_cxx
FAR_NEEDS_GLIBCXX=$needs_glibcxx
FAR_NEEDS_CXXABI=$needs_cxxabi
EOF

{
  echo "far GPU bundle: deploy/gpu-bundle.sh, see docs/gpu.md"
  cat "$out/bundle.env"
  echo
  (cd "$out" && find bin lib lib-cxx lib-x11 debs glvnd data -type f -printf '%-60p %8k KiB\n' | sort)
  echo
  echo "total: $(du -sh "$out" | cut -f1)"
} >"$out/MANIFEST.txt"
cat "$out/MANIFEST.txt"

size_mib=$(($(du -sb "$out" | cut -f1) / 1048576))
if [ "$size_mib" -gt 40 ]; then
  echo "gpu-bundle: WARNING: $size_mib MiB, more than the 40 MiB budget (64 MiB travel in all)" >&2
fi
