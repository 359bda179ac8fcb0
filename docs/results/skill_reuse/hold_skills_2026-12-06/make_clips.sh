#!/usr/bin/env bash
# The arm-skill clips (../arm_skills_2026-12-04/make_clips.sh: the held stance with both arms'
# motion from eight DeepMimic clips, MIT) and, from the same eight, 32 clips that reach one of
# their arm poses from the stance's and hold it (`modskill-motion splice --timing hold`, the pose
# at 20, 40, 60 and 80 % of the source): a reach needs skills that hold a hand somewhere, and
# arms that never stop do not teach that.
#   docs/results/skill_reuse/hold_skills_2026-12-06/make_clips.sh OUT_DIR
set -euo pipefail
out="${1:?usage: make_clips.sh OUT_DIR}"
root="$(cd "$(dirname "$0")/../../../.." && pwd)"
build="${MODSKILL_BUILD_DIR:-$root/build}"
"$root/docs/results/skill_reuse/arm_skills_2026-12-04/make_clips.sh" "$out"
for source in punch dance_a dance_spin cartwheel crawl jump getup_facedown backflip; do
  for at in 20 40 60 80; do
    "$build/server/modskill-motion" splice "$out/deepmimic_stand.msclip" "$root/data/motions/deepmimic_$source.msclip" \
      --parts R_Arm,L_Arm --timing hold --hold_at "0.$at" --name "stand_hold_${source}_$at" --out "$out"
  done
done
ls "$out" | wc -l
