#!/usr/bin/env bash
# Skill reuse benchmark (issue 13): trains one high-level task policy per task over the same
# frozen tracker skills, side by side (each against its own server, same seed, same wall-clock
# budget), then evaluates each beside the same skills driven by random z and by a constant z
# (modskill-learner --eval --task T --task_baselines), and writes a table and the curves.
#
#   bench/task_bench.sh --out DIR --skills TRACKER/policy.pt --minutes M [--motions a,b]
#       [--resume] [--eval_episodes N] [--server_flags "--motions DIR"] [--skills_for NAME=PATH]...
#       NAME="learner flags" [NAME=...]
#
# --skills_for gives one variant other frozen skills (trained and evaluated over them), so heads
# over two skill sets run side by side: --skills_for new=runs/new_skills/policy.pt.
#
# Every variant's flags must name its task, e.g.
#   bench/task_bench.sh --out runs/tasks --skills runs/skills/proprio/policy.pt --minutes 30 \
#       --motions deepmimic_walk,deepmimic_jog,deepmimic_run \
#       steer="--task steer" reach="--task reach" strike="--task strike"
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD="${MODSKILL_BUILD_DIR:-build}"
OUT="" SKILLS="" MINUTES=30 MOTIONS="" RESUME="" EPISODES=64 SERVER_FLAGS=""
VARIANTS=()
declare -A SKILLS_FOR=()
while (($#)); do
  case "$1" in
    --out) OUT="$2"; shift 2 ;;
    --skills) SKILLS="$2"; shift 2 ;;
    --minutes) MINUTES="$2"; shift 2 ;;
    --motions) MOTIONS="$2"; shift 2 ;;
    --eval_episodes) EPISODES="$2"; shift 2 ;;
    --server_flags) SERVER_FLAGS="$2"; shift 2 ;;
    --skills_for) SKILLS_FOR["${2%%=*}"]="${2#*=}"; shift 2 ;;
    --resume) RESUME="--resume"; shift ;;
    -h|--help) sed -n 2,17p "$0"; exit 0 ;;
    *=*) VARIANTS+=("$1"); shift ;;
    *) echo "error: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ -n "$OUT" ] || { echo "error: --out DIR is required" >&2; exit 2; }
[ -f "$SKILLS" ] || { echo "error: --skills: no file '$SKILLS' (a tracker's policy.pt, --controller_input proprioception)" >&2; exit 2; }
((${#VARIANTS[@]})) || { echo "error: give at least one NAME=\"--task T ...\" variant" >&2; exit 2; }
for name in "${!SKILLS_FOR[@]}"; do
  [ -f "${SKILLS_FOR[$name]}" ] || { echo "error: --skills_for $name: no file '${SKILLS_FOR[$name]}'" >&2; exit 2; }
  found=""
  for i in "${!VARIANTS[@]}"; do
    # The learner takes the last --skills it is given: the variant's own.
    if [ "${VARIANTS[$i]%%=*}" = "$name" ]; then VARIANTS[$i]="${VARIANTS[$i]} --skills ${SKILLS_FOR[$name]}"; found=1; fi
  done
  [ -n "$found" ] || { echo "error: --skills_for $name: no variant of that name" >&2; exit 2; }
done
mkdir -p "$OUT"
source bench/side_by_side.sh
train_side_by_side "--no_generative $SERVER_FLAGS" --skills "$SKILLS" --iterations 1000000 --time_budget_min "$MINUTES" \
    ${MOTIONS:+--motions "$MOTIONS"} $RESUME || exit 1

# Evaluation: the task policy, random z and constant z over the same frozen skills, one variant
# after the other (the servers are idle now).
for i in "${!NAMES[@]}"; do
  name="${NAMES[$i]}"
  task=$(sed -n 's/.*--task[ =]\([a-z_]*\).*/\1/p' <<< "${FLAGS[$i]}")
  # The goals it trained on (speeds, intervals, reach's box, the steering) are the goals it is evaluated on.
  goal_flags=$(grep -oE -- '--task_(min_speed|max_speed|min_goal_interval_s|max_goal_interval_s|reach_box_size|reach_center|steering_rate)[ =][^ ]+' \
      <<< "${FLAGS[$i]}" | tr '\n' ' ' || true)
  # A reach head trained with a teacher is evaluated beside the teacher itself, on its parts.
  teacher_flags=""
  if grep -qE -- '--task_teacher[ =]' <<< "${FLAGS[$i]}"; then
    teacher_flags=$(grep -oE -- '--task_(teacher|parts)[ =][^ ]+' <<< "${FLAGS[$i]}" | tr '\n' ' ')
  fi
  "$BUILD/learner/modskill-learner" --eval --task "$task" --checkpoint "$OUT/$name/policy.pt" \
      --skills "${SKILLS_FOR[$name]:-$SKILLS}" \
      --servers "127.0.0.1:${PORTS[$i]}" --task_baselines --eval_episodes "$EPISODES" --seed 7 $goal_flags $teacher_flags \
      ${MOTIONS:+--motions "$MOTIONS"} --eval_out "$OUT/$name/eval" > "$OUT/$name/eval.log" 2>&1
  { echo "### $name"; cat "$OUT/$name/eval/eval.md"; echo; } 
done | tee "$OUT/table.md"
CSVS=()
for name in "${NAMES[@]}"; do CSVS+=("$OUT/$name/progress.csv"); done
/usr/bin/python3 client/python/examples/plot_learning_curve.py "${CSVS[@]}" --out "$OUT/curves.png"
echo "wrote $OUT/table.md and $OUT/curves.png"
