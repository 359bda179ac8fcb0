#!/usr/bin/env python3
"""Opens a simulation session and steps it with uniformly random actions, printing the
throughput (session steps and env steps per second, measured on the client, so including
the network and the numpy encoding) and episode statistics.

It shows the basic training-loop shape: ``Client.session()`` returns the first observations,
``Session.step(actions)`` returns numpy arrays (obs, reward, done, ...) for all envs at once,
and episodes that end are reset by the server in the same step.

    /usr/bin/python3 client/python/examples/random_actions.py --num_envs 256 --steps 200
"""

import argparse
import time

from _path import ensure_modskill_importable

ensure_modskill_importable()
import numpy as np  # noqa: E402

import modskill  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--server", default="127.0.0.1:50051", help="host:port of the server")
    parser.add_argument("--token_file", help="file holding the server's bearer token")
    parser.add_argument("--tls_ca", help="PEM root certificates: connect with TLS")
    parser.add_argument("--num_envs", type=int, default=64)
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--layout", default="", help="part layout (default: the server's default)")
    parser.add_argument("--motions", nargs="*", default=[], help="clip names (default: the whole library)")
    parser.add_argument("--amp_obs", default="omit", choices=["full", "newest", "omit"],
                        help="AMP observation to receive (omit: the smallest replies)")
    parser.add_argument("--scale", type=float, default=1.0, help="actions are uniform in [-scale, scale]")
    args = parser.parse_args()

    rng = np.random.default_rng(args.seed)
    with modskill.Client(args.server, token_file=args.token_file, tls_ca=args.tls_ca) as client:
        opened = time.perf_counter()
        with client.session(args.num_envs, seed=args.seed, part_layout=args.layout, motions=args.motions,
                            amp_obs=args.amp_obs) as session:
            spec = session.spec
            print(f"session {session.session_id}: {session.num_envs} envs, layout {spec.part_layout}, "
                  f"obs {spec.obs_size}, actions {spec.action_size}, {len(session.clip_names)} clips "
                  f"(opened in {time.perf_counter() - opened:.2f} s)")
            episodes, reward_sum, lengths = 0, 0.0, []
            episode_steps = np.zeros(session.num_envs, np.int64)
            start = time.perf_counter()
            for _ in range(args.steps):
                actions = rng.uniform(-args.scale, args.scale, (session.num_envs, spec.action_size)).astype(np.float32)
                result = session.step(actions)
                reward_sum += float(result.reward.sum())
                episode_steps += 1
                episodes += int(result.done.sum())
                lengths.extend(episode_steps[result.done].tolist())
                episode_steps[result.done] = 0
            seconds = time.perf_counter() - start
            server_side = next((s for s in client.stats()["sessions"] if s["session_id"] == session.session_id), None)

    steps = args.steps
    print(f"{steps} steps in {seconds:.2f} s: {steps / seconds:.1f} steps/s, "
          f"{steps * args.num_envs / seconds:.0f} env steps/s")
    print(f"mean reward {reward_sum / (steps * args.num_envs):.3f}, {episodes} episodes ended"
          + (f", mean length {np.mean(lengths):.1f} steps" if lengths else ""))
    if server_side is not None:
        print(f"server: {server_side['steps_per_second']:.0f} env steps/s since the session opened, "
              f"{server_side['physics_resets']} physics resets")


if __name__ == "__main__":
    main()
