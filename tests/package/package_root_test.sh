#!/usr/bin/env bash
# The far .deb as a new user installs it: on a minimal Debian 12 root, with nothing but what the
# package declares, its far-daemon must start and serve its far-client. This is what proves that
# cmake/Packaging.cmake declares every library the binaries load, libepoxy's dlopens included
# (a build machine has them all, so package_test.sh cannot tell).
#   1. cpack builds the .deb from the built tree (no rebuild);
#   2. debootstrap --variant=minbase bookworm makes a root in a scratch directory, from the
#      mirror of the machine's own apt sources (the repository names no host), through the
#      proxy apt is configured with;
#   3. inside it (chroot), `apt-get install --no-install-recommends ./far_<version>_<arch>.deb`:
#      the Depends alone;
#   4. the installed far-daemon, with the installed /etc/far/daemon.json, serves the installed
#      far-client (ping, make-scene, collide), inside the root and a private network namespace
#      (deploy/netns-run.sh: LCM multicast on loopback), on Mesa's llvmpipe: the root has no
#      /dev/dri, so this is a machine without a GPU.
# Everything runs in a private mount namespace: /proc and /dev/shm mounted in the root vanish
# with it whatever happens; the trap unmounts them too and removes the scratch directory.
# Nothing is cached. Skips (exit 77) only when it cannot run: not real root, no debootstrap, no
# private mount namespace (inside a chroot), or no bookworm mirror configured or reachable.
# Prints how long each step took.
# Usage: package_root_test.sh <build dir> <source dir> <project version>
# shellcheck disable=SC2016  # dpkg-query -f '${Field}' formats are literal on purpose
set -euo pipefail
build_dir=$1
source_dir=$2
version=$3
skip() {
  echo "package root test: SKIPPED: $*"
  exit 77
}
fail() {
  echo "package root test: $*" >&2
  exit 1
}
step() { echo "== $*"; }

# Root outside a user namespace: debootstrap makes device nodes and chroots.
if [ "$(id -u)" -ne 0 ] || ! awk 'NR == 1 && $1 == 0 && $2 == 0 { ok = 1 } END { exit !ok }' /proc/self/uid_map; then
  skip "needs real root (debootstrap, chroot, mounts); run ctest as root"
fi
command -v debootstrap >/dev/null || skip "debootstrap is not installed (apt-get install debootstrap; deploy/install-deps.sh lists it)"
# A private mount namespace for everything below (see the header). Inside a chroot whose root is
# no mount point the kernel refuses to make / private, and mounts made here would reach the host.
if [ "${FAR_PACKAGE_ROOT_NS:-}" != 1 ]; then
  unshare -m --propagation private true 2>/dev/null ||
    skip "cannot make a private mount namespace: $(unshare -m --propagation private true 2>&1) (a chroot whose / is no mount point?)"
  FAR_PACKAGE_ROOT_NS=1 exec unshare -m --propagation private bash "$0" "$@"
fi

work=$(mktemp -d "${TMPDIR:-/tmp}/far-package-root.XXXXXX")
root=$work/root
unmount_all() {
  # What this script mounts, and what debootstrap mounts if it was stopped half way.
  local target
  for target in "$root/dev/shm" "$root/dev/pts" "$root/proc" "$root/sys"; do
    if mountpoint -q "$target" 2>/dev/null; then umount -l "$target" || true; fi
  done
}
cleanup() {
  unmount_all
  # Never remove through a mount left in place (--one-file-system as well).
  if findmnt -rn -o TARGET | grep -qF "$root/"; then
    echo "package root test: left $work in place: something is still mounted under it" >&2
  else
    rm -rf --one-file-system "$work"
  fi
}
trap cleanup EXIT
trap 'exit 143' TERM INT
now() { date +%s; }
started=$(now)

