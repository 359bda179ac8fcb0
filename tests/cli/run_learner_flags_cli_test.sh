#!/usr/bin/env bash
# modskill-learner's bad flags as a user meets them: each is refused at once (no server is ever
# reached: the one named does not exist) with a message naming the flag, and nothing is written
# to the run directory.  Usage: run_learner_flags_cli_test.sh BUILD_DIR
set -euo pipefail
learner="$1/learner/modskill-learner"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

expect_error() {  # expect_error PATTERN ARGS...: exit status != 0 within 20 s, PATTERN in the output
  local pattern="$1" status=0; shift
  timeout 20 "$learner" --servers 127.0.0.1:1 --server_timeout_s 1 --run_dir "$out/run" --iterations 1 "$@" \
      > "$out/log.txt" 2>&1 || status=$?
  [ "$status" != 0 ] || fail "accepted: $*"
  [ "$status" != 124 ] || fail "hung: $*"
  grep -q -- "$pattern" "$out/log.txt" || fail "for '$*' expected '$pattern', got: $(cat "$out/log.txt")"
  [ ! -e "$out/run/checkpoint.pt" ] || fail "'$*' wrote a checkpoint"
}
expect_error "--learning_rate_decay_steps" --learning_rate_decay_steps -1
expect_error "--learning_rate_decay_steps" --learning_rate_decay_steps nan
expect_error "--learning_rate_decay_steps" --learning_rate_decay_steps 1e20
expect_error "--learning_rate_floor" --learning_rate_floor 0
expect_error "--learning_rate_floor" --learning_rate_floor 1.5
expect_error "--learning_rate" --learning_rate 3
expect_error "--action_mode" --action_mode sideways
expect_error "--termination_distance" --termination_distance 0
expect_error "--amp_reward_weight" --amp_reward_weight 2
echo "learner flags: every bad value refused, naming its flag"
