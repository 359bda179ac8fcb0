#!/usr/bin/env bash
# modskill-learner's --gamma and --lambda as a user gives them: a value outside their ranges is
# refused with exit 2 naming the flag; the small preset's tracking run discounts at 0.95 unless
# told (config.json says so), an explicit value wins, and a --resume without the flag keeps the
# run's own.  Usage: run_learner_discount_cli_test.sh BUILD_DIR
set -euo pipefail
source "$(dirname "$0")/learner_cli_common.sh"

expect_refused --gamma "--gamma 0" "--gamma 1.5" "--gamma nan"
expect_refused --lambda "--lambda -0.5" "--lambda 2"
start_server
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
