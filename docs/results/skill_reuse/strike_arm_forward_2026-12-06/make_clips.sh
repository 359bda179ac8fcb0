#!/usr/bin/env bash
# The strike base motion: DeepMimic's walk (MIT) with the right arm held straight ahead at shoulder
# height, a pose made by inverse kinematics on the held stance (`modskill-motion reach`, one target
# at (0.5, -0.2, 1.25) m from the root) and spliced onto the walk (`splice --timing hold`).
#   docs/results/skill_reuse/strike_arm_forward_2026-12-06/make_clips.sh OUT_DIR
set -euo pipefail
out="${1:?usage: make_clips.sh OUT_DIR}"
root="$(cd "$(dirname "$0")/../../../.." && pwd)"
build="${MODSKILL_BUILD_DIR:-$root/build}"
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
mkdir -p "$out"
cp "$root/data/motions/deepmimic_walk.msclip" "$out/"
"$build/server/modskill-motion" reach "$root/docs/results/skill_reuse/stand_skills_2026-12-04/deepmimic_stand.msclip" \
  --name arm_forward --count 1 --seed 1 --box_size 0.01 --box_center 0.5,-0.2,1.25 --out "$scratch" | tail -1
"$build/server/modskill-motion" splice "$root/data/motions/deepmimic_walk.msclip" "$scratch/arm_forward_000.msclip" \
  --parts R_Arm --name walk_arm_forward --timing hold --out "$out" | tail -1
