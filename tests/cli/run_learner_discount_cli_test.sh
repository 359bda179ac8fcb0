#!/usr/bin/env bash
# modskill-learner's --gamma and --lambda as a user gives them: a value outside their ranges is
# refused with exit 2 naming the flag; the small preset's tracking run discounts at 0.95 unless
# told (config.json says so), an explicit value wins, and a --resume without the flag keeps the
# run's own.  Usage: run_learner_discount_cli_test.sh BUILD_DIR
set -euo pipefail
server="$1/server/modskill-server"
learner="$1/learner/modskill-learner"
out="$(mktemp -d)"
pid=""
trap '[ -n "$pid" ] && kill "$pid" 2> /dev/null; rm -rf "$out"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

for bad in "--gamma 0" "--gamma 1.5" "--gamma nan" "--lambda -0.5" "--lambda 2"; do
  rc=0
  # shellcheck disable=SC2086
  timeout 30 "$learner" --servers 127.0.0.1:1 --run_dir "$out/bad" --iterations 1 $bad > "$out/log.txt" 2>&1 || rc=$?
  [ "$rc" = 2 ] || fail "$bad: exit $rc, log: $(cat "$out/log.txt")"
  grep -q -- "${bad%% *}: " "$out/log.txt" || fail "$bad: message: $(cat "$out/log.txt")"
done

"$server" --port 0 --threads 1 > "$out/server.txt" 2>&1 &
pid=$!
for _ in $(seq 100); do grep -q "listening on" "$out/server.txt" && break; sleep 0.2; done
port=$(sed -n 's/.*listening on [^:]*:\([0-9]*\) .*/\1/p' "$out/server.txt" | head -1)
[ -n "$port" ] || fail "no port in: $(cat "$out/server.txt")"
small=(--servers "127.0.0.1:$port" --iterations 1 --envs_per_server 16 --horizon 8 --minibatch_size 64
       --motions deepmimic_walk --checkpoint_every 1)
field() { /usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }

"$learner" "${small[@]}" --run_dir "$out/plain" > "$out/plain.txt" 2>&1 || fail "plain run: $(tail -5 "$out/plain.txt")"
[ "$(field "$out/plain/config.json" gamma)" = 0.95 ] || fail "plain run: $(cat "$out/plain/config.json")"
[ "$(field "$out/plain/config.json" lambda)" = 0.95 ] || fail "plain run: $(cat "$out/plain/config.json")"
"$learner" "${small[@]}" --run_dir "$out/told" --gamma 0.9 --lambda 0.8 > "$out/told.txt" 2>&1 ||
  fail "--gamma 0.9 run: $(tail -5 "$out/told.txt")"
[ "$(field "$out/told/config.json" gamma)" = 0.9 ] || fail "--gamma 0.9 run: $(cat "$out/told/config.json")"
"$learner" "${small[@]}" --run_dir "$out/told" --resume > "$out/resumed.txt" 2>&1 ||
  fail "resume: $(tail -5 "$out/resumed.txt")"
grep -q "trained at --gamma 0.9; resuming with it" "$out/resumed.txt" || fail "resume log: $(cat "$out/resumed.txt")"
[ "$(field "$out/told/config.json" gamma)" = 0.9 ] || fail "resumed run: $(cat "$out/told/config.json")"
[ "$(field "$out/told/config.json" lambda)" = 0.8 ] || fail "resumed run: $(cat "$out/told/config.json")"
echo "modskill-learner --gamma/--lambda: ok"
