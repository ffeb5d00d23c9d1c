#!/usr/bin/env bash
# The .deb through dpkg itself: install, reinstall (an upgrade's path through the maintainer
# scripts), remove, purge. Runs in the private mount namespace package_test.sh makes
# (unshare -m) with /etc, /var and /usr (and /lib where it is not /usr/lib) as overlays whose
# changes vanish with the namespace: the host's packages, users and units are never touched.
# Usage (as root): unshare -m dpkg_lifecycle_test.sh <deb> <work dir>
set -euo pipefail
deb=$1
work=$2
fail() {
  echo "dpkg lifecycle: $*" >&2
  exit 1
}

mount --make-rprivate /
dirs=(/etc /var /usr)
case "$(realpath /lib)" in /usr/*) ;; *) dirs+=(/lib) ;; esac
for dir in "${dirs[@]}"; do
  name=$(tr / _ <<<"$dir")
  mkdir -p "$work/$name/upper" "$work/$name/work"
  mount -t overlay overlay -o "lowerdir=$dir,upperdir=$work/$name/upper,workdir=$work/$name/work" "$dir"
done
# Where systemd runs, the maintainer scripts would reach it (daemon-reload, try-restart, stop)
# and, through it, the host's own far daemons: here they find no systemd.
if [ -d /run/systemd ]; then mount -t tmpfs tmpfs /run/systemd; fi
wants=/etc/systemd/system/multi-user.target.wants/far-daemon.service

# Install: the files, and the system user with the GPU's groups that exist here; the service
# is not enabled (the administrator does that).
dpkg -i "$deb" >"$work/dpkg.log" 2>&1 || { cat "$work/dpkg.log"; fail "dpkg -i failed"; }
for file in /usr/bin/far-daemon /usr/bin/far-client /lib/systemd/system/far-daemon.service \
  /lib/systemd/system/far-daemon@.service /etc/far/daemon.json /usr/lib/cmake/far/farConfig.cmake; do
  [ -f "$file" ] || fail "dpkg -i installed no $file"
done
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
[ ! -e "$wants" ] || fail "installing enabled the service"

# The administrator enables it (the link `systemctl enable` makes: [Install] WantedBy=) and
# edits the configuration; installing again keeps user, link and the edited conffile.
mkdir -p "$(dirname "$wants")"
ln -s /lib/systemd/system/far-daemon.service "$wants"
echo '{"log_level": "warn"}' >/etc/far/daemon.json
dpkg -i "$deb" >"$work/dpkg.log" 2>&1 || { cat "$work/dpkg.log"; fail "dpkg -i (again) failed"; }
[ "$(getent passwd far | cut -d: -f3)" = "$uid" ] || fail "reinstalling changed far's uid"
[ -L "$wants" ] || fail "reinstalling removed the enable link"
grep -q '"warn"' /etc/far/daemon.json || fail "reinstalling overwrote the edited /etc/far/daemon.json"

# Remove: the programs go, the conffile and the user stay, the unit is masked.
mkdir -p /var/cache/far/mesa_shader_cache
dpkg -r far >"$work/dpkg.log" 2>&1 || { cat "$work/dpkg.log"; fail "dpkg -r failed"; }
[ ! -e /usr/bin/far-daemon ] || fail "dpkg -r left /usr/bin/far-daemon"
[ -f /etc/far/daemon.json ] || fail "dpkg -r removed the conffile"
[ "$(readlink /etc/systemd/system/far-daemon.service)" = /dev/null ] ||
  fail "removal did not mask the unit"
getent passwd far >/dev/null || fail "removal deleted the user far"

# Purge: the configuration, the enable link, the mask, the recorded state and the cache go.
dpkg -P far >"$work/dpkg.log" 2>&1 || { cat "$work/dpkg.log"; fail "dpkg -P failed"; }
[ ! -e /etc/far ] || fail "purge left /etc/far"
[ ! -e /var/cache/far ] || fail "purge left /var/cache/far"
leftovers=$(find /etc/systemd/system /var/lib/systemd/deb-systemd-helper-enabled \
  /var/lib/systemd/deb-systemd-helper-masked -name 'far-daemon*' 2>/dev/null || true)
[ -z "$leftovers" ] || fail "purge left $leftovers"
echo "dpkg lifecycle: install, reinstall, remove and purge behave (far is uid $uid)"
