#!/usr/bin/env bash
# The far .deb (cmake/Packaging.cmake), built from an already built tree and used as an
# installed system would use it:
#   1. cpack builds it (no rebuild); its control data: name, version, shlibdeps' dependencies,
#      the conffile and the maintainer scripts;
#   2. dpkg-deb -x unpacks it into a scratch root: every part is there, and the CMake package
#      names no path of the build machine;
#   3. the systemd units pass `systemd-analyze verify` (skipped when systemd is not installed);
#   4. dpkg installs, reinstalls, removes and purges it on throw-away overlays of /etc, /var and
#      /usr in a private mount namespace (dpkg_lifecycle_test.sh; needs real root, skipped
#      otherwise);
#   5. the packaged far-daemon, started with the packaged config, serves the packaged
#      far-client (ping, make-scene, collide, play) and a simulator built against the packaged
#      CMake package (find_package(far), far::client); far-snapshot draws a PNG, and the
#      packaged far-client loads no GL, EGL or FCL.
# Steps 1-2 and 5 never skip. Run it inside deploy/netns-run.sh: LCM multicast on a private
# loopback. Usage: package_test.sh <build dir> <source dir> <project version>
set -euo pipefail
build_dir=$1
source_dir=$2
version=$3
work=$(mktemp -d)
daemon_pid=""
cleanup() {
  if [ -n "$daemon_pid" ]; then
    kill "$daemon_pid" 2>/dev/null || true
    wait "$daemon_pid" 2>/dev/null || true
  fi
  rm -rf "$work"
}
trap cleanup EXIT
fail() {
  echo "package test: $*" >&2
  exit 1
}
step() { echo "== $*"; }

# 1. Build and inspect the package.
step "cpack"
cpack --config "$build_dir/CPackConfig.cmake" -B "$work/cpack" >"$work/cpack.log" 2>&1 ||
  { cat "$work/cpack.log"; fail "cpack failed"; }
deb=$work/cpack/far_${version}_$(dpkg --print-architecture).deb
[ -f "$deb" ] || { ls "$work/cpack"; fail "no $deb"; }
[ "$(dpkg-deb -f "$deb" Package)" = far ] || fail "package name is not far"
[ "$(dpkg-deb -f "$deb" Version)" = "$version" ] || fail "version is not $version"
depends=$(dpkg-deb -f "$deb" Depends)
# shlibdeps' libraries, and what libepoxy and libglvnd load at run time (cmake/Packaging.cmake).
for needed in adduser libegl1 libc6 libstdc++6 libepoxy0 libsodium "libopengl0 | libgl1" \
  libegl-mesa0 libgl1-mesa-dri; do
  grep -qF "$needed" <<<"$depends" || fail "Depends lacks $needed: $depends"
done
dpkg-deb -e "$deb" "$work/control"
[ "$(cat "$work/control/conffiles")" = /etc/far/daemon.json ] || fail "conffiles is not /etc/far/daemon.json"
for script in postinst prerm postrm; do
  [ -x "$work/control/$script" ] || fail "$script missing or not executable"
  sh -n "$work/control/$script" || fail "$script: syntax error"
done

# 2. Unpack and look.
step "dpkg-deb -x"
root=$work/root
dpkg-deb -x "$deb" "$root"
for file in usr/bin/far-daemon usr/bin/far-client usr/bin/far-snapshot usr/lib/libfar_client.a \
  usr/lib/libfar_protocol.a \
  usr/lib/libfar_lcm.a usr/lib/libfar_model.a usr/include/far/client/client.h \
  usr/include/far/model/version.h usr/lib/cmake/far/farConfig.cmake \
  usr/lib/cmake/far/farConfigVersion.cmake usr/lib/cmake/far/farClientTargets.cmake \
  lib/systemd/system/far-daemon.service lib/systemd/system/far-daemon@.service etc/far/daemon.json \
  usr/share/far/data/bunny.obj usr/share/doc/far/daemon.md usr/share/doc/far/copyright \
  usr/share/doc/far/lcm/NOTICE usr/share/doc/far/lcm/COPYING \
  usr/share/doc/far/lcm/lcm-1.3.1-receive-bounds.patch \
  usr/share/doc/far/lcm/lcm_1.3.1+repack1.orig.tar.gz; do
  [ -f "$root/$file" ] || fail "the package has no /$file"
