#!/usr/bin/env python3
"""Runs a policy checkpoint on one clip and plots how well it tracks the reference motion.

The server runs the TorchScript checkpoint (uploaded from this machine) with evaluation
termination and streams the simulated and reference body positions of every step
(``Client.rollout(..., frames=True)``). The PNG shows the tracking error of every body over
time (top) and the mean error per body, coloured by body part (bottom); the clip's metrics
are printed.

    /usr/bin/python3 client/python/examples/rollout_plot.py \\
        --checkpoint policy.pt --clip deepmimic_walk --out error.png
"""

import argparse
import sys

from _path import ensure_modskill_importable

ensure_modskill_importable()
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import modskill  # noqa: E402


def plot(result: "modskill.ClipRollout", spec: "modskill.EnvSpec", out: str) -> None:
    errors_mm = result.body_errors() * 1000.0  # [T, bodies]
    seconds = np.arange(errors_mm.shape[0]) * spec.control_dt
    body_names = spec.body_names
    part_of = {body: part.name for part in spec.parts for body in part.bodies}
    part_names = list(spec.part_names)
    colors = {name: plt.get_cmap("tab10")(i % 10) for i, name in enumerate(part_names)}

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(12, 9), gridspec_kw={"height_ratios": [3, 2]})
    for b, name in enumerate(body_names):
        top.plot(seconds, errors_mm[:, b], color=colors.get(part_of.get(name), "gray"), lw=1, alpha=0.8)
    top.plot(seconds, errors_mm.mean(axis=1), color="black", lw=2.5, label="mean over bodies")
    for name in part_names:  # one legend entry per part
        top.plot([], [], color=colors[name], label=name)
    top.set_xlabel("time (s)")
    top.set_ylabel("body position error (mm)")
    top.set_xlim(0, max(seconds[-1], spec.control_dt) if len(seconds) else 1)
    top.set_ylim(bottom=0)
    top.grid(alpha=0.3)
    top.legend(loc="upper left", fontsize=8, ncol=3)
    top.set_title(f"{result.clip}: {'tracked to the end' if result.success else 'terminated'} after "
                  f"{result.steps} steps, g-MPJPE {result.g_mpjpe_mm:.0f} mm, MPJPE {result.mpjpe_mm:.0f} mm")

    mean_mm = errors_mm.mean(axis=0) if len(errors_mm) else np.asarray(result.body_error_mm)
    bottom.bar(np.arange(len(body_names)), mean_mm,
               color=[colors.get(part_of.get(name), "gray") for name in body_names])
    bottom.set_xticks(np.arange(len(body_names)))
    bottom.set_xticklabels(body_names, rotation=60, ha="right", fontsize=8)
    bottom.set_ylabel("mean error (mm)")
    bottom.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--server", default="127.0.0.1:50051", help="host:port of the server")
    parser.add_argument("--token_file", help="file holding the server's bearer token")
    parser.add_argument("--tls_ca", help="PEM root certificates: connect with TLS")
    parser.add_argument("--checkpoint", required=True, help="TorchScript policy checkpoint (a local file)")
    parser.add_argument("--on_server", action="store_true",
                        help="--checkpoint is a path on the server's machine: send the path, not the file")
    parser.add_argument("--clip", help="clip to track (default: the library's first clip)")
    parser.add_argument("--termination", default="evaluation", choices=["evaluation", "training", "none"])
    parser.add_argument("--max_steps", type=int, default=0, help="step limit (0: the clip's length)")
    parser.add_argument("--out", default="error.png", help="PNG to write")
    args = parser.parse_args()

    with modskill.Client(args.server, token_file=args.token_file, tls_ca=args.tls_ca) as client:
        clip = args.clip or client.motions()[0]["name"]
        source = {"server_checkpoint": args.checkpoint} if args.on_server else {"checkpoint": args.checkpoint}
        results = client.rollout(clips=[clip], frames=True, termination=args.termination,
                                 max_steps_per_clip=args.max_steps, **source)
        if not results:
            sys.exit(f"the server returned no metrics for {clip}")
        result = results[0]
        # The checkpoint's layout decides the parts; the bodies and dt are the same in every layout.
        spec = client.describe()
        if len(result.part_error_mm) != len(spec.parts):
            spec = next((s for s in map(client.describe, spec.part_layouts)
                         if len(s.parts) == len(result.part_error_mm)), spec)

    print(f"{result.clip}: success {result.success}, {result.steps} steps, {len(result.frames)} frames")
    print(f"  g-MPJPE {result.g_mpjpe_mm:.1f} mm, MPJPE {result.mpjpe_mm:.1f} mm, "
          f"acceleration error {result.acc_error_mm:.2f} mm/frame^2, velocity error {result.vel_error_mm:.2f} mm/frame")
    for name, error in zip(spec.part_names, result.part_error_mm):
        print(f"  {name:<8} {error:7.1f} mm")
    plot(result, spec, args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
