#!/usr/bin/env bash
# modskill-motion splice and turn as a user runs them: the walk with the punch's arms, and the walk
# turning left, written to a directory, read back by inspect, and bad input refused with a message
# naming what is wrong and nothing written.  Usage: run_motion_splice_cli_test.sh BUILD_DIR
set -euo pipefail
motion="$1/server/modskill-motion"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

"$motion" splice deepmimic_walk deepmimic_punch --parts R_Arm,L_Arm --name walk_with_punch_arms --out "$out" \
    > "$out/splice.txt"
grep -q "walk_with_punch_arms .* 38 frames" "$out/splice.txt" || fail "splice output: $(cat "$out/splice.txt")"
"$motion" inspect "$out/walk_with_punch_arms.msclip" > "$out/inspect.txt"
grep -q "label .*with the R_Arm, L_Arm of deepmimic_punch" "$out/inspect.txt" || fail "label: $(cat "$out/inspect.txt")"
grep -q "source .*deepmimic_walk .*deepmimic_punch" "$out/inspect.txt" || fail "source: $(cat "$out/inspect.txt")"

expect_error() {  # expect_error PATTERN ARGS...: exit status != 0, PATTERN on stderr, no clip written
  local pattern="$1"; shift
  if "$motion" splice "$@" --out "$out/bad" 2> "$out/err.txt"; then fail "accepted: $*"; fi
  grep -q -- "$pattern" "$out/err.txt" || fail "for '$*' expected '$pattern', got: $(cat "$out/err.txt")"
  [ -z "$(ls -A "$out/bad" 2>/dev/null)" ] || fail "'$*' wrote $(ls "$out/bad")"
}
expect_error "'Head' is not a part of layout '5part'" deepmimic_walk deepmimic_punch --parts Head --name x
expect_error "--parts.1.: 'R_Arm' is given twice" deepmimic_walk deepmimic_punch --parts R_Arm,R_Arm --name x
expect_error "no clip of that name" deepmimic_walk no_such_clip --parts R_Arm --name x
expect_error "splice name '../x'" deepmimic_walk deepmimic_punch --parts R_Arm --name ../x
expect_error "timing 'loop'" deepmimic_walk deepmimic_punch --parts R_Arm --name x --timing loop
expect_error "--layout" deepmimic_walk deepmimic_punch --parts R_Arm --name x --layout 9part
expect_error "needs BASE SOURCE" deepmimic_walk --parts R_Arm --name x

"$motion" turn deepmimic_walk --yaw_rate 45 --name walk_left_45 --out "$out" > "$out/turn.txt"
grep -q "walk_left_45 .* 38 frames" "$out/turn.txt" || fail "turn output: $(cat "$out/turn.txt")"
"$motion" inspect "$out/walk_left_45.msclip" > "$out/inspect_turn.txt"
grep -q "label .*turning +45 deg/s" "$out/inspect_turn.txt" || fail "turn label: $(cat "$out/inspect_turn.txt")"
expect_turn_error() {  # expect_turn_error PATTERN ARGS...
  local pattern="$1"; shift
  if "$motion" turn "$@" --out "$out/bad" 2> "$out/err.txt"; then fail "accepted: turn $*"; fi
  grep -q -- "$pattern" "$out/err.txt" || fail "for 'turn $*' expected '$pattern', got: $(cat "$out/err.txt")"
  [ -z "$(ls -A "$out/bad" 2>/dev/null)" ] || fail "'turn $*' wrote $(ls "$out/bad")"
}
expect_turn_error "--yaw_rate 200" deepmimic_walk --yaw_rate 200 --name x
expect_turn_error "--yaw_rate nan" deepmimic_walk --yaw_rate nan --name x
expect_turn_error "turn name '../x'" deepmimic_walk --yaw_rate 30 --name ../x
expect_turn_error "no clip of that name" no_such_clip --yaw_rate 30 --name x
expect_turn_error "needs BASE --yaw_rate" deepmimic_walk deepmimic_jog --yaw_rate 30 --name x
echo "modskill-motion splice and turn: ok"
