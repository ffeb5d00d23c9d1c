#!/usr/bin/env bash
# Runs a command in a private network namespace whose loopback carries multicast, so that LCM
# over UDP multicast (udpm) works and never reaches a real interface (README.md, "Running the
# daemon by hand").
#   deploy/netns-run.sh far-daemon ...
set -euo pipefail
if [ "${FAR_IN_NETNS:-}" = 1 ]; then exec "$@"; fi
flags=-n
[ "$(id -u)" -eq 0 ] || flags=-rn
exec unshare "$flags" env FAR_IN_NETNS=1 bash -c '
  ip link set lo up
  ip link set lo multicast on
  ip route add 224.0.0.0/4 dev lo
  exec "$@"' netns-run "$@"
