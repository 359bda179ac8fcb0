#!/usr/bin/env bash
# Scaling across "hosts" (issue 15): 1, 2 and 4 simulation servers, each on its own network
# namespace joined to the learners' by a veth link, against 1 and 2 data-parallel learner ranks
# (the ranks split the servers; with fewer servers than ranks they share them). For each setup:
# env steps/s over all ranks, the share of rank 0's time in collectives (gradient all-reduces and
# statistics merges, waiting for the other rank included) and the bytes rank 0 sends into them
# per env step. Same seed, small preset, one thread per server, one update thread per rank.
# Needs root and iproute2 (tests/netns/netns_hosts.sh).
#
#   bench/multi_host_bench.sh [--build build] [--out runs/multi_host_bench] [--iterations 8]
#                             [--envs 64] [--servers "1 2 4"] [--ranks "1 2"]
#
# --envs is per server. The first iteration (warm-up) is left out. On this 2-core machine every
# process shares the same two cores, so the table shows contention, not what more machines give:
# bench/scaling_model.py turns measured per-step costs into figures for larger clusters.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=build OUT=runs/multi_host_bench ITERATIONS=8 ENVS=64 SERVER_COUNTS="1 2 4" RANK_COUNTS="1 2"
while (($#)); do
  case "$1" in
    --build) BUILD="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    --iterations) ITERATIONS="$2"; shift 2 ;;
    --envs) ENVS="$2"; shift 2 ;;
    --servers) SERVER_COUNTS="$2"; shift 2 ;;
    --ranks) RANK_COUNTS="$2"; shift 2 ;;
    *) echo "usage: $0 [--build DIR] [--out DIR] [--iterations N] [--envs N] [--servers \"1 2 4\"] [--ranks \"1 2\"]" >&2
       exit 2 ;;
  esac
done
for binary in server/modskill-server learner/modskill-learner; do
  [[ -x "$BUILD/$binary" ]] || { echo "error: no $BUILD/$binary (build it first)" >&2; exit 1; }
done
BUILD="$(cd "$BUILD" && pwd)"
source tests/netns/netns_hosts.sh
if ! why=$(netns_check); then echo "error: $why" >&2; exit 1; fi
rm -rf "$OUT" && mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"
trap netns_cleanup EXIT

max_servers=0
for n in $SERVER_COUNTS; do ((n > max_servers)) && max_servers=$n; done
netns_setup "$max_servers"
PORT=50051
COMMON=(--preset small --iterations "$ITERATIONS" --envs_per_server "$ENVS" --seed 1 --checkpoint_every 1000
        --threads 1 --update_threads 1 --server_timeout_s 60 --motions deepmimic_walk)

RENDEZVOUS_PORT=29510
run_setup() {  # servers ranks
  RENDEZVOUS_PORT=$((RENDEZVOUS_PORT + 1))  # a fresh port per setup: the last one may linger
  local servers="$1" ranks="$2" name="s$1_r$2" i rank list pids=()
  for ((i = 1; i <= servers; i++)); do
    netns_run "${NETNS_SERVER[$i]}" "$BUILD/server/modskill-server" --bind "${SERVER_ADDRESS[$i]}" --port "$PORT" \
        --threads 1 > "$OUT/$name.server$i.log" 2>&1 &
    netns_wait_listening "${NETNS_SERVER[$i]}" "${SERVER_ADDRESS[$i]}:$PORT" 30 || { echo "error: server $i did not start" >&2; exit 1; }
  done
  for ((rank = 0; rank < ranks; rank++)); do
    list=""
    for ((i = 1; i <= servers; i++)); do  # rank r drives servers r+1, r+1+ranks, ...; or shares server 1
      if (((i - 1) % ranks == rank)) || ((servers < ranks)); then list+="${list:+,}${SERVER_ADDRESS[$i]}:$PORT"; fi
    done
    local parallel=()
    ((ranks > 1)) && parallel=(--world_size "$ranks" --rank "$rank" --rendezvous "127.0.0.1:$RENDEZVOUS_PORT")
    netns_run "$NETNS_LEARNER" "$BUILD/learner/modskill-learner" --servers "$list" --run_dir "$OUT/$name" \
        "${COMMON[@]}" "${parallel[@]}" > "$OUT/$name.rank$rank.log" 2>&1 &
    pids+=($!)
  done
  for ((rank = 0; rank < ranks; rank++)); do
    wait "${pids[$rank]}" || { echo "error: $name rank $rank failed; see $OUT/$name.rank$rank.log" >&2; exit 1; }
  done
  for ((i = 1; i <= servers; i++)); do
    pkill -TERM -f -- "--bind ${SERVER_ADDRESS[$i]} " || true
  done
  sleep 1
}

SETUPS=()
for servers in $SERVER_COUNTS; do
  for ranks in $RANK_COUNTS; do
    run_setup "$servers" "$ranks"
    SETUPS+=("s${servers}_r${ranks}")
  done
done

/usr/bin/python3 - "$OUT" "${SETUPS[@]}" << 'PY' | tee "$OUT/table.md"
import csv, sys
out, setups = sys.argv[1], sys.argv[2:]
print("| servers | learner ranks | env steps/s | vs 1 server, 1 rank | rank 0 in collectives | bytes per env step |")
print("|---|---|---|---|---|---|")
base = None
for name in setups:
    servers, ranks = (int(x[1:]) for x in name.split("_"))
    rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(open(f"{out}/{name}/progress.csv"))][1:]
    steps = rows[-1]["env_steps"] - rows[0]["env_steps"]
    wall = rows[-1]["wall_seconds"] - rows[0]["wall_seconds"]
    rate = steps / wall
    base = base or rate
    if ranks > 1:
        share = sum(r["allreduce_s"] for r in rows[1:]) / wall
        sent = sum(r["allreduce_bytes"] for r in rows[1:]) / steps
        collectives = f"{100 * share:.1f} %"
        per_step = f"{sent:,.0f}"
    else:
        collectives, per_step = "-", "-"
    print(f"| {servers} | {ranks} | {rate:,.0f} | {rate / base:.2f} x | {collectives} | {per_step} |")
PY
