#!/usr/bin/env bash
# Every far-client command and far-snapshot, given a path that cannot be read or written, ends
# with one line on stderr naming that path and a non-zero exit status: never an abort (134),
# a segfault (139) or any other signal. "Unwritable" paths fail for root too (tests may run as
# root, which ignores permissions): a path under a regular file, under /proc/version, or a
# folder where a file belongs. Commands that need a daemon get a socket path that does not exist.
#   path_errors_test.sh FAR_CLIENT FAR_SNAPSHOT
set -u
client=${1:?usage: $0 FAR_CLIENT FAR_SNAPSHOT}
snapshot=${2:?usage: $0 FAR_CLIENT FAR_SNAPSHOT}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0
checks=0

# expect_error NAME PATH COMMAND...: COMMAND fails cleanly and its one stderr line names PATH.
expect_error() {
  local name=$1 path=$2 rc lines
  shift 2
  checks=$((checks + 1))
  "$@" >"$tmp/out" 2>"$tmp/err" </dev/null
  rc=$?
  lines=$(wc -l <"$tmp/err")
  local why=""
  if [ "$rc" -eq 0 ]; then
    why="exit status 0"
  elif [ "$rc" -ge 128 ]; then
    why="exit status $rc: killed by signal $((rc - 128)) (134: abort, 139: segfault)"
  elif [ "$lines" -ne 1 ]; then
    why="$lines lines on stderr, expected one"
  elif ! grep -qF -- "$path" "$tmp/err"; then
    why="the message does not name $path"
  fi
  if [ -n "$why" ]; then
    failures=$((failures + 1))
    echo "FAIL $name: $why"
    echo "  \$ $*"
    sed 's/^/  stderr: /' "$tmp/err"
  else
    echo "ok   $name (exit $rc): $(cat "$tmp/err")"
  fi
}

# The paths.
touch "$tmp/file"                   # a regular file: nothing can be under it
mkdir "$tmp/dir"                    # a folder where a file belongs
missing=$tmp/missing/nothing.json   # its folder does not exist either
under_file=$tmp/file/x.json
no_daemon=(--socket "$tmp/missing/far.sock" --connect-timeout 100ms)

# A scene that exists, for the commands whose other path is the bad one.
scene=$tmp/ok/scene.json
"$client" make-scene "$scene" --leaves 2 --frames 2 >/dev/null ||
  { echo "FAIL: far-client make-scene $scene (needed by the checks) failed"; exit 1; }

# make-scene writes: under a file, under /proc, a folder as the file, a missing mesh.
expect_error "make-scene under a file" "$tmp/file/x/scene.json" \
  "$client" make-scene "$tmp/file/x/scene.json" --frames 2
expect_error "make-scene under /proc/version" /proc/version/x/scene.json \
  "$client" make-scene /proc/version/x/scene.json --frames 2
expect_error "make-scene onto a folder" "$tmp/dir" "$client" make-scene "$tmp/dir" --frames 2
expect_error "make-scene --mesh missing" "$tmp/missing/bunny.obj" \
  "$client" make-scene "$tmp/b/scene.json" --kind bunnies --mesh "$tmp/missing/bunny.obj"

# collide, play, load read a scene.
for command in collide play; do
  expect_error "$command missing scene" "$missing" "$client" "${no_daemon[@]}" "$command" "$missing"
  expect_error "$command scene under a file" "$under_file" \
    "$client" "${no_daemon[@]}" "$command" "$under_file"
  expect_error "$command scene is a folder" "$tmp/dir" "$client" "${no_daemon[@]}" "$command" "$tmp/dir"
  expect_error "$command without a daemon" "$tmp/missing/far.sock" \
    "$client" "${no_daemon[@]}" "$command" "$scene"
done
expect_error "load missing scene" "$missing" "$client" "${no_daemon[@]}" load --scene "$missing"
expect_error "load scene under a file" "$under_file" \
  "$client" "${no_daemon[@]}" load --scene "$under_file"
expect_error "load scene is a folder" "$tmp/dir" "$client" "${no_daemon[@]}" load --scene "$tmp/dir"

# record writes its FILE (checked before the command runs).
expect_error "record under a file" "$tmp/file/x.farrec" \
  "$client" "${no_daemon[@]}" record "$tmp/file/x.farrec" play "$scene"
expect_error "record into a missing folder" "$tmp/missing/x.farrec" \
  "$client" "${no_daemon[@]}" record "$tmp/missing/x.farrec" play "$scene"
expect_error "record onto a folder" "$tmp/dir" \
  "$client" "${no_daemon[@]}" record "$tmp/dir" play "$scene"
expect_error "record runs a missing program" "$tmp/missing/simulator" \
  "$client" "${no_daemon[@]}" record "$tmp/run.farrec" -- "$tmp/missing/simulator"

# replay reads a recording.
expect_error "replay missing" "$tmp/missing/x.farrec" \
  "$client" "${no_daemon[@]}" replay "$tmp/missing/x.farrec"
expect_error "replay under a file" "$tmp/file/x.farrec" \
  "$client" "${no_daemon[@]}" replay "$tmp/file/x.farrec"
expect_error "replay a folder" "$tmp/dir" "$client" "${no_daemon[@]}" replay "$tmp/dir"

# ping and status reach a socket.
for command in ping status; do
  expect_error "$command missing socket" "$tmp/missing/far.sock" \
    "$client" --socket "$tmp/missing/far.sock" --connect-timeout 100ms "$command"
  expect_error "$command socket under a file" "$tmp/file/far.sock" \
    "$client" --socket "$tmp/file/far.sock" --connect-timeout 100ms "$command"
  expect_error "$command socket is a folder" "$tmp/dir" \
    "$client" --socket "$tmp/dir" --connect-timeout 100ms "$command"
done

# far-snapshot reads a scene and writes a PNG (checked before the step is drawn).
expect_error "far-snapshot missing scene" "$missing" "$snapshot" "$missing" --png "$tmp/x.png"
expect_error "far-snapshot scene under a file" "$under_file" \
  "$snapshot" "$under_file" --png "$tmp/x.png"
expect_error "far-snapshot scene is a folder" "$tmp/dir" "$snapshot" "$tmp/dir" --png "$tmp/x.png"
expect_error "far-snapshot --png under a file" "$tmp/file/x.png" \
  "$snapshot" "$scene" --png "$tmp/file/x.png"
expect_error "far-snapshot --png in a missing folder" "$tmp/missing/x.png" \
  "$snapshot" "$scene" --png "$tmp/missing/x.png"
expect_error "far-snapshot --png is a folder" "$tmp/dir" "$snapshot" "$scene" --png "$tmp/dir"
expect_error "far-snapshot --png under /proc/version" /proc/version/x.png \
  "$snapshot" "$scene" --png /proc/version/x.png

echo "$((checks - failures)) of $checks checks passed"
[ "$failures" -eq 0 ]
