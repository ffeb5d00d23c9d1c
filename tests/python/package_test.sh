#!/usr/bin/env bash
# The python3-far .deb (deploy/debian/python3-far.cpack.in) beside far's, built from an already
# built tree and used as an installed system would use them (like tests/package/package_test.sh):
#   1. cpack builds both; python3-far's control data: name, version, its dependencies on far
#      of the same version, python3 and NumPy;
#   2. dpkg-deb -x unpacks both into a scratch root: far/ in /usr/lib/python3/dist-packages;
#   3. the packaged far-daemon serves the packaged module: /usr/bin/python3 imports far from the
#      scratch root (nothing from the build tree), opens a session, steps a scene; the packaged
#      example runs in process (far.Pipeline).
# Run it inside deploy/netns-run.sh. Usage: package_test.sh <build dir> <source dir> <version>
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
  echo "python package test: $*" >&2
  exit 1
}
arch=$(dpkg --print-architecture)

echo "== cpack far and python3-far"
for config in CPackConfig.cmake CPackConfig-python3-far.cmake; do
  cpack --config "$build_dir/$config" -B "$work/cpack" >"$work/cpack.log" 2>&1 ||
    { cat "$work/cpack.log"; fail "cpack --config $config failed"; }
done
deb=$work/cpack/python3-far_${version}_${arch}.deb
[ -f "$deb" ] || { ls "$work/cpack"; fail "no $deb"; }
[ "$(dpkg-deb -f "$deb" Package)" = python3-far ] || fail "package name is not python3-far"
[ "$(dpkg-deb -f "$deb" Version)" = "$version" ] || fail "version is not $version"
depends=$(dpkg-deb -f "$deb" Depends)
for needed in "far (= $version)" "python3 (>= 3." "python3 (<< 3." python3-numpy libc6 libstdc++6; do
  grep -qF "$needed" <<<"$depends" || fail "Depends lacks $needed: $depends"
done
dpkg-deb -e "$deb" "$work/control"
[ ! -e "$work/control/postinst" ] || fail "python3-far has maintainer scripts (they are far's)"

echo "== dpkg-deb -x"
root=$work/root
dpkg-deb -x "$work/cpack/far_${version}_${arch}.deb" "$root"
dpkg-deb -x "$deb" "$root"
site=$root/usr/lib/python3/dist-packages
for file in far/__init__.py far/_errors.py far/_result.py; do
  [ -f "$site/$file" ] || fail "the package has no /usr/lib/python3/dist-packages/$file"
done
ls "$site"/far/_client.cpython-*.so "$site"/far/_pipeline.cpython-*.so >/dev/null ||
  fail "the package has no extension modules"
if dpkg-deb -c "$work/cpack/far_${version}_${arch}.deb" | grep -q dist-packages; then
  fail "far's own .deb holds the Python package (it is python3-far's)"
fi

echo "== the packaged module and daemon"
socket=$work/run/far.sock
# Its caches (auto's GPU cost, Mesa's shaders) in the test's folder, not the home.
XDG_CACHE_HOME=$work/cache "$root/usr/bin/far-daemon" --config "$root/etc/far/daemon.json" \
  --socket "$socket" >"$work/daemon.log" 2>&1 &
daemon_pid=$!
"$root/usr/bin/far-client" --socket "$socket" --connect-timeout 30s make-scene \
  "$work/scene/scene.json" --kind scaling --triangles 1000 --frames 2 >/dev/null
out=$(cd "$work" && env -u PYTHONPATH PYTHONPATH="$site" PYTHONDONTWRITEBYTECODE=1 /usr/bin/python3 -c '
import sys, far
assert far.__file__.startswith(sys.argv[1]), far.__file__
far.Client.status(socket_path=sys.argv[2], connect_timeout=30)
with far.Client(socket_path=sys.argv[2]) as client:
    client.load_scene(sys.argv[3])
    r = client.step(method="bvh")
    print("contacts", len(r.contacts), r.contacts.dtype)
' "$site" "$socket" "$work/scene/scene.json" 2>&1) || { cat "$work/daemon.log"; fail "python: $out"; }
grep -qE "^contacts [1-9][0-9]* int64$" <<<"$out" || fail "unexpected: $out"
example=$root/usr/share/doc/python3-far/examples/simulator_loop.py
[ -f "$example" ] || fail "no $example"
ran=$(PYTHONPATH="$site" PYTHONDONTWRITEBYTECODE=1 /usr/bin/python3 "$example" --in-process --frames 12 2>&1) ||
  fail "the example failed: $ran"
grep -qE "^frame 11: box at z=0.03, [1-9][0-9]* contact pairs: floor-box" <<<"$ran" ||
  fail "the example's box never touches: $ran"

kill -TERM "$daemon_pid"
wait "$daemon_pid" || { cat "$work/daemon.log"; fail "far-daemon exited $? on SIGTERM"; }
daemon_pid=""
echo "python package test: python3-far_${version}_${arch}.deb installs beside far and steps a scene"
