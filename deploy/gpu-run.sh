#!/usr/bin/env bash
# The GPU run, on a machine with an NVIDIA GPU and its driver (docs/gpu.md). Checks that an
# OpenGL 4.5 context comes from the GPU through the EGL device platform, then runs the gpu
# method's never-miss tests on it, its kernels alone (far_compute_benchmark: the GPU's own times
# of the refit, traversal and filters), far-study on paper-leaves and on the scaling family to 1M
# triangles (bvh, gpu, auto and FAR side by side), and 16 daemon clients burning CPU per step,
# each under a time limit so that the whole fits one device call of about 8 minutes. Everything
# it prints also goes to RESULTS_DIR/log.txt, next to the study's CSVs and RESULTS.md sections.
#   bash deploy/gpu-run.sh [--smoke] [BUNDLE_DIR] [RESULTS_DIR]
# BUNDLE_DIR: made by deploy/gpu-bundle.sh (default gpu-bundle). RESULTS_DIR: default $OUT when
# set, else gpu-results. --smoke: every stage tiny, on the surfaceless platform, a software
# renderer allowed: the check of a bundle on a machine without a GPU, never for numbers.
# Environment: FAR_RUN_BUDGET_S (whole run, default 540), FAR_RUN_STAGES (a list of tests,
# kernels, paper, scaling, load: the stages to run, default all), FAR_BUNDLE_CXX=auto|bundle|system
# (which libstdc++),
# FAR_GLVND=auto|bundle (bundle: the bundle's unpacked glvnd loader, never the system's).
set -euo pipefail
export PATH=$PATH:/usr/sbin:/sbin # ldconfig

smoke=0
if [ "${1:-}" = "--smoke" ]; then
  smoke=1
  shift
fi
if [ $# -gt 2 ] || [[ "${1:-}" == -* ]]; then
  sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//' >&2
  exit 2
fi
bundle_arg=${1:-gpu-bundle}
[ -f "$bundle_arg/bundle.env" ] || {
  echo "gpu-run: $bundle_arg is not a bundle (no bundle.env): make one with deploy/gpu-bundle.sh" >&2
  exit 2
}
bundle=$(cd "$bundle_arg" && pwd)
results=${2:-${OUT:-gpu-results}}
mkdir -p "$results"
results=$(cd "$results" && pwd)
here=$(cd "$(dirname "$0")" && pwd)
budget=${FAR_RUN_BUDGET_S:-540}
start=$(date +%s)

left() { echo $((budget - ($(date +%s) - start))); }
version_ge() { [ "$(printf '%s\n%s\n' "$1" "$2" | sort -V | head -n 1)" = "$2" ]; }
is_software() {
  case "$1" in *llvmpipe* | *softpipe* | *swrast* | *[Ss]oftware* | *SwiftShader*) return 0 ;; esac
  return 1
}
stop() {
  echo
  echo "STOPPED: $*"
  echo "No numbers were taken. See docs/gpu.md, 'When the driver is missing'."
  exit 1
}

failures=0
summary=()
# stage NAME CAP_S CMD...: CMD under a limit of CAP_S or the time left, whichever is less.
stage() {
  local name=$1 cap=$2 limit rc=0 t0 took what
  shift 2
  limit=$(left)
  [ "$cap" -ge "$limit" ] || limit=$cap
  if [ "$limit" -lt 15 ]; then
    echo
    echo "=== $name: skipped, ${limit}s left of the ${budget}s budget"
    summary+=("$(printf '%-24s %s' "$name" "skipped (no time left)")")
    return 0
  fi
  echo
  echo "=== $name (limit ${limit}s, from $(date +%T))"
  local shown=("$@")
  [ "$1" != env ] || shown=("${shown[@]:2}") # env LD_LIBRARY_PATH=...: said once, above
  echo "\$ ${shown[*]}"
  t0=$(date +%s)
  timeout --kill-after=10 "$limit" "$@" || rc=$?
  took=$(($(date +%s) - t0))
  case $rc in
    0) what=ok ;;
    124 | 137) what="TIMED OUT (limit ${limit}s)" ;;
    3) what="exit status 3 (far-study: a reliability problem, see its tables)" ;;
    *) what="exit status $rc" ;;
  esac
  [ "$rc" -eq 0 ] || failures=$((failures + 1))
  echo "=== $name: $what, ${took}s"
  summary+=("$(printf '%-24s %5ss  %s' "$name" "$took" "$what")")
}

