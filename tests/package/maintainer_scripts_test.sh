#!/usr/bin/env bash
# The .deb's maintainer scripts, run as dpkg runs them (install, upgrade, remove, purge), in
# the private mount namespace package_test.sh makes (unshare -m): /etc, /var and /lib are
# overlays whose changes vanish with the namespace, so the host's users and units are never
# touched. Usage (as root): unshare -m maintainer_scripts_test.sh <scratch root> <control dir> <work dir>
set -euo pipefail
root=$1
control=$2
work=$3
fail() {
  echo "maintainer scripts: $*" >&2
  exit 1
}

mount --make-rprivate /
for dir in /etc /var "$(realpath /lib)"; do
  name=$(tr / _ <<<"$dir")
  mkdir -p "$work/$name/upper" "$work/$name/work"
  mount -t overlay overlay -o "lowerdir=$dir,upperdir=$work/$name/upper,workdir=$work/$name/work" "$dir"
done
# The files dpkg would have unpacked before postinst.
mkdir -p /lib/systemd/system /etc/far
cp "$root"/lib/systemd/system/far-daemon*.service /lib/systemd/system/
cp "$root/etc/far/daemon.json" /etc/far/
export DPKG_MAINTSCRIPT_PACKAGE=far  # deb-systemd-helper refuses to run outside dpkg
! getent passwd far >/dev/null || fail "a user far exists before the test"

# Install: the system user, with the GPU's groups that exist here.
"$control/postinst" configure "" || fail "postinst configure failed"
entry=$(getent passwd far) || fail "postinst made no user far"
IFS=: read -r _ _ uid _ _ home shell <<<"$entry"
[ "$uid" -lt 1000 ] || fail "far is not a system user (uid $uid)"
[ "$home" = /nonexistent ] || fail "far's home is $home"
[ "$shell" = /usr/sbin/nologin ] || fail "far's shell is $shell"
for group in render video; do
  if getent group "$group" >/dev/null; then
    id -nG far | tr ' ' '\n' | grep -qx "$group" || fail "far is not in the group $group"
  fi
done
[ -f /var/lib/systemd/deb-systemd-helper-enabled/far-daemon.service.dsh-also ] ||
  fail "postinst did not record the unit's state for purge"
[ ! -e /etc/systemd/system/multi-user.target.wants/far-daemon.service ] ||
  fail "postinst enabled the service; the administrator does"

# The administrator enables it (the link `systemctl enable` makes: [Install] WantedBy=); an
# upgrade runs postinst again and keeps user, state and link.
mkdir -p /etc/systemd/system/multi-user.target.wants
ln -s /lib/systemd/system/far-daemon.service /etc/systemd/system/multi-user.target.wants/
"$control/postinst" configure 0.0.9 || fail "postinst (upgrade) failed"
[ "$(getent passwd far | cut -d: -f3)" = "$uid" ] || fail "the upgrade changed far's uid"
[ -L /etc/systemd/system/multi-user.target.wants/far-daemon.service ] ||
  fail "the upgrade removed the enable link"

# Remove: dpkg runs prerm, deletes the files, then postrm; the unit is masked, the user stays.
"$control/prerm" remove || fail "prerm remove failed"
rm /lib/systemd/system/far-daemon*.service
"$control/postrm" remove || fail "postrm remove failed"
[ "$(readlink /etc/systemd/system/far-daemon.service)" = /dev/null ] ||
  fail "postrm remove did not mask the unit"
getent passwd far >/dev/null || fail "removal deleted the user far"

# Purge: the enable link, the mask, the recorded state and the cache go.
mkdir -p /var/cache/far/mesa_shader_cache
"$control/postrm" purge || fail "postrm purge failed"
leftovers=$(find /etc/systemd/system /var/lib/systemd/deb-systemd-helper-enabled \
  /var/lib/systemd/deb-systemd-helper-masked -name 'far-daemon*' 2>/dev/null || true)
[ -z "$leftovers" ] || fail "purge left $leftovers"
[ ! -e /var/cache/far ] || fail "purge left /var/cache/far"
echo "maintainer scripts: install, upgrade, remove and purge behave (uid $uid)"
