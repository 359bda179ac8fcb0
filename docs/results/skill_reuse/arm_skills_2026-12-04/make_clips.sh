#!/usr/bin/env bash
# Standing clips whose arms move: the held stance (../stand_skills_2026-12-04/deepmimic_stand.msclip)
# with both arms' motion spliced from eight DeepMimic clips (MIT), each stretched over the stance's
# 3 s. Skills for reach and strike need arms that go somewhere; the shipped library's arm motion
# comes with legs that lunge, flip or crawl.
#   docs/results/skill_reuse/arm_skills_2026-12-04/make_clips.sh OUT_DIR
set -euo pipefail
out="${1:?usage: make_clips.sh OUT_DIR}"
root="$(cd "$(dirname "$0")/../../../.." && pwd)"
build="${MODSKILL_BUILD_DIR:-$root/build}"
mkdir -p "$out"
cp "$root/docs/results/skill_reuse/stand_skills_2026-12-04/deepmimic_stand.msclip" "$out/"
for source in punch dance_a dance_spin cartwheel crawl jump getup_facedown backflip; do
  "$build/server/modskill-motion" splice "$out/deepmimic_stand.msclip" "$root/data/motions/deepmimic_$source.msclip" \
    --parts R_Arm,L_Arm --name "stand_arms_$source" --out "$out"
done
ls "$out"
