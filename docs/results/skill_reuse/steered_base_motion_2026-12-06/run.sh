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
