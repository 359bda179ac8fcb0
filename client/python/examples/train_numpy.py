#!/usr/bin/env python3
"""Trains a linear policy with random search (ARS, Mania et al. 2018), numpy only, through
``modskill.VectorEnv`` in the residual action mode, and prints its return per iteration.

The policy is ``actions = clip(W^T (obs - mean) / std, -1, 1)``, W starting at zero, which in the
residual mode means "play the reference pose open loop". Each iteration evaluates the current W
and ``--directions`` antithetic pairs W +- noise * delta, all at once: one batch of
``(2 * directions + 1) * envs_per_candidate`` envs, each row driven by its candidate's W. A
candidate's return is the reward of each env's first episode within ``--horizon`` steps (an env
that falls stops earning; the server restarts it, SAME_STEP autoreset, but that episode is not
counted), averaged over its envs. Then W moves along the directions whose pairs differ most:
W += step_size / (directions * std(returns)) * sum_k (R_k+ - R_k-) delta_k  (ARS V1, eq. in Alg. 1).

From a fresh clone, with a server running (see the README):

    /usr/bin/python3 client/python/examples/train_numpy.py --server 127.0.0.1:50051 --iterations 20
"""

import argparse
import time

from _path import ensure_modskill_importable

ensure_modskill_importable()
import numpy as np  # noqa: E402

import modskill  # noqa: E402


def rollout(env: modskill.VectorEnv, weights: np.ndarray, mean: np.ndarray, std: np.ndarray, horizon: int,
            seed: int) -> tuple:
    """Runs every candidate ``weights[c]`` ([C, obs_size, action_size]) on its block of envs for
    ``horizon`` steps. Returns each env's first-episode return [C, E] and the observations seen."""
    candidates = weights.shape[0]
    per_candidate = env.num_envs // candidates
    obs, _ = env.reset(seed=seed)
    returns = np.zeros(env.num_envs)
    alive = np.ones(env.num_envs, bool)  # still in its first episode
    seen = [obs.copy()]
    for _ in range(horizon):
        x = ((obs - mean) / std).reshape(candidates, per_candidate, -1)
        actions = np.clip(np.einsum("ceo,coa->cea", x, weights), -1.0, 1.0).reshape(env.num_envs, -1)
        obs, reward, terminated, truncated, _ = env.step(actions.astype(np.float32))
        returns += reward * alive
        alive &= ~(terminated | truncated)
        seen.append(obs.copy())
    return returns.reshape(candidates, per_candidate), np.concatenate(seen)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--server", default="127.0.0.1:50051", help="host:port of the server")
    parser.add_argument("--token_file", help="file holding the server's bearer token")
    parser.add_argument("--tls_ca", help="PEM root certificates: connect with TLS")
    parser.add_argument("--iterations", type=int, default=10)
    parser.add_argument("--directions", type=int, default=4, help="antithetic perturbation pairs per iteration")
    parser.add_argument("--envs_per_candidate", type=int, default=4)
    parser.add_argument("--horizon", type=int, default=40, help="steps per evaluation")
    parser.add_argument("--noise", type=float, default=0.005, help="perturbation scale of W")
    parser.add_argument("--step_size", type=float, default=0.002)
    parser.add_argument("--motions", nargs="*", default=["deepmimic_walk"],
                        help="clip names to track (none given: the whole library)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    if min(args.iterations, args.directions, args.envs_per_candidate, args.horizon) < 1:
        parser.error("--iterations, --directions, --envs_per_candidate and --horizon must be >= 1")

    rng = np.random.default_rng(args.seed)
    candidates = 2 * args.directions + 1  # the current W, then W + noise*delta_k, W - noise*delta_k
    start = time.perf_counter()
    with modskill.VectorEnv(args.server, num_envs=candidates * args.envs_per_candidate, seed=args.seed,
                            token_file=args.token_file, tls_ca=args.tls_ca, motions=args.motions,
                            action_mode="residual") as env:
        obs_size, action_size = env.single_observation_space.shape[0], env.single_action_space.shape[0]
        print(f"{env.num_envs} envs ({candidates} candidates x {args.envs_per_candidate}), obs {obs_size}, "
              f"actions {action_size}, residual action mode")
        weights = np.zeros((obs_size, action_size))
        first, _ = env.reset(seed=args.seed)
        mean, std = first.mean(axis=0), np.maximum(first.std(axis=0), 1e-2)  # updated every iteration
        for iteration in range(args.iterations):
            deltas = rng.standard_normal((args.directions, obs_size, action_size))
            trial = np.concatenate([weights[None], weights + args.noise * deltas, weights - args.noise * deltas])
            returns, seen = rollout(env, trial, mean, std, args.horizon, seed=args.seed + iteration)
            returns = returns.mean(axis=1)
            plus, minus = returns[1:1 + args.directions], returns[1 + args.directions:]
            spread = np.concatenate([plus, minus]).std()
            if spread > 0:
                weights += args.step_size / (args.directions * spread) * np.einsum("k,koa->oa", plus - minus, deltas)
            mean, std = seen.mean(axis=0), np.maximum(seen.std(axis=0), 1e-2)  # the next iteration's normalizer
            print(f"iteration {iteration + 1}: return {returns[0]:.3f} (perturbed {plus.mean():.3f} / "
                  f"{minus.mean():.3f}), |W| {np.linalg.norm(weights):.3f}")
        final, _ = rollout(env, np.repeat(weights[None], candidates, axis=0), mean, std, args.horizon,
                           seed=args.seed + args.iterations)
    print(f"final return {final.mean():.3f} over {env.num_envs} envs x {args.horizon} steps "
          f"({time.perf_counter() - start:.1f} s)")


if __name__ == "__main__":
    main()
