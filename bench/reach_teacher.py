#!/usr/bin/env python3
"""A reach teacher from held reach poses: where each skill holds the hand, and the z that holds it.

    /usr/bin/python3 bench/reach_teacher.py --server HOST:PORT --skills POLICY.pt --out TEACHER.txt
        [--hand R_Hand] [--frames 30] [--part_layout 5part]

The server must serve clips that hold a hand still (`modskill-motion reach`, `splice --timing
hold`); POLICY.pt is a proprioceptive tracker fine-tuned on them (the skills a reach head
reuses). Every clip of the server's library is rolled out with its z recorded; over the clip's
last --frames rows the hand's mean position relative to the root, in the root's heading frame
(the frame of the reach task's goal, ReachTask::WriteGoal), is the entry's point and each part's
mean z (normalized back to the sphere) its z. The file is text: a "parts NAME..." line, an
"embed_dim E" line, then per entry "entry CLIP x y z" and the parts' z (parts x E numbers). Clips the skills do not track to their end
(terminated) are left out. `modskill-learner --task reach --task_teacher TEACHER.txt` pulls the
head toward the z of the entry nearest each goal (behaviour cloning of the nearest held pose).
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "client", "python"))
from modskill.client import Client  # noqa: E402
from modskill.errors import ServerError  # noqa: E402


def inverse_heading(quat_wxyz):
    """The rotation that undoes the yaw of a (w, x, y, z) orientation (MuJoCo's order)."""
    w, x, y, z = quat_wxyz
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])


def held_entry(rollout, hand_index, frames):
    """(point [3], z [parts, E]) over the rollout's last `frames` rows that carry a z."""
    z = np.asarray(rollout.skill_z)
    rows = [t for t in range(len(z)) if np.all(np.isfinite(z[t]))][-frames:]
    if not rows:
        return None
    pos, rot = np.asarray(rollout.sim_body_pos), np.asarray(rollout.sim_body_rot)
    points = [inverse_heading(rot[t, 0]) @ (pos[t, hand_index] - pos[t, 0]) for t in rows]
    mean_z = z[rows].mean(axis=0)
    mean_z /= np.linalg.norm(mean_z, axis=-1, keepdims=True)
    return np.mean(points, axis=0), mean_z


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--server", required=True)
    parser.add_argument("--skills", required=True, help="the tracker's policy.pt")
    parser.add_argument("--out", required=True)
    parser.add_argument("--hand", default="R_Hand")
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--part_layout", default="5part")
    args = parser.parse_args()
    if args.frames < 1:
        sys.exit(f"error: --frames {args.frames}: must be at least 1")
    client = Client(args.server)
    try:
        spec = client.describe(args.part_layout)
        clips = [m["name"] for m in client.motions()]
        if args.hand not in spec.body_names:
            sys.exit(f"error: --hand {args.hand}: not a body of the server's skeleton")
        hand = spec.body_names.index(args.hand)
        entries, dropped = [], []
        for clip in clips:
            rollout = client.record_skills(args.skills, clips=[clip])[0]
            entry = None if not rollout.success else held_entry(rollout, hand, args.frames)
            if entry is None:
                dropped.append(clip)
                continue
            point, z = entry
            entries.append({"clip": clip, "point": [round(float(v), 5) for v in point],
                            "z": [[round(float(v), 6) for v in part] for part in z]})
    except ServerError as e:
        sys.exit(f"error: {args.server}: {e}")
    if not entries:
        sys.exit("error: no clip was tracked to its end; no teacher entries")
    # Plain text, one entry per line, so that the learner reads it without a JSON parser.
    lines = [f"# modskill reach teacher v1: skills {args.skills}, hand {args.hand}, last {args.frames} rows",
             "parts " + " ".join(p.name for p in spec.parts), f"embed_dim {len(entries[0]['z'][0])}"]
    for e in entries:
        values = e["point"] + [v for part in e["z"] for v in part]
        lines.append("entry " + e["clip"] + " " + " ".join(repr(v) for v in values))
    tmp = args.out + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(tmp, args.out)
    print(f"wrote {args.out}: {len(entries)} entries ({len(dropped)} clips not tracked to their end"
          f"{': ' + ', '.join(dropped) if dropped else ''})")


if __name__ == "__main__":
    main()
