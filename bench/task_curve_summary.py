#!/usr/bin/env python3
# Medians per million env steps of a task run's progress.csv: normalized return, episode length and
# each reward term (the figures the skill-reuse results quote).
#   /usr/bin/python3 bench/task_curve_summary.py RUN/progress.csv [STEP]
import csv, sys, statistics
rows = list(csv.DictReader(open(sys.argv[1])))
step = float(sys.argv[2]) if len(sys.argv) > 2 else 1e6
last = float(rows[-1]["env_steps"])
m = 1
while (m - 1) * step < last:
    w = [r for r in rows if (m - 1) * step < float(r["env_steps"]) <= m * step and r["normalized_return"] != "nan"]
    if w:
        print(f"{m*step/1e6:.1f} M: normalized return median {statistics.median(float(r['normalized_return']) for r in w):.3f}, "
              f"episode length {statistics.median(float(r['episode_length']) for r in w):.1f}, "
              + ", ".join(f"{k} {statistics.median(float(r[k]) for r in w):.3f}" for k in rows[0] if k.startswith("reward_")))
    m += 1
