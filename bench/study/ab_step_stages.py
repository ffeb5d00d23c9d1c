#!/usr/bin/python3
"""A/B of far-step-profile binaries by stage: runs each binary in turn, RUNS times, and prints per
binary the median and quartiles over steps 1..STEPS of all its runs of every stage timer in
far-step-profile's stages_ms (with gpu: gl_prepare and gl_passes too), of `other` (the step's
time less its stages: the frame's conversion into updates, Apply, building the answer) and of
`cpu_outside_kernels` (the step less primitive_cull plus gl_passes: for gpu on llvmpipe, every
CPU cost but the kernels, which run inside gl_prepare there). The binaries alternate so that the
machine's drift hits them alike.

Usage: bench/study/ab_step_stages.py [--runs 5] [--steps 30] [--scene paper-leaves]
           [--method gpu] [--distance-fraction F] BINARY...
  e.g. cp build/release/bench/study/far-step-profile /tmp/old  (then rebuild the change)
       bench/study/ab_step_stages.py /tmp/old build/release/bench/study/far-step-profile
"""
import argparse
import collections
import subprocess

STAGES = ("update", "object_cull", "sweep_and_prune", "primitive_cull", "exact", "gl_prepare",
          "gl_passes")


def quartiles(values):
    values = sorted(values)
    n = len(values)
    return f"{values[n // 2]:.3f} [{values[n // 4]:.3f}-{values[3 * n // 4]:.3f}]"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--scene", default="paper-leaves")
    parser.add_argument("--method", default="gpu")
    parser.add_argument("--distance-fraction", default="0",
                        help="far-step-profile's: distance pairs too, D this fraction of the "
                             "scene's diagonal (0: contacts only)")
    parser.add_argument("binaries", nargs="+")
    args = parser.parse_args()
    times = {b: collections.defaultdict(list) for b in args.binaries}
    for _ in range(args.runs):
        for binary in args.binaries:
            out = subprocess.run([binary, "--scene", args.scene, "--method", args.method,
                                  "--steps", str(args.steps),
                                  "--distance-fraction", args.distance_fraction],
                                 capture_output=True, text=True, check=True).stdout
            for line in out.splitlines()[2:]:  # the header, then step 0 (the one-off work)
                fields = line.split(",", 13)
                step_ms = float(fields[1])
                stages = {k: float(v) for k, v in (kv.split("=") for kv in fields[13].split())}
                got = times[binary]
                for stage in STAGES:
                    if stage in stages:
                        got[stage].append(stages[stage])
                in_stages = sum(v for k, v in stages.items() if not k.startswith("gl_"))
                got["other"].append(step_ms - in_stages)
                got["cpu_outside_kernels"].append(step_ms - stages.get("primitive_cull", 0) +
                                                  stages.get("gl_passes", 0))
    for binary, got in times.items():
        print(binary, f"{args.scene} {args.method}, ms, median [p25-p75] of",
              len(got["other"]), "steps:")
        for name, values in got.items():
            print(f"  {name} {quartiles(values)}")


if __name__ == "__main__":
    main()
