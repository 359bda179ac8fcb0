#!/usr/bin/env python3
"""Where and when a tracking policy leaves the reference: one rollout per policy on one clip,
frame by frame (E_mpjpe's own definition: body positions relative to the root, not rotated).

    /usr/bin/python3 bench/rollout_errors.py --server HOST:PORT --clip NAME POLICY.pt [POLICY.pt ...]

Prints per policy: E_mpjpe of the rollout; the bodies with the largest root-relative error and
their mean offset from the reference (x, y, z in the world frame, mm: a systematic lean or a
foot that lags shows here, noise averages out); the mean error per step (does it grow?); the
worst body's height beside the reference's, step by step (stance and swing); the pelvis's height
and its roll / pitch / yaw beside the reference's. The server must serve the clip (run it with
--no_generative to keep the reference as shipped).
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "client", "python"))
from modskill.client import Client  # noqa: E402
from modskill.errors import ServerError  # noqa: E402


def roll_pitch_yaw(quats):
    """Degrees, from (w, x, y, z) rows."""
    w, x, y, z = quats.T
    roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1, 1))
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return np.degrees(np.stack([roll, pitch, yaw], axis=1))


def report(client, names, policy, clip, worst):
    rollouts = client.rollout(checkpoint=policy, clips=[clip], frames=True)
    if not rollouts:
        sys.exit(f"error: clip '{clip}': the server returned no rollout")
    r = rollouts[0]
    sim, ref = np.asarray(r.sim_body_pos), np.asarray(r.ref_body_pos)
    offset = (sim - sim[:, :1]) - (ref - ref[:, :1])  # T x bodies x 3, root-relative
    error = np.linalg.norm(offset, axis=2) * 1000
    print(f"## {policy} on {clip}: {len(error)} steps, E_mpjpe {error.mean():.1f} mm")
    per_body = error.mean(axis=0)
    for b in np.argsort(-per_body)[:worst]:
        mean = offset[:, b].mean(axis=0) * 1000
        print(f"  {names[b]:<10} {per_body[b]:6.1f} mm, mean offset x {mean[0]:+6.1f} y {mean[1]:+6.1f} z {mean[2]:+6.1f}")
    print("  error per step, mean of bodies (mm): " + " ".join(f"{e:.0f}" for e in error.mean(axis=1)))
    top = int(np.argmax(per_body))
    print(f"  {names[top]} height, sim (mm): " + " ".join(f"{z * 1000:.0f}" for z in sim[:, top, 2]))
    print(f"  {names[top]} height, ref (mm): " + " ".join(f"{z * 1000:.0f}" for z in ref[:, top, 2]))
    pelvis_rpy = roll_pitch_yaw(np.asarray(r.sim_body_rot)[:, 0]) - roll_pitch_yaw(np.asarray(r.ref_body_rot)[:, 0])
    pelvis_rpy = (pelvis_rpy + 180) % 360 - 180
    print(f"  pelvis, sim - ref: height {(sim[:, 0, 2] - ref[:, 0, 2]).mean() * 1000:+.1f} mm, roll / pitch / yaw "
          + " / ".join(f"{v:+.1f}" for v in pelvis_rpy.mean(axis=0)) + " deg (means)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--server", required=True)
    parser.add_argument("--clip", required=True)
    parser.add_argument("--worst", type=int, default=6, help="bodies listed (default 6)")
    parser.add_argument("policies", nargs="+")
    args = parser.parse_args()
    for policy in args.policies:
        if not os.path.isfile(policy):
            sys.exit(f"error: policy '{policy}': no such file")
    client = Client(args.server)
    try:
        names = list(client.describe().body_names)
        for policy in args.policies:
            report(client, names, policy, args.clip, args.worst)
    except ServerError as e:
        sys.exit(f"error: {e}")


if __name__ == "__main__":
    main()
