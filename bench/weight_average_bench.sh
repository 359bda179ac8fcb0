#!/usr/bin/env bash
# Weight-averaging benchmark: how much one run's evaluation moves from export to export, and what
# averaging the last K exports' weights (modskill-policy-average) gives. Reads the milestone
# exports (policy_at_<N>M.pt, --milestones) of a run directory, evaluates each one and the
# averages of the last K of them with the paper's protocol, and writes a table.
#
#   bench/weight_average_bench.sh --run DIR [--motions a,b] [--from STEPS] [--to STEPS]
#       [--windows 5,10,20] [--server_flags "--no_generative"]
#
# --from / --to pick the exports between two step counts (a run with several blocks of
# milestones is measured block by block); the windows end at the last export picked.
# e.g. learner --milestones at every iteration from 171 to 200 (171x8192, ...), then
#      bench/weight_average_bench.sh --run runs/walk/s1 --motions deepmimic_walk --from 1.4e6
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD="${MODSKILL_BUILD_DIR:-build}"
RUN="" MOTIONS="" FROM=0 TO=1e18 WINDOWS="5,10,20" SERVER_FLAGS=""
while (($#)); do
  case "$1" in
    --run) RUN="$2"; shift 2 ;;
    --motions) MOTIONS="$2"; shift 2 ;;
    --from) FROM="$2"; shift 2 ;;
    --to) TO="$2"; shift 2 ;;
    --windows) WINDOWS="$2"; shift 2 ;;
    --server_flags) SERVER_FLAGS="$2"; shift 2 ;;
    -h|--help) sed -n 2,13p "$0"; exit 0 ;;
    *) echo "error: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ -d "$RUN" ] || { echo "error: --run DIR is required (a run directory with milestone exports)" >&2; exit 2; }
# The exports in the range, in step order: "steps path" lines.
mapfile -t EXPORTS < <(/usr/bin/python3 - "$RUN" "$FROM" "$TO" <<'PY'
import glob, os, re, sys
run, lo, hi = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
found = []
for path in glob.glob(os.path.join(run, "policy_at_*M.pt")):
    steps = float(re.search(r"policy_at_(.*)M\.pt$", path).group(1)) * 1e6
    if lo <= steps <= hi:
        found.append((steps, path))
for steps, path in sorted(found):
    print(f"{steps:.0f} {path}")
PY
)
((${#EXPORTS[@]} >= 2)) || { echo "error: fewer than two policy_at_*M.pt exports in $RUN between $FROM and $TO" >&2; exit 2; }
OUT="$RUN/weight_average"
mkdir -p "$OUT"
source bench/side_by_side.sh  # free_port
port=$(free_port)
# shellcheck disable=SC2086  # the flags are words on purpose
"$BUILD/server/modskill-server" --port "$port" --threads 1 $SERVER_FLAGS > "$OUT/server.log" 2>&1 &
SERVERS+=($!)  # stopped on exit (side_by_side.sh)
CLIPS=()
[ -n "$MOTIONS" ] && CLIPS=(--clips "$MOTIONS")
evaluate() {  # evaluate NAME POLICY
  "$BUILD/learner/modskill-learner" --eval --checkpoint "$2" --servers "127.0.0.1:$port" "${CLIPS[@]}" \
      --eval_out "$OUT/$1" > "$OUT/$1.log" 2>&1 || { echo "error: evaluating $2 failed; see $OUT/$1.log" >&2; exit 1; }
}
for line in "${EXPORTS[@]}"; do
  evaluate "single_${line%% *}" "${line#* }"
done
IFS=, read -r -a KS <<< "$WINDOWS"
for k in "${KS[@]}"; do
  ((k >= 2 && k <= ${#EXPORTS[@]})) || continue
  files=()
  for line in "${EXPORTS[@]: -k}"; do files+=("${line#* }"); done
  "$BUILD/learner/modskill-policy-average" --out "$OUT/average_last$k.pt" "${files[@]}" > /dev/null
  evaluate "average_last$k" "$OUT/average_last$k.pt"
done
/usr/bin/python3 - "$OUT" <<'PY' | tee "$OUT/table.md"
import glob, json, os, statistics, sys
out = sys.argv[1]
rows = []
for path in glob.glob(os.path.join(out, "*", "eval.json")):
    name = os.path.basename(os.path.dirname(path))
    with open(path) as f:
        ev = json.load(f)
    steps = sum(c["steps"] for c in ev["clips"])
    rows.append((name, ev["success_rate"], steps, ev["mpjpe_mm"], ev["g_mpjpe_mm"]))
single = sorted((r for r in rows if r[0].startswith("single_")), key=lambda r: int(r[0][7:]))
average = sorted((r for r in rows if r[0].startswith("average_")), key=lambda r: int(r[0][12:]))
print("| policy | Succ | steps tracked | E_mpjpe (mm) | E_g-mpjpe (mm) |\n|---|---|---|---|---|")
for name, succ, steps, mpjpe, g in single + average:
    print(f"| {name} | {100 * succ:.0f} % | {steps} | {mpjpe:.1f} | {g:.1f} |")
if single:
    col = lambda i: [r[i] for r in single]
    print(f"\nSingle exports ({len(single)}): Succ median {100 * statistics.median(col(1)):.0f} %, "
          f"E_mpjpe median {statistics.median(col(3)):.1f} mm (range {min(col(3)):.1f}-{max(col(3)):.1f}), "
          f"E_g-mpjpe median {statistics.median(col(4)):.1f} mm (range {min(col(4)):.1f}-{max(col(4)):.1f})")
PY
