# Shared by the learner's CLI tests (sourced after `set -euo pipefail`, with $1 the build dir):
# the binaries, a scratch dir removed on exit, and the steps every such test repeats.
server="$1/server/modskill-server"
learner="$1/learner/modskill-learner"
out="$(mktemp -d)"
pid=""
trap '[ -n "$pid" ] && kill "$pid" 2> /dev/null; rm -rf "$out"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# expect_refused FLAG "ARGS" ...: each ARGS is refused with exit 2 and a message naming FLAG,
# before any server is contacted.
expect_refused() {
  local flag="$1" bad rc
  shift
  for bad in "$@"; do
    rc=0
    # shellcheck disable=SC2086
    timeout 30 "$learner" --servers 127.0.0.1:1 --run_dir "$out/bad" --iterations 1 $bad > "$out/log.txt" 2>&1 || rc=$?
    [ "$rc" = 2 ] || fail "$bad: exit $rc, log: $(cat "$out/log.txt")"
    grep -q -- "$flag: " "$out/log.txt" || fail "$bad: message: $(cat "$out/log.txt")"
  done
}

# Starts a one-thread server on a free port; sets pid and `small`, the flags of a tiny tracking run
# against it.
start_server() {
  "$server" --port 0 --threads 1 > "$out/server.txt" 2>&1 &
  pid=$!
  for _ in $(seq 100); do grep -q "listening on" "$out/server.txt" && break; sleep 0.2; done
  local port
  port=$(sed -n 's/.*listening on [^:]*:\([0-9]*\) .*/\1/p' "$out/server.txt" | head -1)
  [ -n "$port" ] || fail "no port in: $(cat "$out/server.txt")"
  small=(--servers "127.0.0.1:$port" --iterations 1 --envs_per_server 16 --horizon 8 --minibatch_size 64
         --motions deepmimic_walk --checkpoint_every 1)
}
