#!/usr/bin/env bash
# The far-daemon built here accepts what deploy/kubernetes gives the daemon: the ConfigMap's
# daemon.json (every key known, every value in range) and the DaemonSet container's flags.
# far-daemon has no check-only mode, so one invalid flag is added, --max-sessions 0: the daemon
# reads the file and the flags, applies the flags over the file, validates the result, and
# only then stops on max_sessions (status 2), before it opens any GL, socket or file. Any other
# message (an unknown key in the file, an unknown flag, a bad value) fails the test.
#   tests/kubernetes/daemon_flags_test.sh <far-daemon> <source dir>
set -euo pipefail
daemon=$1
source_dir=$2
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT

# The ConfigMap's daemon.json into a file, and the container's args with --config pointed at it.
/usr/bin/python3 - "$source_dir/deploy/kubernetes" "$scratch" <<'PY'
import sys, yaml
kube, scratch = sys.argv[1], sys.argv[2]
config = yaml.safe_load(open(f"{kube}/configmap.yaml"))["data"]["daemon.json"]
open(f"{scratch}/daemon.json", "w").write(config)
pod = yaml.safe_load(open(f"{kube}/daemonset.yaml"))["spec"]["template"]["spec"]
container = next(c for c in pod["containers"] if c["name"] == "far-daemon")
assert container["command"] == ["/usr/bin/far-daemon"], container["command"]
args = list(container["args"])
args[args.index("--config") + 1] = f"{scratch}/daemon.json"
open(f"{scratch}/args", "w").write("\n".join(args) + "\n")
PY
mapfile -t args <"$scratch/args"
echo "far-daemon ${args[*]} --max-sessions 0"
status=0
timeout 20 "$daemon" "${args[@]}" --max-sessions 0 >"$scratch/out" 2>&1 || status=$?
cat "$scratch/out"
expected="far-daemon: invalid_argument: config 'max_sessions': must be >= 1"
if [ "$status" -ne 2 ] || [ "$(cat "$scratch/out")" != "$expected" ]; then
  echo "FAIL: far-daemon refused deploy/kubernetes' flags or daemon.json (status $status; expected status 2 and only: $expected)" >&2
  exit 1
fi
echo "far-daemon accepts the DaemonSet's flags and the ConfigMap's daemon.json"
