#!/usr/bin/env python3
"""Summarizes a bench/learning_bench.sh output directory as a Markdown table.

One row per variant and evaluated policy (the final policy.pt, any policy_at_<N>M.pt milestone
and, with --keep_best_every, policy_best.pt at the iteration it was kept), plus the open-loop
reference baseline: env steps and wall time trained, the mean training episode length and
imitation reward at that point, and the evaluation (paper protocol: a clip fails when its mean
body error exceeds 0.5 m) success rate, E_mpjpe and E_g-mpjpe.

    /usr/bin/python3 bench/learning_table.py OUT_DIR NAME [NAME ...]
"""
import csv
import glob
import json
import os
import re
import sys


def progress(run_dir):
    path = os.path.join(run_dir, "progress.csv")
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return [{k: float(v) for k, v in row.items() if v not in ("", None)} for row in csv.DictReader(f)]


def row_at(rows, steps, slack=1.02):
    """The last progress row at or before `steps` env steps (None: the last row). A milestone is
    exported at the first iteration past it, hence the slack."""
    if not rows:
        return {}
    if steps is None:
        return rows[-1]
    before = [r for r in rows if r["env_steps"] <= steps * slack]
    return before[-1] if before else rows[0]


def last_10(rows, row, value):
    """Mean of value(r) over the last 10 iterations up to `row` (one iteration is noisy)."""
    upto = [r for r in rows if r["env_steps"] <= row.get("env_steps", 0)][-10:]
    return sum(value(r) for r in upto) / max(1, len(upto))


def kept_at(run_dir):
    """policy_best.json (--keep_best_every): the iteration and env steps of the kept policy."""
    path = os.path.join(run_dir, "policy_best.json")
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)


IMITATION_TERMS = ("reward_pos", "reward_rot", "reward_vel", "reward_ang_vel")


def imitation_reward(r):
    """The per-step imitation reward during training, energy left out (1: perfect tracking). It
    averages thousands of episodes, where the evaluation is one rollout per clip: a steadier
    measure of how closely a policy tracks."""
    return sum(r.get(term, 0.0) for term in IMITATION_TERMS)


def main():
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    out, names = sys.argv[1], sys.argv[2:]
    lines = ["| variant | policy at | env steps | train minutes | episode length (train, last 10 it.) | "
             "imitation reward (train, last 10 it.) | eval Succ | E_mpjpe (mm) | E_g-mpjpe (mm) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name in names:
        rows = progress(os.path.join(out, name))
        for eval_json in sorted(glob.glob(os.path.join(out, name, "eval*", "eval.json"))):
            tag = os.path.basename(os.path.dirname(eval_json))
            milestone = re.match(r"eval_at_([0-9.e+]+)M$", tag)
            steps = float(milestone.group(1)) * 1e6 if milestone else None
            label = f"{milestone.group(1)} M" if milestone else "end"
            kept = kept_at(os.path.join(out, name)) if tag == "eval_best" else None
            if kept:
                steps, label = kept["env_steps"], "best kept (it. %d)" % kept["iteration"]
            row = row_at(rows, steps, 1.0 if kept else 1.02)
            with open(eval_json) as f:
                ev = json.load(f)
            lines.append("| %s | %s | %.2f M | %.1f | %.1f | %.3f | %.0f %% | %.1f | %.1f |" % (
                name, label, row.get("env_steps", 0) / 1e6,
                row.get("wall_seconds", 0) / 60, last_10(rows, row, lambda r: r["episode_length"]),
                last_10(rows, row, imitation_reward), 100 * ev["success_rate"], ev["mpjpe_mm"], ev["g_mpjpe_mm"]))
    baseline = os.path.join(out, "baseline", "eval.json")
    if os.path.exists(baseline):
        with open(baseline) as f:
            ev = json.load(f)
        lines.append("| open-loop reference (no learning) | - | 0 | 0 | - | - | %.0f %% | %.1f | %.1f |" % (
            100 * ev["success_rate"], ev["mpjpe_mm"], ev["g_mpjpe_mm"]))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
