#!/bin/bash
# Fine-tune the looping walk tracker 60 iterations with and without --anchor_reference (equal steps,
# side by side), then measure each one's skill prior alone in steer (task_bench, 2-iteration head).
set -e
cd "$(dirname "$0")/../../../.."
export MODSKILL_BUILD_DIR="${MODSKILL_BUILD_DIR:-build}"
F="--controller_input proprioception --loop_clips --init_from data/policies/walk_proprio_loop/policy.pt"
bench/learning_bench.sh --out runs/anchor_ft --iterations 60 --motions deepmimic_walk --server_flags "--no_generative" \
  global="$F" anchored="$F --anchor_reference" > runs/anchor_ft.log 2>&1
for v in global anchored; do
  bench/task_bench.sh --out runs/anchor_steer_$v --skills runs/anchor_ft/$v/policy.pt --minutes 5 --motions deepmimic_walk \
    --eval_episodes 64 steer="--task steer --task_log_std -3 --learning_rate 5e-5 --iterations 2" > runs/anchor_steer_$v.log 2>&1
done
echo finished
