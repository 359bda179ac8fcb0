#!/usr/bin/env bash
# modskill-learner's --keep_best_every as a user gives it: a negative value is refused with exit 2
# naming the flag; a run keeps policy_best.pt with policy_best.json and .md beside it and a row per
# evaluation in evaluations.csv, and --eval of the kept file reports the errors policy_best.json
# recorded (the evaluation is deterministic).
# Usage: run_learner_keep_best_cli_test.sh BUILD_DIR
set -euo pipefail
source "$(dirname "$0")/learner_cli_common.sh"

expect_refused --keep_best_every "--keep_best_every -1"
start_server
"$learner" "${small[@]}" --iterations 2 --keep_best_every 1 --run_dir "$out/run" > "$out/run.txt" 2>&1 ||
  fail "run: $(tail -5 "$out/run.txt")"
for file in policy_best.pt policy_best.json policy_best.md evaluations.csv; do
  [ -f "$out/run/$file" ] || fail "no $file: $(ls "$out/run")"
done
[ ! -e "$out/run/policy_candidate.pt" ] || fail "policy_candidate.pt left behind"
[ "$(grep -c "evaluated: Succ" "$out/run.txt")" = 2 ] || fail "two evaluations expected: $(cat "$out/run.txt")"
[ "$(wc -l < "$out/run/evaluations.csv")" = 3 ] || fail "evaluations.csv: $(cat "$out/run/evaluations.csv")"
"$learner" --eval --checkpoint "$out/run/policy_best.pt" --servers "${small[1]}" --clips deepmimic_walk \
  --eval_out "$out/eval" > "$out/eval.txt" 2>&1 || fail "eval: $(tail -5 "$out/eval.txt")"
/usr/bin/python3 - "$out/run/policy_best.json" "$out/eval/eval.json" <<'PY' || fail "kept and evaluated differ"
import json, sys
kept, evaluated = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
assert kept["iteration"] in (1, 2), kept["iteration"]
for key in ("success_rate", "mpjpe_mm", "g_mpjpe_mm"):
    assert kept["evaluation"][key] == evaluated[key], (key, kept["evaluation"][key], evaluated[key])
PY
echo "modskill-learner --keep_best_every: ok"
