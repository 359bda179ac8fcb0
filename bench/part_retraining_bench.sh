#!/usr/bin/env bash
# A new part without retraining the rest (issue 13 item 4): from a tracker, retrain only some
# parts on new clips while the others stay frozen (their controllers and attention maps, or their
# controllers alone with --train_attention=false), beside the same tracker continued with every
# part training, side by side (bench/learning_bench.sh: same seed, same clips, same wall-clock
# budget); then each policy and the tracker it started from are rolled out on the new clips and
# on the tracker's own, and their per-part errors are tabulated (DIR/parts.md, DIR/parts.json).
#
#   bench/part_retraining_bench.sh --out DIR [--minutes 15] [--tracker data/policies/walk_small/policy.pt]
#       [--parts R_Arm,L_Arm] [--new deepmimic_punch] [--old deepmimic_walk] [--motions DIR]
#       [--learner_flags "FLAGS"] [--eval_only] [--resume] [NAME="FLAGS" ...]
#
# NAME="FLAGS" arguments replace the three default variants (parts, parts_controllers, every_part)
# with your own; each starts from --tracker with --learner_flags, e.g.
#   arms_reward="--train_parts R_Arm,L_Arm --reward_parts R_Arm,L_Arm --frozen_parts_act_on_mean"
#
# Per part, averaged over the steps each rollout tracked: the error of its bodies relative to the
# root (without the drift of the whole body), and its "own motion" error, its bodies in the frame
# of the body it hangs from (an arm: the Chest; that frame's orientation in simulation and
# reference found from the positions of that body and its children), which the rest of the
# body's pose does not enter either. --motions serves a library of your own (e.g. the shipped
# clips plus one made by `modskill-motion splice`) to every server; --learner_flags go to every variant (e.g. "--termination_distance 0.5").
# --eval_only evaluates the policies of an earlier run in DIR; --resume continues its variants for
# --minutes more (bench/learning_bench.sh --resume) before evaluating.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD="${MODSKILL_BUILD_DIR:-build}"
OUT="" MINUTES=15 TRACKER=data/policies/walk_small/policy.pt PARTS=R_Arm,L_Arm NEW=deepmimic_punch OLD=deepmimic_walk
EVAL_ONLY="" RESUME="" MOTIONS_FLAG="" LEARNER_FLAGS="" VARIANT_ARGS=()
while (($#)); do
  case "$1" in
    --out) OUT="$2"; shift 2 ;;
    --minutes) MINUTES="$2"; shift 2 ;;
    --tracker) TRACKER="$2"; shift 2 ;;
    --parts) PARTS="$2"; shift 2 ;;
    --new) NEW="$2"; shift 2 ;;
    --old) OLD="$2"; shift 2 ;;
    --motions) MOTIONS_FLAG="--motions $2"; shift 2 ;;
    --learner_flags) LEARNER_FLAGS="$2"; shift 2 ;;
    --eval_only) EVAL_ONLY=1; shift ;;
    --resume) RESUME="--resume"; shift ;;
    -h|--help) sed -n 2,24p "$0"; exit 0 ;;
    [A-Za-z]*=*) VARIANT_ARGS+=("$1"); shift ;;
    *) echo "error: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ -n "$OUT" ] || { echo "error: --out DIR is required" >&2; exit 2; }
