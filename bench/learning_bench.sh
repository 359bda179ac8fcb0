#!/usr/bin/env bash
# Learning benchmark: trains variants of the small preset side by side (each against its own
# server, same seed, same clips, same wall-clock budget, so each gets an equal share of this
# machine), evaluates every policy with the paper's protocol (mean body error > 0.5 m ends a
# clip) beside the open-loop reference baseline, and writes a table and the learning curves.
#
#   bench/learning_bench.sh --out DIR (--minutes M | --iterations N) [--motions a,b] [--resume]
#       [--milestones 1e6,5e6] [--server_flags "--no_generative"] [--server_flags_for NAME="flags"]...
#       NAME="learner flags" [NAME=...]
#
# --minutes gives every variant the same wall-clock budget; --iterations the same env steps
# (iterations x 8192).
#
# e.g. bench/learning_bench.sh --out docs/results/learning/walk --minutes 10 --motions deepmimic_walk \
#          residual="" paper="--action_mode absolute"
# --server_flags_for adds flags to one variant's server only, e.g. the same learner on two clip
# sets: --server_flags_for old="--motions /tmp/old/data/motions" old="" new="".
# With --resume every variant continues its run in DIR/NAME (a benchmark longer than one sitting
# runs in parts); env steps and the curve continue where they stopped.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD="${MODSKILL_BUILD_DIR:-build}"
OUT="" MINUTES=10 ITERATIONS=1000000 MOTIONS="" RESUME="" MILESTONES="" SERVER_FLAGS=""
VARIANTS=()
declare -A SERVER_FLAGS_FOR=()
while (($#)); do
  case "$1" in
    --out) OUT="$2"; shift 2 ;;
    --minutes) MINUTES="$2"; shift 2 ;;
    --iterations) ITERATIONS="$2"; MINUTES=0; shift 2 ;;
    --server_flags) SERVER_FLAGS="$2"; shift 2 ;;
    --server_flags_for) SERVER_FLAGS_FOR["${2%%=*}"]="${2#*=}"; shift 2 ;;
    --motions) MOTIONS="$2"; shift 2 ;;
    --milestones) MILESTONES="$2"; shift 2 ;;
    --resume) RESUME="--resume"; shift ;;
    -h|--help) sed -n 2,17p "$0"; exit 0 ;;
    *=*) VARIANTS+=("$1"); shift ;;
    *) echo "error: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ -n "$OUT" ] || { echo "error: --out DIR is required" >&2; exit 2; }
((${#VARIANTS[@]})) || { echo "error: give at least one NAME=\"learner flags\" variant" >&2; exit 2; }
mkdir -p "$OUT"
source bench/side_by_side.sh
# shellcheck disable=SC2086  # the optional flags are words on purpose
train_side_by_side "$SERVER_FLAGS" --iterations "$ITERATIONS" --time_budget_min "$MINUTES" \
    ${MOTIONS:+--motions "$MOTIONS"} ${MILESTONES:+--milestones "$MILESTONES"} $RESUME || exit 1

# Evaluation, one variant after the other (the servers are idle now), and the baseline once.
CLIPS=()
[ -n "$MOTIONS" ] && CLIPS=(--clips "$MOTIONS")
for i in "${!NAMES[@]}"; do
  name="${NAMES[$i]}"
  for policy in "$OUT/$name"/policy*.pt; do
    tag=$(basename "$policy" .pt); tag="${tag#policy}"
    "$BUILD/learner/modskill-learner" --eval --checkpoint "$policy" --servers "127.0.0.1:${PORTS[$i]}" \
        "${CLIPS[@]}" --eval_out "$OUT/$name/eval$tag" > "$OUT/$name/eval$tag.log" 2>&1
  done
done
"$BUILD/learner/modskill-learner" --eval --baseline --servers "127.0.0.1:${PORTS[0]}" "${CLIPS[@]}" \
    --eval_out "$OUT/baseline" > "$OUT/baseline.log" 2>&1
# A variant whose server has its own flags (other clips, say) gets its own baseline too.
for i in "${!NAMES[@]}"; do
  name="${NAMES[$i]}"
  [ -n "${SERVER_FLAGS_FOR[$name]:-}" ] || continue
  "$BUILD/learner/modskill-learner" --eval --baseline --servers "127.0.0.1:${PORTS[$i]}" "${CLIPS[@]}" \
      --eval_out "$OUT/$name/baseline" > "$OUT/$name/baseline.log" 2>&1
done
/usr/bin/python3 bench/learning_table.py "$OUT" "${NAMES[@]}" | tee "$OUT/table.md"
CSVS=()
for name in "${NAMES[@]}"; do CSVS+=("$OUT/$name/progress.csv"); done
/usr/bin/python3 client/python/examples/plot_learning_curve.py "${CSVS[@]}" --out "$OUT/curves.png"
echo "wrote $OUT/table.md and $OUT/curves.png"
