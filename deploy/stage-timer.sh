# Sourced by deploy/run-tests.sh and deploy/run-sanitizers.sh: `timed NAME COMMAND...` runs a
# stage and says how long it took, wall time and CPU time (meaningful when the machine is
# shared: CPU seconds / cores is what the stage would take alone), as
# "<stage_timer_name>: stage NAME took N s (M s CPU)" on stderr. Set stage_timer_name first.

# Sets `cpu` to the CPU seconds this shell's finished children used (bash's `times`, second
# line). `times` must run in this shell, not in a $(...) subshell, whose children are its own.
cpu_file=$(mktemp)
trap 'rm -f "$cpu_file"' EXIT
children_cpu() {
  times >"$cpu_file"
  cpu=$(awk 'NR == 2 {
    for (i = 1; i <= 2; ++i) { split($i, t, /[ms]/); total += 60 * t[1] + t[2] }
    printf "%d", total }' "$cpu_file")
}

timed() {
  local name=$1
  shift
  local start=$SECONDS before
  children_cpu
  before=$cpu
  "$@"
  children_cpu
  echo "$stage_timer_name: stage $name took $((SECONDS - start)) s ($((cpu - before)) s CPU)" >&2
}