# Issue 42's load runs: one far-daemon, 16 clients of the paper's leaves, each burning
# FAR_CLIENT_CPU_MS of its own CPU per step (a simulator's physics), for each method of
# FAR_LOAD_METHODS, the sessions' gpu steps issued together (--gpu-batch true, the default);
# then gpu again with each session's steps on its own context in turns under the GL lock
# (--gpu-batch false), and without the lock (FAR_COMPUTE_GL_LOCK=off). Exported and
# run by a fresh bash (under timeout, maybe in a network namespace).
load_runs() {
  set -euo pipefail
  local bin=$FAR_BUNDLE/bin work rc=0
  work=$(mktemp -d)
  far() { env LD_LIBRARY_PATH="$FAR_LIB_PATH" "$@"; }
  client() { far "$bin/far-client" --socket "$work/far.sock" "$@"; }
  # shellcheck disable=SC2086 # FAR_LOAD_SCENE_ARGS is a list of flags
  client make-scene "$work/leaves/scene.json" $FAR_LOAD_SCENE_ARGS >/dev/null
  one_daemon() { # MODE METHOD...: a daemon (MODE batch, turns or unlocked), a load run per method
    local mode=$1 daemon answered=0 batch=true lock=on
    shift
    [ "$mode" = batch ] || batch=false
    [ "$mode" != unlocked ] || lock=off
    env LD_LIBRARY_PATH="$FAR_LIB_PATH" FAR_COMPUTE_GL_LOCK="$lock" "$bin/far-daemon" \
      --gl-platform "$FAR_PLATFORM" --socket "$work/far.sock" --log-level warn \
      --gpu-batch "$batch" --metrics-file "$work/daemon-$mode.prom" --metrics-interval-s 0.5 \
      --gpu-cost-cache "$FAR_GPU_COST_CACHE" \
      >"$work/daemon-$mode.log" 2>&1 &
    daemon=$!
    for _ in $(seq 50); do
      if client --connect-timeout 300ms ping >/dev/null 2>&1; then
        answered=1
        break
      fi
      sleep 0.2
    done
    [ "$answered" = 1 ] || { cat "$work/daemon-$mode.log"; kill "$daemon" || true; return 1; }
    for method in "$@"; do
      echo
      echo "--- load: method $method, gpu steps: $mode (--gpu-batch $batch, GL lock $lock)"
      client load --clients "$FAR_LOAD_CLIENTS" --seconds "$FAR_LOAD_SECONDS" --steps 0 \
        --method "$method" --scene "$work/leaves/scene.json" \
        --client-cpu-ms "$FAR_CLIENT_CPU_MS" || rc=$?
    done
    client status | grep -i "steps\|renderer\|error" || true
    sleep 1  # the metrics file's next rewrite: how many steps went in how many batches
    grep '^far_gpu_batch' "$work/daemon-$mode.prom" || true
    kill -TERM "$daemon"
    wait "$daemon" || rc=$?
  }
  # shellcheck disable=SC2086 # FAR_LOAD_METHODS is a list of methods
  one_daemon batch $FAR_LOAD_METHODS
  one_daemon turns gpu
  one_daemon unlocked gpu
  rm -rf "$work"
  return "$rc"
}