done
cmp -s "$root/usr/share/far/data/bunny.obj" "$source_dir/bench/data/bunny.obj" ||
  fail "the packaged bunny differs from bench/data/bunny.obj"
# Licenses: far's copyright in Debian's machine-readable format, and for the statically linked
# LCM (LGPL) its license, its source as used (the pinned tarball and far's patch) and the notice
# naming the revision of far the binaries came from.
copyright=$root/usr/share/doc/far/copyright
head -1 "$copyright" | grep -q '^Format: .*copyright-format/1.0/$' || fail "copyright: no DEP-5 Format line"
for field in "^Files: \*$" "^License: BSD-3-Clause$" "^License: LGPL-2.1\+$" "^License: MPL-2.0$"; do
  grep -qE "$field" "$copyright" || fail "copyright lacks /$field/"
done
cmp -s "$root/usr/share/doc/far/lcm/lcm-1.3.1-receive-bounds.patch" \
  "$source_dir/protocol/third_party/lcm/lcm-1.3.1-receive-bounds.patch" ||
  fail "the packaged LCM patch differs from protocol/third_party/lcm/"
echo "abf293e54aff3d073cb4f9d4d5a261eab0e5ffea02e13fd601715c11612b85e8  $root/usr/share/doc/far/lcm/lcm_1.3.1+repack1.orig.tar.gz" |
  sha256sum -c --status || fail "the packaged LCM tarball is not Debian's lcm_1.3.1+repack1.orig.tar.gz"
grep -q "GNU LESSER GENERAL PUBLIC LICENSE" "$root/usr/share/doc/far/lcm/COPYING" || fail "lcm/COPYING is not the LGPL"
grep -qE "^  (git commit [0-9a-f]{40}( with local changes)?|not a git checkout: .*)$" "$root/usr/share/doc/far/lcm/NOTICE" ||
  fail "lcm/NOTICE names no revision of far"
if grep -rlF -e "$build_dir" -e "$source_dir" "$root/usr/lib/cmake/far"; then
  fail "the CMake package names paths of the build machine (above)"
fi

# 3. The units, as systemd reads them. verify exits 0 even on unknown or bad settings; any
# line it prints is a finding. It resolves ExecStart= and the unit's dependencies inside --root:
# the packaged binary and a copy of the host's units.
step "systemd-analyze verify"
if command -v systemd-analyze >/dev/null && [ -d /lib/systemd/system ]; then
  vroot=$work/verify-root
  mkdir -p "$vroot/lib/systemd" "$vroot/usr/bin"
  cp -a /lib/systemd/system "$vroot/lib/systemd/"
  cp "$root"/lib/systemd/system/far-daemon*.service "$vroot/lib/systemd/system/"
  cp "$root/usr/bin/far-daemon" "$vroot/usr/bin/"
  findings=$(systemd-analyze verify --root="$vroot" far-daemon.service far-daemon@1.service 2>&1) ||
    fail "systemd-analyze verify failed: $findings"
  [ -z "$findings" ] || fail "systemd-analyze verify: $findings"
else
  echo "skipped: systemd-analyze is not installed (apt-get install systemd)"
fi

# 4. dpkg itself, on throw-away copies of /etc, /var and /usr. Overlays need root (not a user
# namespace's: it cannot read /etc/shadow) and overlayfs.
step "dpkg -i, -r, -P"
overlay_works() {
  local probe=$work/probe
  mkdir -p "$probe/lower" "$probe/upper" "$probe/work" "$probe/mnt"
  unshare -m mount -t overlay overlay \
    -o "lowerdir=$probe/lower,upperdir=$probe/upper,workdir=$probe/work" "$probe/mnt" 2>/dev/null
}
if getent passwd far >/dev/null || dpkg -s far >/dev/null 2>&1; then
  echo "skipped: this machine has far installed, or a user far (it checks that dpkg makes it)"
