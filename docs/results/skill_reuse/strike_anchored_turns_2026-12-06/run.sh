#!/bin/bash
# Strike over skills that stay up (session of 2026-12-06, sixth). From the arm-forward walk skills
# of ../strike_arm_forward_2026-12-06/ (runs/armf_skills, made by that folder's commands):
# (1) 120 iterations each, side by side: fine-tuned on the global reference, on the anchored
#     reference, anchored with a loose termination; (2) each one's skill prior alone in strike;
# (3) the anchored skills 25 more minutes on the two straight clips or on ten clips with turns
#     (modskill-motion turn); (4) their priors in strike; (5) a strike head over each, 40 minutes.
set -e
cd "$(dirname "$0")/../../../.."
export MODSKILL_BUILD_DIR="${MODSKILL_BUILD_DIR:-build}"
M="$MODSKILL_BUILD_DIR/server/modskill-motion"
mkdir -p runs/turn_lib && cp runs/strike_lib/*.msclip runs/turn_lib/
for r in 30 60; do
  for side in left right; do
    rate=$r; [ "$side" = right ] && rate=-$r
    "$M" turn runs/strike_lib/walk_arm_forward.msclip --yaw_rate "$rate" --name "walk_arm_forward_${side}_$r" --out runs/turn_lib
    "$M" turn deepmimic_walk --yaw_rate "$rate" --name "walk_${side}_$r" --out runs/turn_lib
  done
done
F="--init_from runs/armf_skills/armf/policy.pt --controller_input proprioception --loop_clips"
bench/learning_bench.sh --out runs/anchor_armf --iterations 120 --motions deepmimic_walk,walk_arm_forward \
  --server_flags "--no_generative --motions runs/strike_lib" \
  global="$F" anchored="$F --anchor_reference" loose="$F --anchor_reference --termination_distance 0.5 --termination_bodies no_feet"
S="--task strike --task_log_std -3 --learning_rate 5e-5 --energy_weight 0 --update_threads 1 --iterations 2"
bench/task_bench.sh --out runs/strike_priors --skills runs/armf_skills/armf/policy.pt --minutes 10 --motions walk_arm_forward \
  --eval_episodes 64 --server_flags "--motions runs/strike_lib" --skills_for global=runs/anchor_armf/global/policy.pt \
  --skills_for anchored=runs/anchor_armf/anchored/policy.pt --skills_for loose=runs/anchor_armf/loose/policy.pt \
  orig="$S" global="$S" anchored="$S" loose="$S"
F="--init_from runs/anchor_armf/anchored/policy.pt --controller_input proprioception --loop_clips --anchor_reference"
bench/learning_bench.sh --out runs/turn_skills --minutes 25 --server_flags "--no_generative --motions runs/turn_lib" \
  --server_flags_for straight="--no_generative --motions runs/strike_lib" straight="$F" turns="$F"
bench/task_bench.sh --out runs/strike_priors2 --skills runs/turn_skills/straight/policy.pt --minutes 10 --motions walk_arm_forward \
  --eval_episodes 64 --server_flags "--motions runs/strike_lib" --skills_for turns=runs/turn_skills/turns/policy.pt \
  straight="$S" turns="$S"
S="--task strike --task_log_std -2.5 --learning_rate 1e-4 --energy_weight 0 --update_threads 1"
bench/task_bench.sh --out runs/strike_turns --skills runs/turn_skills/straight/policy.pt --minutes 40 --motions walk_arm_forward \
  --eval_episodes 64 --server_flags "--motions runs/strike_lib" --skills_for turns=runs/turn_skills/turns/policy.pt \
  straight="$S" turns="$S"
# (6) the head's step size over the turning skills, 20 minutes each, side by side (the session's
#     full build ran beside them).
S="--task strike --energy_weight 0 --update_threads 1"
bench/task_bench.sh --out runs/strike_step --skills runs/turn_skills/turns/policy.pt --minutes 20 --motions walk_arm_forward \
  --eval_episodes 64 --server_flags "--motions runs/strike_lib" \
  lr1e-4="$S --task_log_std -2.5 --learning_rate 1e-4" lr3e-4="$S --task_log_std -2 --learning_rate 3e-4"
# (7) steer over the turning skills against the looping walk skills, 20 minutes each, side by side.
S="--task steer --task_log_std -3 --learning_rate 5e-5 --update_threads 1"
bench/task_bench.sh --out runs/steer_turns --skills data/policies/walk_proprio_loop/policy.pt --minutes 20 \
  --motions deepmimic_walk --eval_episodes 64 --server_flags "--motions runs/strike_lib" \
  --skills_for turns=runs/turn_skills/turns/policy.pt loop="$S" turns="$S"
