#!/usr/bin/env bash
# modskill-motion reach as a user runs it: held reach poses of the walk written to a directory,
# read back by inspect, the same seed giving the same targets, and bad input refused with a
# message naming the flag and nothing written.  Usage: run_motion_reach_cli_test.sh BUILD_DIR
set -euo pipefail
motion="$1/server/modskill-motion"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

"$motion" reach deepmimic_walk --count 4 --seed 3 --box_size 0.4 --box_center 0.3,-0.3,1.2 --name walk_reach \
    --out "$out/a" > "$out/a.txt"
[ "$(ls "$out/a" | wc -l)" -eq 4 ] || fail "expected 4 clips, got: $(ls "$out/a")"
grep -q "^4 clips: hand-to-target median 0.0[0-4]" "$out/a.txt" || fail "near box not reached: $(cat "$out/a.txt")"
"$motion" inspect "$out/a/walk_reach_002.msclip" > "$out/inspect.txt"
grep -q "label .*R_Hand held at" "$out/inspect.txt" || fail "label: $(cat "$out/inspect.txt")"
"$motion" reach deepmimic_walk --count 4 --seed 3 --box_size 0.4 --box_center 0.3,-0.3,1.2 --name walk_reach \
    --out "$out/b" > "$out/b.txt"
diff <(sed 's/->.*//' "$out/a.txt") <(sed 's/->.*//' "$out/b.txt") || fail "the same seed drew other targets"

expect_error() {  # expect_error PATTERN ARGS...: exit status != 0, PATTERN on stderr, no clip written
  local pattern="$1"; shift
  if "$motion" reach "$@" --out "$out/bad" 2> "$out/err.txt"; then fail "accepted: $*"; fi
  grep -q -- "$pattern" "$out/err.txt" || fail "for '$*' expected '$pattern', got: $(cat "$out/err.txt")"
  [ -z "$(ls -A "$out/bad" 2>/dev/null)" ] || fail "'$*' wrote $(ls "$out/bad")"
}
expect_error "--hand 'Tail'" deepmimic_walk --name x --hand Tail
expect_error "--hand 'Pelvis'" deepmimic_walk --name x --hand Pelvis
expect_error "--box_size: 0 outside (0, 4\] m" deepmimic_walk --name x --box_size 0
expect_error "--box_center: expected x,y,z" deepmimic_walk --name x --box_center 1,2
expect_error "--box_center y: nan puts the reach box" deepmimic_walk --name x --box_center 0,nan,1
expect_error "--box_center z: 0.5 puts the reach box (edge 2 m) outside \[0, 3\] m" deepmimic_walk --name x --box_center 0,0,0.5
expect_error "--box_center 'abc': not a number" deepmimic_walk --name x --box_center 0,abc,1
expect_error "--count 0" deepmimic_walk --name x --count 0
expect_error "no clip of that name" no_such_clip --name x
expect_error "reach pose name '../x_000'" deepmimic_walk --name ../x
expect_error "needs BASE --name NAME --out DIR" deepmimic_walk
echo "modskill-motion reach: ok"
