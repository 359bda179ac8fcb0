#!/usr/bin/env bash
# Data-parallel learners on this machine: env steps/s of 1 learner on 1 server against 2 learner
# ranks (--world_size 2) on 2 servers, each server with one thread, same settings and seed; and
# for the 2 ranks the share of rank 0's iteration time spent in collectives (progress.csv's
# allreduce_s: gradient all-reduces, statistics all-gathers and the small agreements, waiting for
# the other rank included) and the bytes rank 0 sends into them per env step.
#
#   bench/data_parallel_bench.sh [--build build] [--out runs/data_parallel_bench] [--iterations 8]
#                                [--envs 128]
#
# The first iteration (warm-up) is left out of the figures.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=build OUT=runs/data_parallel_bench ITERATIONS=8 ENVS=128
while (($#)); do
  case "$1" in
    --build) BUILD="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    --iterations) ITERATIONS="$2"; shift 2 ;;
    --envs) ENVS="$2"; shift 2 ;;
    *) echo "usage: $0 [--build DIR] [--out DIR] [--iterations N] [--envs N]" >&2; exit 2 ;;
  esac
done
for binary in server/modskill-server learner/modskill-learner; do
  [[ -x "$BUILD/$binary" ]] || { echo "error: no $BUILD/$binary (build it first)" >&2; exit 1; }
done
rm -rf "$OUT" && mkdir -p "$OUT"

free_port() { /usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
SERVERS=()
stop_servers() { for pid in "${SERVERS[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done; }
trap stop_servers EXIT
start_server() {  # prints the port
  local port; port=$(free_port)
  "$BUILD/server/modskill-server" --port "$port" --threads 1 > "$OUT/server_$port.log" 2>&1 &
  SERVERS+=($!)
  echo "$port"
}
# Both setups: small preset, one update thread per learner (two learners share the 2 cores).
COMMON=(--preset small --iterations "$ITERATIONS" --envs_per_server "$ENVS" --seed 1 --checkpoint_every 1000
        --update_threads 1 --server_timeout_s 60)

port=$(start_server)
"$BUILD/learner/modskill-learner" --servers "127.0.0.1:$port" --run_dir "$OUT/one" "${COMMON[@]}" \
    > "$OUT/one.log" 2>&1 || { echo "error: 1 learner failed; see $OUT/one.log" >&2; exit 1; }

rendezvous="127.0.0.1:$(free_port)"
pids=()
for rank in 0 1; do
  port=$(start_server)
  "$BUILD/learner/modskill-learner" --servers "127.0.0.1:$port" --run_dir "$OUT/two" "${COMMON[@]}" \
      --world_size 2 --rank "$rank" --rendezvous "$rendezvous" > "$OUT/two_rank$rank.log" 2>&1 &
  pids+=($!)
done
for rank in 0 1; do
  wait "${pids[$rank]}" || { echo "error: rank $rank failed; see $OUT/two_rank$rank.log" >&2; exit 1; }
done

/usr/bin/python3 - "$OUT" <<'PY'
import csv, sys
out = sys.argv[1]
def rows(name):
    with open(f"{out}/{name}/progress.csv") as f:
        return [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
def summary(name):
    r = rows(name)[1:]  # without the warm-up iteration
    if len(r) < 2:
        sys.exit(f"error: {name}: fewer than 3 iterations in progress.csv")
    steps = r[-1]["env_steps"] - r[0]["env_steps"]
    wall = r[-1]["wall_seconds"] - r[0]["wall_seconds"]
    return r, steps, wall
one, one_steps, one_wall = summary("one")
two, two_steps, two_wall = summary("two")
print(f"| setup | env steps/s (iterations 3..{int(two[-1]['iteration'])}) |")
print("|---|---|")
print(f"| 1 learner, 1 server | {one_steps / one_wall:,.0f} |")
print(f"| 2 ranks, 2 servers | {two_steps / two_wall:,.0f} ({two_steps / two_wall / (one_steps / one_wall):.2f}x) |")
allreduce = sum(x["allreduce_s"] for x in two[1:])
sent = sum(x["allreduce_bytes"] for x in two[1:])
print(f"\nrank 0 in collectives: {allreduce:.2f} s of {two_wall:.2f} s ({100 * allreduce / two_wall:.1f} %), "
      f"{sent / len(two[1:]) / 1e6:.2f} MB sent per iteration, {sent / two_steps:,.0f} bytes per env step (both ranks' steps)")
PY
