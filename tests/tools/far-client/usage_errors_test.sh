#!/usr/bin/env bash
# What far-client says to a command line it cannot run: an unknown command is named and the
# commands listed; snapshot says where it went (far-snapshot); a duration without a unit is
# refused, not read as seconds; load's --client-cpu-ms out of range is refused; --help lists the
# commands there are. Exit status 2, one line.
#   usage_errors_test.sh FAR_CLIENT
set -u
client=${1:?usage: $0 FAR_CLIENT}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0

# expect STATUS NAME TEXT... -- COMMAND...: exit STATUS, one stderr line holding every TEXT.
expect() {
  local status=$1 name=$2 texts=() rc text
  shift 2
  while [ "$1" != -- ]; do
    texts+=("$1")
    shift
  done
  shift
  "$@" >"$tmp/out" 2>"$tmp/err" </dev/null
  rc=$?
  local why=""
  [ "$rc" -eq "$status" ] || why="exit status $rc, expected $status"
  [ -n "$why" ] || [ "$(wc -l <"$tmp/err")" -eq 1 ] || why="not one line on stderr"
  for text in "${texts[@]}"; do
    [ -n "$why" ] || grep -qF -- "$text" "$tmp/err" || why="stderr lacks '$text'"
  done
  if [ -n "$why" ]; then
    failures=$((failures + 1))
    echo "FAIL $name: $why"
    sed 's/^/  stderr: /' "$tmp/err"
  else
    echo "ok   $name: $(cat "$tmp/err")"
  fi
}

commands=(ping status collide play load make-scene record replay)
expect 2 "unknown command" "far-client: 'bogus' is not a command" "${commands[@]}" -- \
  "$client" bogus
expect 2 "no command" "a command is required" "${commands[@]}" -- "$client"
expect 2 "snapshot moved" "far-snapshot" -- \
  "$client" snapshot scene.json --png out.png --frame 2
expect 2 "snapshot --help" "far-snapshot" -- "$client" snapshot --help
"$client" make-scene "$tmp/scene.json" --leaves 2 --frames 2 >/dev/null ||
  { echo "FAIL: make-scene (needed below) failed"; exit 1; }
expect 1 "--timeout without a unit" "--timeout: '5' has no unit" "5s" "5ms" "5min" -- \
  "$client" --socket "$tmp/none.sock" collide "$tmp/scene.json" --timeout 5
expect 1 "--connect-timeout without a unit" "--connect-timeout: '5' has no unit" -- \
  "$client" --socket "$tmp/none.sock" --connect-timeout 5 ping
expect 2 "replay --timeout without a unit" "--timeout: '2' has no unit" -- \
  "$client" --socket "$tmp/none.sock" --connect-timeout 100ms replay "$tmp/scene.json" --timeout 2
expect 2 "an option's bad value" "--resolution" -- \
  "$client" collide "$tmp/scene.json" --resolution lots
expect 2 "--clients 0" "--clients" -- "$client" load --clients 0
# --client-cpu-ms: finite milliseconds in [0, 10000] (CLI11's Range alone let NaN through).
for bad in nan inf -1 10001 lots; do
  expect 2 "--client-cpu-ms $bad" "--client-cpu-ms: '$bad' is not a number of milliseconds" -- \
    "$client" --socket "$tmp/none.sock" load --client-cpu-ms "$bad"
done

# --help: every command, and no snapshot among them (it is far-snapshot's now; the footer
# names far-snapshot).
help=$("$client" --help) || { echo "FAIL: far-client --help exited non-zero"; failures=$((failures + 1)); }
grep -qF "far-snapshot --help" <<<"$help" || { echo "FAIL: --help does not name far-snapshot"; failures=$((failures + 1)); }
for command in "${commands[@]}"; do
  grep -qE "^  $command( |$)" <<<"$help" || { echo "FAIL: --help does not list $command"; failures=$((failures + 1)); }
done
if grep -qE "^  snapshot( |$)" <<<"$help"; then
  echo "FAIL: --help still lists snapshot as a command"
  failures=$((failures + 1))
fi
[ "$failures" -eq 0 ] && echo "PASS"
[ "$failures" -eq 0 ]
