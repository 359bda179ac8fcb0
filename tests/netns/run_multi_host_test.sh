#!/usr/bin/env bash
# Multi-host training on this machine (issue 15): two simulation servers on two "hosts" (network
# namespaces), the learner on a third, every byte crossing veth links.
#   1. a short run, then the same run with 20 ms more latency on each link (tc netem, or a
#      userspace relay where the kernel has no sch_netem): env steps/s of both are printed, and
#      the delayed run's collection must take at least horizon x 20 ms (the delay was real);
#   2. a long run in which server 2's link is cut (both ends down: no reset, packets dropped) and
#      healed, then server 2 is killed: each time the learner must go on with server 1 alone, take
#      server 2 back when it returns, keep its checkpoint, and resume from it.
# Exit 77 (ctest: skipped) with the reason where namespaces cannot be made (not root, no iproute2,
# a container without CAP_NET_ADMIN).
#
#   tests/netns/run_multi_host_test.sh BUILD_DIR
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
BUILD="$(cd "${1:?usage: $0 BUILD_DIR}" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
# shellcheck source=tests/netns/netns_hosts.sh
source "$HERE/netns_hosts.sh"
if ! why=$(netns_check); then
  echo "SKIPPED: multi-host test: $why"
  exit 77
fi
OUT="$(mktemp -d /tmp/modskill_multi_host.XXXXXX)"
trap 'netns_cleanup; rm -rf "$OUT"' EXIT
fail() {
  echo "FAILED: $*" >&2
  for log in "$OUT"/*.log; do echo "--- $log (last lines)" >&2; tail -n 15 "$log" >&2; done
  exit 1
}

netns_setup 2
PORT=50051
start_server() {  # host index
  netns_run "${NETNS_SERVER[$1]}" "$BUILD/server/modskill-server" --bind "${SERVER_ADDRESS[$1]}" --port "$PORT" \
      --threads 1 --motions "$ROOT/data/motions" >> "$OUT/server$1.log" 2>&1 &
  netns_wait_listening "${NETNS_SERVER[$1]}" "${SERVER_ADDRESS[$1]}:$PORT" 30 || fail "server $1 did not start"
}
start_server 1
start_server 2
SERVERS="${SERVER_ADDRESS[1]}:$PORT,${SERVER_ADDRESS[2]}:$PORT"
LEARNER=("$BUILD/learner/modskill-learner" --preset small --motions deepmimic_walk --envs_per_server 32
         --horizon 16 --seed 1 --threads 1 --update_threads 1 --server_timeout_s 60)

# Env steps/s over iterations 2..N of a run's progress.csv (the first one warms up), and the
# shortest collection of those iterations.
progress_figures() {
  /usr/bin/python3 - "$1/progress.csv" << 'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))[1:]
steps = float(rows[-1]["env_steps"]) - float(rows[0]["env_steps"])
wall = float(rows[-1]["wall_seconds"]) - float(rows[0]["wall_seconds"])
print(f"{steps / wall:.0f} {min(float(r['collect_seconds']) for r in rows):.3f}")
PY
}

# 1. Latency.
netns_run "$NETNS_LEARNER" "${LEARNER[@]}" --servers "$SERVERS" --run_dir "$OUT/plain" --iterations 5 \
    > "$OUT/plain.log" 2>&1 || fail "the run without delay failed"
read -r plain_rate plain_collect <<< "$(progress_figures "$OUT/plain")"
DELAY_MS=20
delayed_servers="$SERVERS"
if ! why=$(netns_delay 1 "$DELAY_MS") || ! netns_delay 2 "$DELAY_MS" > /dev/null; then
  echo "note: $why; delaying with a userspace relay in the learner's namespace instead"
  delayed_servers=""
  for i in 1 2; do
    relay_port=$((PORT + 100 + i))
    netns_run "$NETNS_LEARNER" /usr/bin/python3 "$HERE/delay_proxy.py" --listen "127.0.0.1:$relay_port" \
        --to "${SERVER_ADDRESS[$i]}:$PORT" --delay_ms "$DELAY_MS" > "$OUT/relay$i.log" 2>&1 &
    netns_wait_listening "$NETNS_LEARNER" "127.0.0.1:$relay_port" 10 || fail "relay $i did not start"
    delayed_servers+="${delayed_servers:+,}127.0.0.1:$relay_port"
  done
fi
netns_run "$NETNS_LEARNER" "${LEARNER[@]}" --servers "$delayed_servers" --run_dir "$OUT/delayed" --iterations 5 \
    > "$OUT/delayed.log" 2>&1 || fail "the run with ${DELAY_MS} ms latency failed"
netns_undelay 1
netns_undelay 2
read -r delayed_rate delayed_collect <<< "$(progress_figures "$OUT/delayed")"
echo "2 servers on 2 hosts, 64 envs: ${plain_rate} env steps/s (collection ${plain_collect} s);" \
     "with ${DELAY_MS} ms latency ${delayed_rate} env steps/s (collection ${delayed_collect} s)"
/usr/bin/python3 -c "import sys; sys.exit(0 if $delayed_collect >= 16 * $DELAY_MS / 1000 else 1)" ||
  fail "the delayed collection took ${delayed_collect} s, under 16 steps x ${DELAY_MS} ms: the delay did not apply"

# 2. A cut link, a killed server.
RUN="$OUT/faults"
# Not through netns_run: $! must be the learner itself, which SIGTERM stops below.
ip netns exec "$NETNS_LEARNER" "${LEARNER[@]}" --servers "$SERVERS" --run_dir "$RUN" --iterations 100000 \
    --checkpoint_every 2 > "$OUT/faults.log" 2>&1 &
learner_pid=$!
iterations() { if [[ -f $RUN/progress.csv ]]; then echo $(($(wc -l < "$RUN/progress.csv") - 1)); else echo 0; fi; }
count() { grep -c -- "$1" "$OUT/faults.log" || true; }
wait_for() {  # seconds, what, test command...
  local deadline=$((SECONDS + $1)) what="$2"
  shift 2
  until "$@"; do
    kill -0 "$learner_pid" 2> /dev/null || fail "the learner exited while waiting for: $what"
    ((SECONDS < deadline)) || fail "not within the time allowed: $what"
    sleep 0.2
  done
}
more_iterations_than() { (($(iterations) > $1)); }
more_lines_than() { (($(count "$1") > $2)); }
# How many iterations after row $2 of progress.csv gathered from exactly $1 live sessions (each
# server opens two).
iterations_with_sessions() {
  /usr/bin/python3 - "$RUN/progress.csv" "$1" "$2" << 'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))[int(sys.argv[3]):]
print(sum(1 for r in rows if int(float(r["live_sessions"])) == int(sys.argv[2])))
PY
}
at_least_iterations_with_sessions() { (($(iterations_with_sessions "$1" "$2") >= $3)); }
SERVER2="${SERVER_ADDRESS[2]}:$PORT"

wait_for 60 "3 iterations on both servers" more_iterations_than 2
lost_before=$(count "server $SERVER2: session .* lost")
netns_link 2 down
cut_at=$(iterations) cut_s=$SECONDS
wait_for 60 "the learner declares server 2 lost after its link is cut" more_lines_than "server $SERVER2: session .* lost" "$lost_before"
echo "link cut: the learner declared server 2 lost within $((SECONDS - cut_s + 1)) s:" \
     "$(grep -- "server $SERVER2: session .* lost" "$OUT/faults.log" | tail -n 1 | cut -d' ' -f3-)"
wait_for 30 "2 iterations on server 1 alone while the link is down" at_least_iterations_with_sessions 2 "$cut_at" 2
back_before=$(count "server $SERVER2: session .* back after")
netns_link 2 up
wait_for 60 "server 2 back after the link heals" more_lines_than "server $SERVER2: session .* back after" "$back_before"
healed_at=$(iterations)
wait_for 30 "an iteration on both servers again" at_least_iterations_with_sessions 4 "$healed_at" 1
echo "link cut at iteration $cut_at, healed by iteration $healed_at"

lost_before=$(count "server $SERVER2: session .* lost")
pkill -KILL -f -- "--bind ${SERVER_ADDRESS[2]} " || fail "could not kill server 2"
killed_at=$(iterations)
wait_for 30 "the learner declares server 2 lost after it is killed" more_lines_than "server $SERVER2: session .* lost" "$lost_before"
wait_for 30 "2 iterations on server 1 alone after the kill" at_least_iterations_with_sessions 2 "$killed_at" 2
echo "server 2 killed at iteration $killed_at; the run went on to iteration $(iterations)"

kill -TERM "$learner_pid"
wait "$learner_pid" || fail "the learner did not stop cleanly on SIGTERM"
final=$(iterations)
[[ -s $RUN/checkpoint.pt ]] || fail "no checkpoint.pt after the run"
netns_run "$NETNS_LEARNER" "${LEARNER[@]}" --servers "$SERVERS" --run_dir "$RUN" --iterations 1 --resume \
    > "$OUT/resume.log" 2>&1 || fail "--resume after the faults failed"
grep -q "resumed .* at iteration $final " "$OUT/resume.log" ||
  fail "the resumed run did not start at iteration $final: $(grep resumed "$OUT/resume.log")"
echo "PASSED: stopped at iteration $final, resumed from its checkpoint at iteration $final"
