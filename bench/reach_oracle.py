#!/usr/bin/env python3
"""What a skill set could earn on reach if a head always chose the right skill: an upper bound.

    /usr/bin/python3 bench/reach_oracle.py EVAL.html [--box_size 2] [--box_center 0,0,1] [--base deepmimic_stand]

EVAL.html: the learner's tracking evaluation page (`modskill-learner --eval ... --eval_out DIR`)
of the skills on clips that hold a hand still (`modskill-motion reach`, `splice --timing hold`).
For each clip and each role (reference, simulated) the R_Hand's mean position over the clip's last
30 frames, in the reach task's frame (heading frame on the root's ground point), is one "held
point". For 100,000 targets drawn uniformly in the box (as ReachTask draws them, seed 0) the
oracle's per-step reward is the best exp(-5 d^2) over the held points: a head that switched to
the right skill at once, with no time spent moving, would earn it. Printed beside it: the base
clip's hand alone (a head that never leaves its prior, standing). The simulated row is what the
trained skills actually do; the reference row is what the clips ask for.
"""
import argparse
import base64
import json
import re
import sys

import numpy as np


def load_scene(path):
    try:
        text = open(path, encoding="utf-8").read()
    except OSError as e:
        sys.exit(f"error: {path}: {e.strerror}")
    match = re.search(r'<script id="modskill-scene"[^>]*>(.*?)</script>', text, re.S)
    if not match:
        sys.exit(f"error: {path}: not a viewer page (no modskill-scene script)")
    return json.loads(match.group(1))


def heading_inverse(quat_wxyz):
    w, x, y, z = quat_wxyz
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])


def held_points(scene, hand, frames=30):
    """{role: [(clip name, held point)]}"""
    names = [b["name"] for b in scene["bodies"]]
    if hand not in names:
        sys.exit(f"error: the page's skeleton has no body '{hand}'")
    h, n = names.index(hand), len(names)
    points = {}
    for clip in scene["clips"]:
        for track in clip["tracks"]:
            pos = np.frombuffer(base64.b64decode(track["pos"]), dtype=np.float32).reshape(-1, n, 3)
            rot = np.frombuffer(base64.b64decode(track["rot"]), dtype=np.float32).reshape(-1, n, 4)
            local = []
            for f in range(max(0, len(pos) - frames), len(pos)):
                ground = pos[f, 0] * np.array([1, 1, 0])
                local.append(heading_inverse(rot[f, 0]) @ (pos[f, h] - ground))
            points.setdefault(track["role"], []).append((clip["name"], np.mean(local, axis=0)))
    return points


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("page")
    parser.add_argument("--box_size", type=float, default=2.0)
    parser.add_argument("--box_center", default="0,0,1")
    parser.add_argument("--base", default="deepmimic_stand", help="the clip whose hand is the prior's")
    parser.add_argument("--hand", default="R_Hand")
    args = parser.parse_args()
    try:
        center = np.array([float(v) for v in args.box_center.split(",")])
        assert center.shape == (3,) and np.isfinite(center).all()
    except (ValueError, AssertionError):
        sys.exit(f"error: --box_center '{args.box_center}': expected x,y,z")
    if not 0 < args.box_size <= 4:
        sys.exit(f"error: --box_size {args.box_size}: expected (0, 4] m")
    targets = center + np.random.default_rng(0).uniform(-args.box_size / 2, args.box_size / 2, size=(100000, 3))
    print(f"box {args.box_size} m at ({args.box_center}); per-step reach reward exp(-5 d^2), mean over targets")
    for role, named in held_points(load_scene(args.page), args.hand).items():
        held = np.array([p for _, p in named])
        best = np.exp(-5 * ((targets[:, None, :] - held[None]) ** 2).sum(-1)).max(1).mean()
        base = [p for name, p in named if name == args.base]
        alone = np.exp(-5 * ((targets - base[0]) ** 2).sum(-1)).mean() if base else float("nan")
        print(f"  {role:10s} {len(held):3d} held points: oracle {best:.3f}, {args.base}'s hand alone {alone:.3f}")


if __name__ == "__main__":
    main()
