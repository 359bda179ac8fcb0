#!/bin/bash
# A steered base motion (session of 2026-12-06, eighth): skills fine-tuned on a reference anchored in
# position only (--anchor_position_only), then steer and strike heads over them with the base motion
# turning toward the goal (--task_steering_rate 60), side by side, and every head evaluated at the
# steering rates 0 and 60 (the prior-alone row of each evaluation is the skills with z from the
# base motion alone).
set -e
cd "$(dirname "$0")/../../../.."
export MODSKILL_BUILD_DIR="${MODSKILL_BUILD_DIR:-build}"
B="$MODSKILL_BUILD_DIR"
# The ten walks with turns of ../strike_anchored_turns_2026-12-06/run.sh (runs/turn_lib); its
# turning skills are data/policies/strike_turns/skills.
F="--init_from data/policies/strike_turns/skills/policy.pt --controller_input proprioception --loop_clips --anchor_reference --anchor_position_only"
bench/learning_bench.sh --out runs/heading_skills --minutes 22 --server_flags "--no_generative --motions runs/turn_lib" posonly="$F"
# Heads over the new skills with the base motion steered at 60 deg/s, side by side, 20 minutes each.
S=runs/heading_skills/posonly/policy.pt
bench/task_bench.sh --out runs/steer_steered --skills $S --minutes 20 --motions deepmimic_walk --eval_episodes 64 \
  --server_flags "--motions runs/turn_lib" \
  steered="--task steer --task_log_std -3 --learning_rate 5e-5 --update_threads 1 --task_steering_rate 60" &
sleep 10
bench/task_bench.sh --out runs/strike_steered --skills $S --minutes 20 --motions walk_arm_forward --eval_episodes 64 \
  --server_flags "--motions runs/turn_lib" \
  steered="--task strike --task_log_std -2.5 --learning_rate 1e-4 --energy_weight 0 --update_threads 1 --task_steering_rate 60"
wait
# A strike head with a smaller step, alone, 25 minutes (after the two heads above).
bench/task_bench.sh --out runs/strike_steered_small --skills $S --minutes 25 --motions walk_arm_forward --eval_episodes 64 \
  --server_flags "--motions runs/turn_lib" \
  small_step="--task strike --task_log_std -3 --learning_rate 3e-5 --energy_weight 0 --task_steering_rate 60"
