#!/usr/bin/env python3
"""Per-body errors of a run's exports: which bodies carry E_g-mpjpe.

    /usr/bin/python3 bench/body_errors.py RUN_DIR...

For each run directory, the median over its eval_at_*/eval.json of each body's global error
(mm, eval.json's body_error_mm) and of each part's; prints the feet (ankles, toes) beside the
median of the other bodies, then every body. A lever that tracks the walk closer has to lower the
bodies that dominate here.
"""
import glob
import json
import os
import statistics
import sys


def main(runs):
    if not runs:
        sys.exit(__doc__)
    for run in runs:
        files = sorted(glob.glob(os.path.join(run, "eval_at_*", "eval.json")))
        if not files:
            sys.exit(f"error: {run}: no eval_at_*/eval.json (run bench/learning_bench.sh with --milestones)")
        evals = [json.load(open(f)) for f in files]
        bodies = list(evals[0]["body_error_mm"])
        body = {b: statistics.median(e["body_error_mm"][b] for e in evals) for b in bodies}
        part = {p: statistics.median(e["part_error_mm"][p] for e in evals) for p in evals[0]["part_error_mm"]}
        feet = [b for b in bodies if "Ankle" in b or "Toe" in b]
        rest = statistics.median(body[b] for b in bodies if b not in feet)
        print(f"## {run} ({len(evals)} exports)")
        print("feet: " + ", ".join(f"{b} {body[b]:.1f}" for b in feet) + f"; median of the other {len(bodies) - len(feet)} bodies {rest:.1f} mm")
        print("parts: " + ", ".join(f"{p} {v:.1f}" for p, v in part.items()))
        print("bodies: " + ", ".join(f"{b} {body[b]:.1f}" for b in bodies))


if __name__ == "__main__":
    main(sys.argv[1:])
