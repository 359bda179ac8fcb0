#!/usr/bin/env python3
"""Medians per window of env steps of a task run's progress.csv: normalized return, episode length
and each reward term (the figures the skill-reuse results quote).

    /usr/bin/python3 bench/task_curve_summary.py RUN/progress.csv [--window 1e6]
"""
import argparse
import csv
import statistics
import sys


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("progress", help="a task run's progress.csv")
    parser.add_argument("--window", type=float, default=1e6, help="env steps per row (default 1e6)")
    args = parser.parse_args()
    if not args.window > 0:
        sys.exit("error: --window must be > 0")
    try:
        with open(args.progress, newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        sys.exit(f"error: {args.progress}: {e.strerror}")
    if not rows or "normalized_return" not in rows[0]:
        sys.exit(f"error: {args.progress}: not a task run's progress.csv (no normalized_return column)")
    terms = [k for k in rows[0] if k.startswith("reward_")]
    last = float(rows[-1]["env_steps"])
    window = 1
    while (window - 1) * args.window < last:
        # Iterations in which no episode ended have no normalized return (nan).
        rows_in = [r for r in rows if (window - 1) * args.window < float(r["env_steps"]) <= window * args.window
                   and r["normalized_return"] != "nan"]
        if rows_in:
            def median(key):
                return statistics.median(float(r[key]) for r in rows_in)
            figures = [f"normalized return {median('normalized_return'):.3f}",
                       f"episode length {median('episode_length'):.1f}"]
            figures += [f"{k[len('reward_'):]} {median(k):.3f}" for k in terms]
            print(f"{window * args.window / 1e6:.1f} M: " + ", ".join(figures))
        window += 1


if __name__ == "__main__":
    main()
