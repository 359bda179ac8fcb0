# Sourced by the training benchmarks (learning_bench.sh, task_bench.sh): trains the variants
# NAME="learner flags" side by side, each learner against its own server on a free port, same
# seed, and waits for all of them.
#
#   train_side_by_side "SERVER FLAGS" LEARNER_FLAG...
#
# Reads BUILD, OUT, VARIANTS and, when the caller declares it, SERVER_FLAGS_FOR[NAME] (flags for
# that variant's server only); fills NAMES, FLAGS (each variant's own flags) and PORTS (its
# server's, kept running for evaluation until the script exits). Returns non-zero, naming the
# log, when a variant fails.

free_port() { /usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }

NAMES=() FLAGS=() PORTS=() SERVERS=()
stop_servers() { for pid in "${SERVERS[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done; }
trap stop_servers EXIT

train_side_by_side() {
  local server_flags="$1"; shift
  # Side by side, each learner updates on one thread: two learners with two OpenMP threads each on
  # two cores spin against each other (measured: 8 s updates instead of 1.2 s).
  local shared=""
  ((${#VARIANTS[@]} > 1)) && shared="--update_threads 1"
  local pids=() variant name flags port
  for variant in "${VARIANTS[@]}"; do
    name="${variant%%=*}" flags="${variant#*=}"
    port=$(free_port)
    local own_server_flags=""
    if declare -p SERVER_FLAGS_FOR > /dev/null 2>&1; then own_server_flags="${SERVER_FLAGS_FOR[$name]:-}"; fi
    # shellcheck disable=SC2086  # the flags are words on purpose
    "$BUILD/server/modskill-server" --port "$port" --threads 1 $server_flags $own_server_flags \
        > "$OUT/$name.server.log" 2>&1 &
    SERVERS+=($!)
    NAMES+=("$name") FLAGS+=("$flags") PORTS+=("$port")
    # shellcheck disable=SC2086
    "$BUILD/learner/modskill-learner" --servers "127.0.0.1:$port" --run_dir "$OUT/$name" --preset small \
        --seed 1 --checkpoint_every 20 "$@" $shared $flags > "$OUT/$name.train.log" 2>&1 &
    pids+=($!)
  done
  local status=0 i
  for i in "${!pids[@]}"; do
    wait "${pids[$i]}" || { echo "error: variant ${NAMES[$i]} failed; see $OUT/${NAMES[$i]}.train.log" >&2; status=1; }
  done
  return "$status"
}
