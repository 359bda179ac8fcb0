#!/usr/bin/env bash
# modskill-learner's --reference_frames as a user gives it: a count outside [1, 8] or one beside
# --loop_clips is refused with exit 2 naming the flag; a run observes 1 frame unless told, and 3
# when told (config.json and the exported policy say so); a --resume without the flag keeps its
# checkpoint's count and one with another is refused.
#   Usage: run_learner_reference_frames_cli_test.sh BUILD_DIR
set -euo pipefail
source "$(dirname "$0")/learner_cli_common.sh"

expect_refused --reference_frames "--reference_frames 9" "--reference_frames 0" "--reference_frames 2 --loop_clips"
start_server
frames() { /usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1])).get('reference_frames', 1))" "$1"; }

"$learner" "${small[@]}" --run_dir "$out/plain" > "$out/plain.txt" 2>&1 || fail "plain run: $(tail -5 "$out/plain.txt")"
[ "$(frames "$out/plain/config.json")" = 1 ] || fail "plain run: $(cat "$out/plain/config.json")"
"$learner" "${small[@]}" --run_dir "$out/ahead" --reference_frames 3 > "$out/ahead.txt" 2>&1 ||
  fail "3-frame run: $(tail -5 "$out/ahead.txt")"
[ "$(frames "$out/ahead/config.json")" = 3 ] || fail "3-frame run: $(cat "$out/ahead/config.json")"
/usr/bin/python3 - "$out/ahead/policy.pt" > "$out/spec.json" <<'PY' || fail "policy.pt has no env_spec.json"
import sys, zipfile
archive = zipfile.ZipFile(sys.argv[1])
print(archive.read(next(n for n in archive.namelist() if n.endswith("extra/modskill/env_spec.json"))).decode())
PY
[ "$(frames "$out/spec.json")" = 3 ] || fail "policy.pt: $(cat "$out/spec.json")"
"$learner" "${small[@]}" --run_dir "$out/ahead" --resume > "$out/resume.txt" 2>&1 || fail "resume: $(tail -5 "$out/resume.txt")"
grep -q "resumed .* at iteration 1" "$out/resume.txt" || fail "resume log: $(tail -5 "$out/resume.txt")"
[ "$(frames "$out/ahead/config.json")" = 3 ] || fail "resumed run: $(cat "$out/ahead/config.json")"
"$learner" "${small[@]}" --run_dir "$out/ahead" --resume --reference_frames 1 > "$out/other.txt" 2>&1 &&
  fail "a resume with another count ran"
grep -q -- "resume with --reference_frames 3, not 1" "$out/other.txt" || fail "other count: $(tail -3 "$out/other.txt")"
echo "modskill-learner --reference_frames: ok"