elif awk 'NR == 1 && $1 == 0 && $2 == 0 { ok = 1 } END { exit !ok }' /proc/self/uid_map &&
  [ "$(id -u)" -eq 0 ] && overlay_works; then
  unshare -m bash "$source_dir/tests/package/dpkg_lifecycle_test.sh" "$deb" "$work/overlay" ||
    fail "dpkg lifecycle (above)"
else
  echo "skipped: needs root outside a user namespace and overlayfs (for throw-away /etc, /var, /usr)"
fi

# 5. Run what the package holds, from the scratch root.
step "packaged far-daemon and far-client"
socket=$work/run/far.sock
# Its caches (auto's GPU cost, Mesa's shaders) in the test's folder, not the home.
XDG_CACHE_HOME=$work/cache "$root/usr/bin/far-daemon" --config "$root/etc/far/daemon.json" \
  --socket "$socket" >"$work/daemon.log" 2>&1 &
daemon_pid=$!
client() { "$root/usr/bin/far-client" --socket "$socket" --connect-timeout 30s "$@"; }
check() {
  grep -qE "$1" <<<"$2" || { cat "$work/daemon.log"; fail "expected /$1/ in: $2"; }
}
check "^far-daemon 'far' answered on $socket" "$(client ping)"
"$root/usr/bin/far-daemon" --version | grep -qx "far-daemon $version" || fail "far-daemon --version"
client make-scene "$work/scene/scene.json" --leaves 4 --frames 3 --cells 2 >/dev/null
# Frame 0: the leaves and vase are near the tree, not touching it yet.
check '^\{"contacts":\[\],.*"object_pairs":\[\[' \
  "$(client collide "$work/scene/scene.json" --resolution 128)"
played=$(client play "$work/scene/scene.json" --resolution 128 --contacts)
check "frame   1: vase breaks into 4 fragments" "$played"
check "vase-fragment-[0-9] touches tree \([0-9]+ triangle pairs\)" "$played"

step "packaged far-snapshot, and a far-client without GL"
snapshot_out=$("$root/usr/bin/far-snapshot" "$work/scene/scene.json" --frame 1 --resolution 128 \
  --width 64 --height 48 --png "$work/snap.png") || fail "far-snapshot failed: $snapshot_out"
check "^wrote $work/snap.png \(64x48\)" "$snapshot_out"
[ "$(head -c 8 "$work/snap.png" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] ||
  fail "far-snapshot wrote no PNG"
if ldd "$root/usr/bin/far-client" | grep -E '(libEGL|libGL|libOpenGL|libGLdispatch|libepoxy|libfcl)'; then
  fail "the packaged far-client loads GL, EGL or FCL (above)"
fi
moved=$(client snapshot x.json --png x.png 2>&1) && fail "far-client snapshot succeeded"
check "far-snapshot" "$moved"

step "a simulator built against the packaged CMake package"
cmake -S "$source_dir/client/examples/simulator" -B "$work/simulator" -G Ninja \
  -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$root/usr" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF \
  >"$work/simulator.log" 2>&1 || { cat "$work/simulator.log"; fail "configuring the simulator"; }
grep -qF "$root/usr/lib/cmake/far" "$work/simulator/CMakeCache.txt" ||
  fail "the simulator did not find far in the scratch root"
cmake --build "$work/simulator" >>"$work/simulator.log" 2>&1 ||
  { cat "$work/simulator.log"; fail "building the simulator"; }
# The box falls onto the floor: apart until step 5, touching from step 6 on (z = 0.58: its
# bottom, 0.08, is below the floor's top, 0.1).
simulated=$("$work/simulator/simulator" "$socket") || fail "the simulator failed: $simulated"
check "step 5: box at z=0.64, 0 contact pairs" "$simulated"
check "step 6: box at z=0.58, [1-9][0-9]* contact pairs" "$simulated"
check "step 9: box at z=0.40, [1-9][0-9]* contact pairs" "$simulated"

kill -TERM "$daemon_pid"
wait "$daemon_pid" || { cat "$work/daemon.log"; fail "far-daemon exited $? on SIGTERM"; }
daemon_pid=""
check "event=daemon_stopped" "$(cat "$work/daemon.log")"
echo "package test: $(basename "$deb") builds, unpacks and runs from a scratch root"
