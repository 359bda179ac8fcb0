#!/usr/bin/python3
"""PNG figures of skill composition (issue 13) from modskill-client's JSON; run with Debian's
/usr/bin/python3 (numpy, matplotlib).

  tools/plot_skills.py velocity DIR/compose.json OUT.png
      the composed parts' speed per frame in the composed rollout, beside the same parts in the
      base and source rollouts alone (root-relative, and global dashed)
  tools/plot_skills.py embedding DIR/skills.json OUT.png
      the recorded z of every clip and part on their 2-D PCA plane: colour by clip, marker by part
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def save(figure, out):
    """Writes the PNG atomically (a temporary file beside it, then a rename)."""
    tmp = out + ".tmp.png"
    figure.savefig(tmp, dpi=120, bbox_inches="tight")
    os.replace(tmp, out)
    print(f"wrote {out}")


def velocity(compose_path, out):
    with open(compose_path) as f:
        data = json.load(f)
    dt = data["control_dt"]
    parts = data["parts"]
    figure, axes = plt.subplots(len(parts), 1, figsize=(8, 3 * len(parts)), squeeze=False)
    styles = {"composed": ("C3", 2.0), "base": ("C0", 1.0), "source": ("C2", 1.0)}
    for axis, part in zip(axes[:, 0], parts):
        for key, (colour, width) in styles.items():
            rollout = data["rollouts"][key]
            frames = rollout["frames"]
            t = [i * dt for i in range(len(frames))]
            local = [fr["part_root_relative_speed_mps"][part] for fr in frames]
            label = f"{key}: {rollout['clip']}" + ("" if rollout["success"] else " (terminated)")
            axis.plot(t, local, color=colour, linewidth=width, label=label)
            axis.plot(t, [fr["part_speed_mps"][part] for fr in frames], color=colour, linewidth=0.6, linestyle="--")
        axis.set_ylabel(f"{part} speed (m/s)")
        axis.set_title(f"{part}: root-relative speed (solid), global (dashed)", fontsize=9)
        axis.legend(fontsize=8)
    axes[-1, 0].set_xlabel("time (s)")
    mode = data["mode"].lower()
    figure.suptitle(f"{','.join(parts)} of {data['source']} {mode}ped onto {data['base']}" if mode == "swap"
                    else f"{','.join(parts)} interpolated from {data['base']} to {data['source']}", fontsize=10)
    save(figure, out)


def embedding(skills_path, out):
    with open(skills_path) as f:
        data = json.load(f)
    points = data["pca"]["points"]
    clips = list(dict.fromkeys(p["clip"] for p in points))
    parts = data["parts"]
    markers = "osD^v<>ph*"
    figure, axis = plt.subplots(figsize=(7, 6))
    for c, clip in enumerate(clips):
        for k, part in enumerate(parts):
            xs = [p["x"] for p in points if p["clip"] == clip and p["part"] == part]
            ys = [p["y"] for p in points if p["clip"] == clip and p["part"] == part]
            axis.scatter(xs, ys, s=9, color=f"C{c % 10}", marker=markers[k % len(markers)], alpha=0.7,
                         label=f"{clip} / {part}")
    explained = data["pca"]["explained_variance"]
    axis.set_xlabel(f"PC 1 ({100 * explained[0]:.1f} % of the variance)")
    axis.set_ylabel(f"PC 2 ({100 * explained[1]:.1f} % of the variance)")
    axis.set_title("skill embeddings z per clip (colour) and part (marker), PCA", fontsize=10)
    axis.legend(fontsize=6, ncol=2, markerscale=1.5)
    save(figure, out)


def main(argv):
    if len(argv) != 4 or argv[1] not in ("velocity", "embedding"):
        print(__doc__, file=sys.stderr)
        return 2
    (velocity if argv[1] == "velocity" else embedding)(argv[2], argv[3])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
