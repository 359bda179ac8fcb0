#!/usr/bin/env python3
"""A model on paper of training throughput on a cluster, built from costs measured on this
machine (issue 15): env steps/s for a number of server cores and of data-parallel learner ranks,
and what limits each setup.

Per env step of its own, each learner rank spends: collection time (at the rate of the slowest
of its share of the servers, its inference, and its network link), update time (on
`--learner_cores` cores, the parallel speedup measured from 1 to 2 threads extrapolated by
Amdahl's law), and its share of the gradient all-reduces (a ring: 2(R-1)/R of the payload over the
link and 2(R-1) latencies per all-reduce, one per minibatch and epoch). Collection and update are
sequential, as in the default learner; the batch per iteration does not matter per step.

    /usr/bin/python3 bench/scaling_model.py [--allreduce_bytes_per_iteration N] [--learner_cores 16] ...

The defaults are the figures measured here; each flag names the benchmark that measures it.
"""
import argparse


def parse():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sim_steps_per_core_s", type=float, default=2857,
                   help="env steps/s of one server thread (sim_throughput_bench, 256 envs)")
    p.add_argument("--inference_per_core_s", type=float, default=30345,
                   help="small policy inference samples/s on one thread (learner_throughput_bench, batch 2048)")
    p.add_argument("--update_per_core_s", type=float, default=8323,
                   help="small PPO update samples/s on one thread (learner_throughput_bench, batch 2048)")
    p.add_argument("--update_two_thread_speedup", type=float, default=15040 / 8323,
                   help="update samples/s on 2 threads over 1 (learner_throughput_bench)")
    p.add_argument("--stream_bytes_per_step", type=float, default=13070,
                   help="action + step result bytes per env step (grpc_transport_bench; 4.9 KB with amp_obs NEWEST)")
    p.add_argument("--allreduce_bytes_per_step", type=float, default=2 * 2146,
                   help="all-reduce payload a rank sends per env step of its own (data_parallel_bench "
                        "reports it per step of both ranks: 2146 B)")
    p.add_argument("--minibatch_size", type=int, default=2048, help="the small preset's")
    p.add_argument("--epochs", type=int, default=2 + 1, help="PPO epochs + discriminator epochs (small preset)")
    p.add_argument("--learner_cores", type=int, default=16, help="cores of one learner rank's machine")
    p.add_argument("--link_gbit_s", type=float, default=10, help="network bandwidth of each machine")
    p.add_argument("--link_latency_us", type=float, default=50, help="one-way latency inside a cluster")
    p.add_argument("--server_cores", default="8,64,512")
    p.add_argument("--ranks", default="1,2,4,8")
    return p.parse_args()


def amdahl(speedup_two, cores):
    serial = 2 / speedup_two - 1  # from 1 / (f + (1 - f) / 2) = speedup_two
    return 1 / (serial + (1 - serial) / cores)


def model(a, server_cores, ranks):
    """(env steps/s, the largest cost per step, all-reduce's share, what the servers alone give)."""
    bandwidth = a.link_gbit_s * 1e9 / 8
    rates = {
        "servers": server_cores * a.sim_steps_per_core_s / ranks,
        "inference": a.inference_per_core_s * a.learner_cores,
        "learner link": bandwidth / a.stream_bytes_per_step,
    }
    limit = min(rates, key=rates.get)
    costs = {f"collection ({limit})": 1 / rates[limit],
             "update": 1 / (a.update_per_core_s * amdahl(a.update_two_thread_speedup, a.learner_cores)),
             "all-reduce": 0.0}
    if ranks > 1:
        ring = 2 * (ranks - 1)
        costs["all-reduce"] = (ring / ranks * a.allreduce_bytes_per_step / bandwidth +
                               a.epochs / a.minibatch_size * ring * a.link_latency_us * 1e-6)
    per_step = sum(costs.values())
    return ranks / per_step, max(costs, key=costs.get), costs["all-reduce"] / per_step, rates["servers"] * ranks


def main():
    a = parse()
    print(f"learner rank = {a.learner_cores} cores (update speedup {amdahl(a.update_two_thread_speedup, a.learner_cores):.1f} x "
          f"by Amdahl from {a.update_two_thread_speedup:.2f} x on 2), {a.link_gbit_s:g} Gbit/s links, "
          f"{a.link_latency_us:g} us latency")
    print("| server cores | learner ranks | env steps/s | servers could give | largest cost per step | all-reduce share |")
    print("|---|---|---|---|---|---|")
    for cores in (int(x) for x in a.server_cores.split(",")):
        for ranks in (int(x) for x in a.ranks.split(",")):
            rate, bound, share, supply = model(a, cores, ranks)
            print(f"| {cores} | {ranks} | {rate:,.0f} | {supply:,.0f} | {bound} | {100 * share:.1f} % |")


if __name__ == "__main__":
    main()
