#!/usr/bin/env bash
# A new part without retraining the rest (issue 13 item 4): from a tracker, retrain only some
# parts on new clips while the others stay frozen, beside the same tracker continued with every
# part training, side by side (bench/learning_bench.sh: same seed, same clips, same wall-clock
# budget); then each policy and the tracker it started from are rolled out on the new clips and
# on the tracker's own, and their per-part errors are tabulated (DIR/parts.md, DIR/parts.json).
#
#   bench/part_retraining_bench.sh --out DIR [--minutes 15] [--tracker data/policies/walk_small/policy.pt]
#       [--parts R_Arm,L_Arm] [--new deepmimic_punch] [--old deepmimic_walk]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD="${MODSKILL_BUILD_DIR:-build}"
OUT="" MINUTES=15 TRACKER=data/policies/walk_small/policy.pt PARTS=R_Arm,L_Arm NEW=deepmimic_punch OLD=deepmimic_walk
while (($#)); do
  case "$1" in
    --out) OUT="$2"; shift 2 ;;
    --minutes) MINUTES="$2"; shift 2 ;;
    --tracker) TRACKER="$2"; shift 2 ;;
    --parts) PARTS="$2"; shift 2 ;;
    --new) NEW="$2"; shift 2 ;;
    --old) OLD="$2"; shift 2 ;;
    -h|--help) sed -n 2,9p "$0"; exit 0 ;;
    *) echo "error: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ -n "$OUT" ] || { echo "error: --out DIR is required" >&2; exit 2; }
mkdir -p "$OUT"
bench/learning_bench.sh --out "$OUT" --minutes "$MINUTES" --motions "$NEW" --server_flags "--no_generative" \
    parts="--init_from $TRACKER --train_parts $PARTS" every_part="--init_from $TRACKER"

source bench/side_by_side.sh  # free_port, stop_servers at exit
port=$(free_port)
"$BUILD/server/modskill-server" --port "$port" --threads 1 > "$OUT/eval_server.log" 2>&1 &
SERVERS+=($!)
sleep 2
for policy in tracker:"$TRACKER" parts:"$OUT/parts/policy.pt" every_part:"$OUT/every_part/policy.pt"; do
  name="${policy%%:*}"
  "$BUILD/client/modskill-client" --server "127.0.0.1:$port" --timeout_s 30 rollout --checkpoint "${policy#*:}" \
      --clip "$NEW,$OLD" --out "$OUT/rollout_$name.json" > /dev/null
done
/usr/bin/python3 - "$OUT" "$NEW" "$OLD" "$PARTS" <<'PY'
import json, sys
out, new, old, parts = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4].split(",")
rows, table = {}, []
for name in ("tracker", "parts", "every_part"):
    clips = {c["clip"]: c for c in json.load(open(f"{out}/rollout_{name}.json"))["clips"]}
    rows[name] = {clip: {"steps": c["steps"], "success": c["success"], "mpjpe_mm": c["mpjpe_mm"],
                         "part_error_mm": c["part_error_mm"]} for clip, c in clips.items()}
part_names = list(rows["tracker"][new]["part_error_mm"])
with open(f"{out}/parts.md", "w") as f:
    head = "| policy | clip | steps | E_mpjpe (mm) | " + " | ".join(f"{p} (mm)" for p in part_names) + " |"
    f.write(head + "\n|" + "---|" * (4 + len(part_names)) + "\n")
    for name, by_clip in rows.items():
        for clip in (new, old):
            r = by_clip[clip]
            cells = " | ".join(f"{r['part_error_mm'][p]:.1f}" + (" *" if p in parts else "") for p in part_names)
            f.write(f"| {name} | {clip} | {r['steps']}{' (all)' if r['success'] else ''} | {r['mpjpe_mm']:.1f} | {cells} |\n")
    f.write(f"\n(* the retrained parts, {', '.join(parts)}; part errors are global body errors averaged over the "
            "part's bodies, over the steps tracked)\n")
json.dump(rows, open(f"{out}/parts.json", "w"), indent=1)
print(open(f"{out}/parts.md").read())
PY