# The Debian 12 entries of the machine's apt sources ("URI SUITE COMPONENTS" per line), in both
# formats, as deploy/fetch-lcm-source.sh reads them; entries of other suites (vendors'
# repositories) are left out: the root has neither their keys nor a use for them.
apt_entries() {
  local f
  for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
    [ -f "$f" ] || continue
    sed -nE 's/^[[:space:]]*deb[[:space:]]+(\[[^]]*\][[:space:]]+)?([^[:space:]]+)[[:space:]]+([^[:space:]]+)[[:space:]]+(.*)$/\2 \3 \4/p' "$f"
  done
  for f in /etc/apt/sources.list.d/*.sources; do
    [ -f "$f" ] || continue
    # deb822: one stanza per blank-line-separated block; Types, URIs, Suites, Components, Enabled.
    awk 'function flush() {
           if (types ~ /(^| )deb( |$)/ && tolower(enabled) != "no")
             for (u = 1; u <= nu; u++) for (s = 1; s <= ns; s++) print uris[u], suites[s], comps
           types = ""; enabled = ""; comps = ""; nu = 0; ns = 0
         }
         /^#/ { next }
         /^[[:space:]]*$/ { flush(); next }
         { key = tolower($1); $1 = ""; sub(/^ +/, "") }
         key == "types:" { types = $0 } key == "enabled:" { enabled = $0 }
         key == "components:" { comps = $0 }
         key == "uris:" { nu = split($0, uris, " ") } key == "suites:" { ns = split($0, suites, " ") }
         END { flush() }' "$f"
  done
}
entries=$(apt_entries | awk '$2 ~ /^bookworm(-updates|-security)?$/ && $1 ~ /^(https?|ftp|file):/' | sort -u)
mirror=$(awk '$2 == "bookworm" { print $1; exit }' <<<"$entries")
[ -n "$mirror" ] || skip "the machine's apt sources have no Debian 12 (bookworm) entry to debootstrap from"
# apt's proxy, for debootstrap's downloader; the root's apt gets the machine's Acquire settings.
eval "$(apt-config shell http_proxy Acquire::http::Proxy https_proxy Acquire::https::Proxy)"
export http_proxy https_proxy
/usr/lib/apt/apt-helper -o APT::Sandbox::User=root download-file "${mirror%/}/dists/bookworm/Release" "$work/Release" \
  >"$work/reach.log" 2>&1 || skip "the bookworm mirror of the apt sources is not reachable: $(tail -1 "$work/reach.log")"

# 1. The package.
step "cpack"
t=$(now)
cpack --config "$build_dir/CPackConfig.cmake" -B "$work/cpack" >"$work/cpack.log" 2>&1 ||
  { cat "$work/cpack.log"; fail "cpack failed"; }
deb_name=far_${version}_$(dpkg --print-architecture).deb
[ -f "$work/cpack/$deb_name" ] || { ls "$work/cpack"; fail "no $deb_name"; }
echo "cpack: $(($(now) - t)) s; Depends: $(dpkg-deb -f "$work/cpack/$deb_name" Depends)"

# 2. The minimal root.
step "debootstrap --variant=minbase bookworm (from the apt sources' mirror)"
t=$(now)
debootstrap --variant=minbase bookworm "$root" "$mirror" >"$work/debootstrap.log" 2>&1 ||
  { tail -30 "$work/debootstrap.log"; fail "debootstrap failed (log above)"; }
debootstrap_s=$(($(now) - t))
echo "debootstrap: $debootstrap_s s, $(chroot "$root" dpkg-query -W | wc -l) packages"

# 3. The package, with its declared dependencies only.
step "apt-get install --no-install-recommends ./$deb_name"
t=$(now)
awk '{ print "deb", $0 }' <<<"$entries" >"$root/etc/apt/sources.list"
apt-config dump | grep '^Acquire::' >"$root/etc/apt/apt.conf.d/90far-test-acquire" || true
if grep -q '^https:' <<<"$entries" && [ -f /etc/ssl/certs/ca-certificates.crt ]; then
  mkdir -p "$root/etc/ssl/certs" && cp /etc/ssl/certs/ca-certificates.crt "$root/etc/ssl/certs/"
fi
mount -t proc proc "$root/proc"
mount -t tmpfs -o mode=1777,nosuid,nodev shm "$root/dev/shm"
cp "$work/cpack/$deb_name" "$root/tmp/"
installed() { chroot "$root" dpkg-query -W -f='${Installed-Size}\n' | awk '{ n++; kb += $1 } END { print n, kb }'; }
read -r packages_before kb_before < <(installed)
chroot "$root" dpkg-query -W -f='${Package}\n' | sort >"$work/before.txt"
in_root() { chroot "$root" env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin DEBIAN_FRONTEND=noninteractive "$@"; }
in_root apt-get update -qq >"$work/apt.log" 2>&1 || { cat "$work/apt.log"; fail "apt-get update in the root failed"; }
in_root apt-get install -y -qq --no-install-recommends "/tmp/$deb_name" >>"$work/apt.log" 2>&1 ||
  { tail -40 "$work/apt.log"; fail "apt-get install ./$deb_name in the root failed (log above)"; }
in_root dpkg-query -W -f='${Status}\n' far | grep -qx "install ok installed" || fail "far is not installed in the root"
install_s=$(($(now) - t))
read -r packages_after kb_after < <(installed)
echo "apt-get install: $install_s s, $((packages_after - packages_before)) packages," \
  "$(((kb_after - kb_before) / 1024)) MB installed"
echo "added: $(comm -13 "$work/before.txt" <(chroot "$root" dpkg-query -W -f='${Package}\n' | sort) | tr '\n' ' ')"

# 4. The installed daemon and client, on a private loopback.
step "installed far-daemon and far-client in the root"
t=$(now)
cat >"$root/tmp/serve.sh" <<'SERVE'
set -euo pipefail
# A socket directory only root may write to (the daemon refuses /tmp).
mkdir -m 0755 /tmp/far-run
far-daemon --config /etc/far/daemon.json --socket /tmp/far-run/far.sock >/tmp/daemon.log 2>&1 &
daemon=$!
client() { far-client --socket /tmp/far-run/far.sock --connect-timeout 60s "$@"; }
client ping
client make-scene /tmp/scene/scene.json --leaves 4 --frames 3 --cells 2 >/dev/null
client collide /tmp/scene/scene.json --resolution 128
kill -TERM "$daemon"
wait "$daemon"
SERVE
served=$("$source_dir/deploy/netns-run.sh" chroot "$root" env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin \
  bash /tmp/serve.sh 2>&1) || {
  echo "$served"
  cat "$root/tmp/daemon.log"
  fail "the installed far-daemon did not serve the installed far-client (output and daemon log above)"
}
check() {
  grep -qE "$1" <<<"$2" || { cat "$root/tmp/daemon.log"; fail "expected /$1/ in: $2"; }
}
check "^far-daemon 'far' answered on /tmp/far-run/far.sock .*GL_RENDERER: llvmpipe" "$served"
# Frame 0: the leaves and vase are near the tree, not touching it yet.
check '^\{"contacts":\[\],.*"object_pairs":\[\[' "$served"
check "event=daemon_stopped" "$(cat "$root/tmp/daemon.log")"
echo "daemon and client: $(($(now) - t)) s"

echo "package root test: $deb_name installs on a minimal Debian 12 with its Depends alone and" \
  "serves a collide (debootstrap $debootstrap_s s, install $install_s s, whole $(($(now) - started)) s)"
