#!/usr/bin/env bash
# modskill-learner's --reference_frames as a user gives it: a count outside [1, 8] or one beside
# --loop_clips is refused with exit 2 naming the flag; a run observes 1 frame unless told, and 3
# when told (config.json and the exported policy say so); a --resume without the flag keeps its
# checkpoint's count and one with another is refused.
#   Usage: run_learner_reference_frames_cli_test.sh BUILD_DIR
set -euo pipefail
server="$1/server/modskill-server"
learner="$1/learner/modskill-learner"
out="$(mktemp -d)"
pid=""
trap '[ -n "$pid" ] && kill "$pid" 2> /dev/null; rm -rf "$out"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

for bad in "--reference_frames 9" "--reference_frames 0" "--reference_frames 2 --loop_clips"; do
  rc=0
  # shellcheck disable=SC2086
  timeout 30 "$learner" --servers 127.0.0.1:1 --run_dir "$out/bad" --iterations 1 $bad > "$out/log.txt" 2>&1 || rc=$?
  [ "$rc" = 2 ] || fail "$bad: exit $rc, log: $(cat "$out/log.txt")"
  grep -q -- "--reference_frames: " "$out/log.txt" || fail "$bad: message: $(cat "$out/log.txt")"
done

"$server" --port 0 --threads 1 > "$out/server.txt" 2>&1 &
pid=$!
for _ in $(seq 100); do grep -q "listening on" "$out/server.txt" && break; sleep 0.2; done
port=$(sed -n 's/.*listening on [^:]*:\([0-9]*\) .*/\1/p' "$out/server.txt" | head -1)
[ -n "$port" ] || fail "no port in: $(cat "$out/server.txt")"
small=(--servers "127.0.0.1:$port" --iterations 1 --envs_per_server 16 --horizon 8 --minibatch_size 64
       --motions deepmimic_walk --checkpoint_every 1)
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