main() {
  local platform=device
  [ "$smoke" = 0 ] || platform=surfaceless
  # shellcheck disable=SC1091 # written by gpu-bundle.sh
  . "$bundle/bundle.env"
  echo "far GPU run$([ "$smoke" = 0 ] || echo ' (SMOKE: tiny sizes, software renderer allowed; not for numbers)')"
  echo "date: $(date -u '+%Y-%m-%d %H:%M:%S UTC'); budget ${budget}s; results: $results"
  echo "bundle: $bundle (commit $FAR_BUNDLE_COMMIT, made $FAR_BUNDLE_DATE on $FAR_BUNDLE_BUILT_ON)"
  local os glibc
  os=$(sed -n 's/^PRETTY_NAME="\(.*\)"$/\1/p' /etc/os-release 2>/dev/null || true)
  glibc=$(getconf GNU_LIBC_VERSION | awk '{ print $2 }')
  echo "host: ${os:-unknown distribution}, $(uname -srm), glibc $glibc, $(nproc) CPUs:$(grep -m 1 'model name' /proc/cpuinfo | cut -d: -f2)"

  echo
  echo "=== GPU and driver"
  if command -v nvidia-smi >/dev/null; then
    timeout 30 nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv || true
    timeout 30 nvidia-smi || true
  else
    echo "nvidia-smi: not installed"
  fi

  # The C and C++ runtimes: glibc is the target's own; libstdc++ the target's when it is new
  # enough for the binaries, else the bundle's (which needs a newer glibc itself).
  version_ge "$glibc" "$FAR_NEEDS_GLIBC" ||
    stop "glibc $glibc is older than the $FAR_NEEDS_GLIBC the bundle was built for: build the bundle on an older distribution"
  # The loader cache, read once (grep -q on a pipe would race with pipefail).
  local ldcache cxx=${FAR_BUNDLE_CXX:-auto} system_cxx
  ldcache=$(ldconfig -p)
  system_cxx=$(awk '$1 == "libstdc++.so.6" && /x86-64/ { print $NF; exit }' <<<"$ldcache")
  if [ "$cxx" = auto ]; then
    cxx=bundle
    if [ -n "$system_cxx" ] && grep -qaF "GLIBCXX_$FAR_NEEDS_GLIBCXX" "$system_cxx" &&
      grep -qaF "CXXABI_$FAR_NEEDS_CXXABI" "$system_cxx"; then
      cxx=system
    fi
  fi
  local lib_path=$bundle/lib
  if [ "$cxx" = bundle ]; then
    version_ge "$glibc" "$FAR_NEEDS_GLIBC_FOR_LIB_CXX" ||
      stop "this libstdc++ (${system_cxx:-none}) lacks GLIBCXX_$FAR_NEEDS_GLIBCXX and the bundle's needs glibc $FAR_NEEDS_GLIBC_FOR_LIB_CXX"
    lib_path=$lib_path:$bundle/lib-cxx
  fi
  echo
  echo "=== EGL loader and driver"
  echo "libstdc++: $cxx ($([ "$cxx" = system ] && echo "$system_cxx" || echo "$bundle/lib-cxx"))"

  # The glvnd loader (libEGL.so.1 and friends): the system's; when it has none, the bundle's
  # packages unpacked into / (as the device docs do it), or the bundle's unpacked copy.
  local glvnd=${FAR_GLVND:-auto}
  if [ "$glvnd" = auto ] && ! grep -q 'libEGL\.so\.1 ' <<<"$ldcache"; then
    if [ "$(id -u)" -eq 0 ] && command -v dpkg >/dev/null; then
      echo "libEGL.so.1 is missing: unpacking the glvnd loader packages into /"
      for f in "$bundle"/debs/*.deb; do dpkg -x "$f" /; done
      ldconfig
      ldcache=$(ldconfig -p)
    fi
    grep -q 'libEGL\.so\.1 ' <<<"$ldcache" || glvnd=bundle
  fi
  if [ "$glvnd" = bundle ]; then
    lib_path=$bundle/glvnd:$lib_path
    echo "glvnd loader: the bundle's ($bundle/glvnd)"
  else
    echo "glvnd loader: $(awk '$1 == "libEGL.so.1" { print $NF; exit }' <<<"$ldcache")"
  fi
  # libepoxy loads glvnd's libGL.so.1, which links the X11 client libraries (it opens no
  # display): the bundle's when the target lacks one of them, or with the bundle's glvnd.
  local x11=system
  for f in "$bundle"/lib-x11/*; do
    grep -qF "${f##*/} " <<<"$ldcache" || x11=bundle
  done
  [ "${FAR_GLVND:-auto}" != bundle ] || x11=bundle
  [ "$x11" = system ] || lib_path=$lib_path:$bundle/lib-x11
  echo "X11 client libraries (for libGL.so.1): $x11"

  # The NVIDIA EGL driver: glvnd finds it through a vendor file. When none of the standard
  # places names it, use the driver's own file (where the device machines keep it).
  local nvidia_json=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
  if [ -z "${__EGL_VENDOR_LIBRARY_FILENAMES:-}" ] && [ "$smoke" = 0 ] &&
    ! grep -qs libEGL_nvidia /usr/share/glvnd/egl_vendor.d/*.json /etc/glvnd/egl_vendor.d/*.json &&
    [ -f "$nvidia_json" ]; then
    export __EGL_VENDOR_LIBRARY_FILENAMES=$nvidia_json
  fi
  if ! grep -q 'libEGL_nvidia\.so\.0 ' <<<"$ldcache"; then
    for d in /usr/local/nvidia/lib64 /usr/local/nvidia/lib; do
      [ ! -e "$d/libEGL_nvidia.so.0" ] || lib_path=$lib_path:$d
    done
  fi
  echo "__EGL_VENDOR_LIBRARY_FILENAMES=${__EGL_VENDOR_LIBRARY_FILENAMES:-(unset: the standard vendor folders)}"
  echo "LD_LIBRARY_PATH (bundle binaries only)=$lib_path"

  # Every library of every binary must resolve; the bundle's own from the bundle.
  if command -v ldd >/dev/null; then
    local missing
    missing=$(for b in "$bundle"/bin/*; do
      LD_LIBRARY_PATH=$lib_path ldd "$b" | awk -v b="${b##*/}" '/not found/ { print b ": " $1 }'
    done)
    [ -z "$missing" ] || stop "libraries not found: $missing"
    echo "ldd: every library of the bundle's binaries resolves"
  fi

  # The renderer, from far-daemon's startup line (deploy/gl-renderer.sh).
  echo
  echo "=== GL context through the EGL $platform platform (far-daemon startup)"
  local renderer probe_log
  probe_log=$(mktemp)
  # It measures auto's GPU cost (its log's event=gpu_cost line) and keeps it in the results,
  # where the load stage's daemons read it instead of measuring again.
  renderer=$(bash "$here/gl-renderer.sh" "$platform" env LD_LIBRARY_PATH="$lib_path" \
    "$bundle/bin/far-daemon" --gpu-cost-cache "$results/gpu-costs.json" 2>"$probe_log") || true
  cat "$probe_log"
  rm -f "$probe_log"
  [ -n "$renderer" ] ||
    stop "no OpenGL context through the EGL $platform platform (the daemon's message is above): the NVIDIA EGL driver (libEGL_nvidia.so.0 and its vendor file) was not found or failed"
  echo "GL_RENDERER: $renderer"
  if is_software "$renderer" && [ "$smoke" = 0 ]; then
    stop "the EGL device platform gave a software renderer ('$renderer'), not the GPU: no NVIDIA EGL driver was loaded"
  fi

  cd "$results"
  local far_env=(env "LD_LIBRARY_PATH=$lib_path")
  local bin=$bundle/bin
  local study=("$bin/far-study" --gl-platform "$platform" --bunny "$bundle/data/bunny.obj"
    --plot-script "$bundle/data/plot_study.gp"
    --scaling-plot-script "$bundle/data/plot_scaling.gp")
  local tests_args=(--gtest_brief=1)
  local kernels=(--benchmark_repetitions=3 --benchmark_enable_random_interleaving=true
    --benchmark_report_aggregates_only=true)

  # Issue 42: the gpu method held to exact on this GPU's own rasterizer and arithmetic, then
  # timed beside bvh and FAR (far-study, one interleaved run per family), then the shared case
  # through the daemon (16 clients burning CPU per step).
  local gpu_tests='ComputeCollider*:ComputeBatcher*:PipelineCullingTest.Reliable*:PipelineCullingTest.HardCases*:PipelineCullingTest.DistanceCulling*:PipelineCullingTest.OneHuge*:PipelineCullingTest.TinyContact*:PipelineCullingTest.AutoRuns*:PipelineCullingTest.GpuFinds*'
  local paper=(--scenes paper-leaves --methods bvh,gpu,auto,far --paper-gpu far/id-buffer/256
    --steps 8 --distance paper --reference-steps 2)
  local scaling=(--scenes scaling --scaling-sizes 50000,100000,150000,300000,600000,1000000
    --methods bvh,gpu,auto --steps 6 --distance none --scaling-reference-max 150000
    --reference-steps 1)
  export FAR_LOAD_SCENE_ARGS="--kind leaves --frames 200" FAR_LOAD_CLIENTS=16 \
    FAR_LOAD_SECONDS=12 FAR_CLIENT_CPU_MS=5 FAR_LOAD_METHODS="bvh gpu auto"
  if [ "$smoke" = 1 ]; then
    gpu_tests='ComputeCollider*:PipelineCullingTest.RejectsBadRequests'
    kernels=(--benchmark_filter='BM_Gpu/1/0/' --benchmark_min_time=0.01)
    paper=(--scenes leaves --methods bvh,gpu --steps 1 --leaves 10 --leaf-cells 2)
    scaling=(--scenes scaling --scaling-sizes 5000 --methods bvh,gpu --steps 1 --distance none)
    FAR_LOAD_SCENE_ARGS="--kind leaves --frames 3 --leaves 6" FAR_LOAD_CLIENTS=2
    FAR_LOAD_SECONDS=1 FAR_CLIENT_CPU_MS=1 FAR_LOAD_METHODS="bvh gpu"
  fi

  # The GPU's clocks and load once a second while the stages run (gpu-clocks.txt): a GPU that
  # steps in short bursts may stay at low clocks, which the GPU's timers alone cannot tell.
  local dmon=
  if [ "$smoke" = 0 ] && command -v nvidia-smi >/dev/null; then
    nvidia-smi dmon -s pcu -d 1 -o T >"$results/gpu-clocks.txt" 2>&1 &
    dmon=$!
  fi

  # FAR_RUN_STAGES: which of them run (default all: tests kernels paper scaling load).
  local stages=" ${FAR_RUN_STAGES:-tests kernels paper scaling load} "
  [[ "$stages" == *" tests "* ]] &&
  stage "gpu tests" 90 "${far_env[@]}" "$bin/far_gpu_test" "${tests_args[@]}" \
    --gtest_filter="$gpu_tests"
  [[ "$stages" == *" kernels "* ]] &&
  stage "gpu kernels" 90 "${far_env[@]}" "$bin/far_compute_benchmark" \
    --gl-platform "$platform" "${kernels[@]}"
  [[ "$stages" == *" paper "* ]] &&
  stage "far-study paper-leaves" 100 "${far_env[@]}" "${study[@]}" "${paper[@]}" \
    --csv paper.csv --results paper.md
  [[ "$stages" == *" scaling "* ]] &&
  stage "far-study scaling" 140 "${far_env[@]}" "${study[@]}" "${scaling[@]}" \
    --csv scaling.csv --results scaling.md

  # LCM is UDP multicast: in a private network namespace when this machine allows one.
  export FAR_BUNDLE=$bundle FAR_LIB_PATH=$lib_path FAR_PLATFORM=$platform \
    FAR_GPU_COST_CACHE=$results/gpu-costs.json
  export -f load_runs
  local netns=()
  if command -v unshare >/dev/null && command -v ip >/dev/null && unshare -n true 2>/dev/null; then
    netns=(bash "$here/netns-run.sh")
  fi
  [[ "$stages" == *" load "* ]] &&
  stage "daemon load (16 clients)" 120 "${netns[@]}" bash -c load_runs

  [ -z "$dmon" ] || kill "$dmon" 2>/dev/null || true

  echo
  echo "=== summary ($(($(date +%s) - start))s in all; GL_RENDERER: $renderer)"
  printf '%s\n' "${summary[@]}"
  echo
  echo "files in $results:"
  ls -l
  [ "$failures" -eq 0 ]
}

main 2>&1 | tee "$results/log.txt"
