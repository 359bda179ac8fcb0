#!/usr/bin/env bash
# The held stance (../stand_skills_2026-12-04/deepmimic_stand.msclip, from DeepMimic's clips, MIT)
# and 64 clips in which the right hand reaches a target drawn in the reach task's 2 m box and holds
# it, the arm's pose by inverse kinematics (`modskill-motion reach`, seed 1): 23 targets are within
# the arm's reach (hand within 5 cm), the other 41 leave the arm stretched toward them.
#   docs/results/skill_reuse/ik_skills_2026-12-06/make_clips.sh OUT_DIR
set -euo pipefail
out="${1:?usage: make_clips.sh OUT_DIR}"
root="$(cd "$(dirname "$0")/../../../.." && pwd)"
build="${MODSKILL_BUILD_DIR:-$root/build}"
mkdir -p "$out"
cp "$root/docs/results/skill_reuse/stand_skills_2026-12-04/deepmimic_stand.msclip" "$out/"
"$build/server/modskill-motion" reach "$out/deepmimic_stand.msclip" --name stand_reach --count 64 --seed 1 \
  --box_size 2 --box_center 0,0,1 --out "$out" | tail -1