mkdir -p "$OUT"
if ((${#VARIANT_ARGS[@]} == 0)); then
  VARIANT_ARGS=(parts="--train_parts $PARTS" parts_controllers="--train_parts $PARTS --train_attention=false" every_part="")
fi
RUNS=() VARIANT_NAMES=()
for variant in "${VARIANT_ARGS[@]}"; do
  VARIANT_NAMES+=("${variant%%=*}")
  RUNS+=("${variant%%=*}=--init_from $TRACKER ${variant#*=} $LEARNER_FLAGS")
done
[ -n "$EVAL_ONLY" ] || bench/learning_bench.sh --out "$OUT" --minutes "$MINUTES" --motions "$NEW" \
    --server_flags "--no_generative $MOTIONS_FLAG" $RESUME "${RUNS[@]}"

source bench/side_by_side.sh  # free_port, stop_servers at exit
port=$(free_port)
# shellcheck disable=SC2086  # the flag and its directory are two words
"$BUILD/server/modskill-server" --port "$port" --threads 1 $MOTIONS_FLAG > "$OUT/eval_server.log" 2>&1 &
SERVERS+=($!)
sleep 2
for name in tracker "${VARIANT_NAMES[@]}"; do
  policy="$OUT/$name/policy.pt"
  [ "$name" != tracker ] || policy="$TRACKER"
  [ -f "$policy" ] || continue
  "$BUILD/client/modskill-client" --server "127.0.0.1:$port" --timeout_s 30 rollout --checkpoint "$policy" \
      --clip "$NEW,$OLD" --frames --out "$OUT/rollout_$name.json" > /dev/null
done
PYTHONPATH=client/python /usr/bin/python3 - "$OUT" "$NEW" "$OLD" "$PARTS" "127.0.0.1:$port" tracker "${VARIANT_NAMES[@]}" <<'PY'
import json, os, sys
import numpy as np
import modskill
out, new, old, parts, server = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4].split(",")[:], sys.argv[5]
with modskill.Client(server) as client:
    spec = client.describe()
parent = [g.parent for g in spec.body_geometry]


def own_motion_error(sim, ref, body_index, part_bodies):
    """[T, len(part_bodies)] m: each body against the reference in the frame of the body the part
    hangs from (its attachment: the Chest for an arm, the Pelvis for a leg), whose orientation in sim
    and reference is found by aligning it and its children's positions (rigid in its frame; Kabsch).
    What is left is the part's own motion: the rest of the body's pose and drift do not enter."""
    members = [body_index[b] for b in part_bodies]
    attachment = next(parent[m] for m in members if parent[m] not in members)
    if attachment < 0:
        attachment = members[0]
    rigid = [attachment] + [b for b, p in enumerate(parent) if p == attachment]
    errors = []
    for s, r in zip(sim, ref):
        a = s[rigid] - s[attachment]
        b = r[rigid] - r[attachment]
        u, _, vt = np.linalg.svd(a.T @ b)
        d = np.sign(np.linalg.det(vt.T @ u.T))
        rotation = vt.T @ np.diag([1, 1, d]) @ u.T  # rotation @ a[i] ~ b[i]
        local_sim = (s[members] - s[attachment]) @ rotation.T
        errors.append(np.linalg.norm(local_sim - (r[members] - r[attachment]), axis=-1))
    return np.array(errors)


rows = {}
for name in sys.argv[6:]:
    if not os.path.exists(f"{out}/rollout_{name}.json"):
        continue
    data = json.load(open(f"{out}/rollout_{name}.json"))
    index = {body: i for i, body in enumerate(data["body_names"])}
    rows[name] = {}
    for c in data["clips"]:
        sim = np.array([f["sim_body_pos"] for f in c["frames"]])
        ref = np.array([f["ref_body_pos"] for f in c["frames"]])
        local = np.linalg.norm((sim - sim[:, :1]) - (ref - ref[:, :1]), axis=-1)  # [T, bodies], m
        part_error = {p.name: 1000 * float(local[:, [index[b] for b in p.bodies]].mean()) for p in spec.parts}
        retrained = [index[b] for p in spec.parts if p.name in parts for b in p.bodies]
        frozen = [index[b] for p in spec.parts if p.name not in parts for b in p.bodies]
        own = {p.name: own_motion_error(sim, ref, index, p.bodies) for p in spec.parts}
        own_mean = lambda chosen: 1000 * float(np.concatenate([own[p.name] for p in spec.parts if chosen(p)], 1).mean())
        rows[name][c["clip"]] = {"steps": c["steps"], "success": c["success"], "mpjpe_mm": c["mpjpe_mm"],
                                 "part_error_mm": part_error,
                                 "retrained_error_mm": 1000 * float(local[:, retrained].mean()),
                                 "frozen_error_mm": 1000 * float(local[:, frozen].mean()),
                                 "part_own_motion_error_mm": {k: 1000 * float(v.mean()) for k, v in own.items()},
                                 "retrained_own_motion_error_mm": own_mean(lambda p: p.name in parts),
                                 "frozen_own_motion_error_mm": own_mean(lambda p: p.name not in parts)}
        c.pop("frames")
part_names = [p.name for p in spec.parts]
with open(f"{out}/parts.md", "w") as f:
    head = ("| policy | clip | steps | E_mpjpe (mm) | " + " | ".join(f"{p} (mm)" for p in part_names) +
            " | retrained parts (mm) | frozen parts (mm) | retrained, own motion (mm) | frozen, own motion (mm) |")
    f.write(head + "\n|" + "---|" * (8 + len(part_names)) + "\n")
    for name, by_clip in rows.items():
        for clip in (new, old):
            r = by_clip[clip]
            cells = " | ".join(f"{r['part_error_mm'][p]:.1f}" + (" *" if p in parts else "") for p in part_names)
            f.write(f"| {name} | {clip} | {r['steps']}{' (all)' if r['success'] else ''} | {r['mpjpe_mm']:.1f} | {cells} | "
                    f"{r['retrained_error_mm']:.1f} | {r['frozen_error_mm']:.1f} | "
                    f"{r['retrained_own_motion_error_mm']:.1f} | {r['frozen_own_motion_error_mm']:.1f} |\n")
    f.write(f"\n(* the retrained parts, {', '.join(parts)}; a part's error: its bodies' positions relative to the "
            "root against the reference's, averaged over its bodies and the steps tracked; the last two columns "
            "average over all the retrained parts' bodies and over all the others'; own motion: each part's bodies in "
            "the frame of the body it hangs from, aligned between simulation and reference, so that neither the "
            "root's drift nor the rest of the body's pose enters)\n")
json.dump(rows, open(f"{out}/parts.json", "w"), indent=1)
print(open(f"{out}/parts.md").read())
PY
