#!/usr/bin/env python3
"""The median and range of every milestone export's evaluation, per variant of a
bench/learning_bench.sh output directory: one run's exports spread far more than one figure
shows (README, Performance, "Learning"), so lever comparisons use the median of many exports.

    /usr/bin/python3 bench/export_medians.py OUT_DIR NAME [NAME ...]

Reads OUT_DIR/NAME/eval_at_*M/eval.json (learning_bench.sh evaluates every policy_at_*M.pt) and
OUT_DIR/NAME/progress.csv (training figures over the last 30 iterations). "Under the bar" counts
the exports that meet the tracking bars' thresholds (Succ 100 %, E_mpjpe < 30 mm, E_g-mpjpe < 60 mm).
"""
import csv
import glob
import json
import os
import statistics
import sys

IMITATION = ["reward_pos", "reward_rot", "reward_vel", "reward_ang_vel"]


def main(out, names):
    print("| variant | exports | Succ (mean) | E_mpjpe median (range), mm | E_g-mpjpe median (range), mm "
          "| under the bar | train episode length | imitation reward | energy term |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in names:
        evals = []
        for path in glob.glob(os.path.join(out, name, "eval_at_*M", "eval.json")):
            with open(path) as f:
                ev = json.load(f)
            evals.append((ev["success_rate"], ev["mpjpe_mm"], ev["g_mpjpe_mm"]))
        if not evals:
            sys.exit(f"error: no {out}/{name}/eval_at_*M/eval.json (run learning_bench.sh with --milestones)")
        with open(os.path.join(out, name, "progress.csv"), newline="") as f:
            last = list(csv.DictReader(f))[-30:]
        mean = lambda value: statistics.mean(value(r) for r in last)
        mpjpe, g = [e[1] for e in evals], [e[2] for e in evals]
        under_bar = sum(1 for e in evals if e[0] == 1 and e[1] < 30 and e[2] < 60)
        print(f"| {name} | {len(evals)} | {100 * statistics.mean(e[0] for e in evals):.0f} % "
              f"| {statistics.median(mpjpe):.1f} ({min(mpjpe):.1f}-{max(mpjpe):.1f}) "
              f"| {statistics.median(g):.1f} ({min(g):.1f}-{max(g):.1f}) "
              f"| {under_bar} / {len(evals)} "
              f"| {mean(lambda r: float(r['episode_length'])):.1f} "
              f"| {mean(lambda r: sum(float(r[k]) for k in IMITATION)):.3f} "
              f"| {mean(lambda r: float(r['reward_energy'])):.3f} |")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2:])
