#!/usr/bin/env python3
"""Prints what a modskill server offers: the env spec of a part layout (observation and action
sizes, the body parts with their observation and action slices, joints, reward terms) and the
clips of its motion library.

This is the first thing to run against a new server: clients never hard-code sizes, they read
them from ``Client.describe()`` as shown here.

    /usr/bin/python3 client/python/examples/print_spec.py --server 127.0.0.1:50051
"""

import argparse

from _path import ensure_modskill_importable

ensure_modskill_importable()
import modskill  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--server", default="127.0.0.1:50051", help="host:port of the server")
    parser.add_argument("--token_file", help="file holding the server's bearer token")
    parser.add_argument("--tls_ca", help="PEM root certificates: connect with TLS")
    parser.add_argument("--layout", default="", help="part layout (default: the server's default)")
    parser.add_argument("--joints", action="store_true", help="also list the joints in action order")
    args = parser.parse_args()

    with modskill.Client(args.server, token_file=args.token_file, tls_ca=args.tls_ca) as client:
        spec = client.describe(args.layout)
        motions = client.motions()

    print(f"server {args.server}")
    print(f"part layout {spec.part_layout} (offered: {', '.join(spec.part_layouts)})")
    print(f"  obs_size {spec.obs_size} (self {spec.self_obs_size} + task {spec.task_obs_size}), "
          f"action_size {spec.action_size}")
    print(f"  amp_obs {spec.amp_history} frames x {spec.amp_obs_per_frame} = {spec.amp_obs_size}")
    print(f"  control_dt {spec.control_dt:.4f} s ({1.0 / spec.control_dt:.0f} Hz)")
    print(f"  reward terms: {', '.join(spec.reward_terms)}")
    print(f"  {len(spec.body_names)} bodies, {len(spec.joint_names)} joints")
    print(f"  {'part':<8} {'obs slice':>12} {'action slice':>13}  bodies")
    for part in spec.parts:
        print(f"  {part.name:<8} {f'[{part.obs.start}, {part.obs.stop})':>12} "
              f"{f'[{part.action.start}, {part.action.stop})':>13}  {' '.join(part.bodies)}")
    if args.joints:
        for i, name in enumerate(spec.joint_names):
            print(f"  action {i:3d}: {name:<14} target = {spec.action_offset[i]:+.3f} "
                  f"{spec.action_scale[i]:+.3f} * a rad")

    total = sum(m["duration"] for m in motions)
    print(f"\n{len(motions)} motions, {total / 60:.1f} min")
    print(f"  {'name':<26} {'frames':>6} {'fps':>5} {'seconds':>7}  label")
    for m in motions:
        print(f"  {m['name']:<26} {m['frames']:>6} {m['fps']:>5.0f} {m['duration']:>7.1f}  {m['label']}")


if __name__ == "__main__":
    main()
