#!/usr/bin/env python3
"""Plots a training run's learning curve from its progress.csv.

modskill-learner writes one row per iteration to RUN_DIR/progress.csv (and the same scalars
as TensorBoard events). This draws mean episode return, mean per-step task reward (the
normalized return in task runs, which have that column) and mean episode length against
environment steps, one line per run, to a PNG. A run trained with --keep_best_every has an
evaluations.csv beside its progress.csv; then a fourth panel draws its evaluation curve (E_mpjpe
solid, E_g-mpjpe dashed, the kept policies as dots).

    /usr/bin/python3 plot_learning_curve.py runs/walk/progress.csv runs/library/progress.csv --out curve.png
"""
import argparse
import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise SystemExit(f"error: {path}: no rows")
    # Columns added after a run started are empty in its older rows (resumed runs): NaN there.
    return {key: [float(row[key]) if row[key] not in ("", None) else float("nan") for row in rows] for key in rows[0]}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("csv", nargs="+", help="progress.csv files")
    parser.add_argument("--labels", nargs="*", help="one label per file (default: the run directory's name)")
    parser.add_argument("--out", required=True, help="PNG to write")
    args = parser.parse_args()
    labels = args.labels or [os.path.basename(os.path.dirname(os.path.abspath(p))) for p in args.csv]
    if len(labels) != len(args.csv):
        raise SystemExit("error: --labels needs one label per file")
    runs = [read(path) for path in args.csv]
    evaluations = [os.path.join(os.path.dirname(os.path.abspath(p)), "evaluations.csv") for p in args.csv]
    evaluations = [read(p) if os.path.exists(p) else None for p in evaluations]
    panels = 4 if any(evaluations) else 3
    figure, axes = plt.subplots(1, panels, figsize=(5 * panels, 4))
    task_runs = all("normalized_return" in run for run in runs)
    middle = "normalized_return" if task_runs else "mean_task_reward"
    for run, label in zip(runs, labels):
        steps = [s / 1e6 for s in run["env_steps"]]
        axes[0].plot(steps, run["episode_return"], label=label)
        axes[1].plot(steps, run[middle], label=label)
        axes[2].plot(steps, run["episode_length"], label=label)
    for evaluation, label, color in zip(evaluations, labels, plt.rcParams["axes.prop_cycle"].by_key()["color"] * 4):
        if evaluation is None:
            continue
        steps = [s / 1e6 for s in evaluation["env_steps"]]
        axes[3].plot(steps, evaluation["mpjpe_mm"], color=color, label=f"{label} E_mpjpe")
        axes[3].plot(steps, evaluation["g_mpjpe_mm"], color=color, linestyle="--", label=f"{label} E_g-mpjpe")
        kept = [(x, y) for x, y, k in zip(steps, evaluation["mpjpe_mm"], evaluation["kept"]) if k > 0.5]
        axes[3].plot([x for x, _ in kept], [y for _, y in kept], "o", color=color, markersize=3)
    middle_title = "normalized return (episodes ended)" if task_runs else "mean task reward per step"
    titles = ["mean episode return", middle_title, "mean episode length (steps)", "evaluation errors (mm)"]
    for axis, title in zip(axes, titles):
        axis.set_title(title)
        axis.set_xlabel("env steps (millions)")
        axis.grid(alpha=0.3)
        axis.legend()
    figure.tight_layout()
    figure.savefig(args.out, dpi=100)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
