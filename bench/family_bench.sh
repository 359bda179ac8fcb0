#!/usr/bin/env bash
# The motor-skill family bar (issue 14): trains a family from one clip for a time budget against a
# server of its own, then rolls the policy out at a few parameter values, and plots the elites'
# coverage of the range over training time (DIR/coverage.png from DIR/run/progress.csv).
#
#   bench/family_bench.sh --out DIR [--minutes 20] [--clip deepmimic_jump]
#       [--param gravity=4:14 ...] [--eval 5,9.81,14] [--resume] [--server_flags "FLAGS"]
#       [-- LEARNER_FLAGS...]
#
# DIR/run/family_eval.csv: per evaluated value, the root's apex (m), the time with both feet off
# the floor (s) and the fitness. --resume continues DIR/run (a run in parts, its checkpoint kept).
# Then the exported DIR/run/policy.pt goes through the server as a user would run it:
# DIR/rollout_<value>.json (modskill-client rollout --param NAME=VALUE, the first varied
# parameter), DIR/rollout.html (the viewer page at the first value) and DIR/family_query.json
# (modskill-client family: the ranges, P(a) at the middle and the nearest elites), and
# DIR/rollouts.md: per value, the root's apex, mean height, travel and speed, the flight time and F.
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${MODSKILL_BUILD_DIR:-$repo/build}"
OUT="" minutes=20 clip=deepmimic_jump eval_values="5,9.81,14" resume="" server_flags=""
params=()
while (($#)); do
  case "$1" in
    --out) OUT="$2"; shift 2 ;;
    --minutes) minutes="$2"; shift 2 ;;
    --clip) clip="$2"; shift 2 ;;
    --param) params+=(--param "$2"); shift 2 ;;
    --eval) eval_values="$2"; shift 2 ;;
    --resume) resume="--resume"; shift ;;
    --server_flags) server_flags="$2"; shift 2 ;;
    --) shift; break ;;
    *) echo "bench/family_bench.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
[[ -n "$OUT" ]] || { echo "bench/family_bench.sh: --out DIR is required" >&2; exit 2; }
((${#params[@]})) || params=(--param gravity=4:14)
mkdir -p "$OUT"
source "$repo/bench/side_by_side.sh"  # free_port, stop_servers at exit

port=$(free_port)
# shellcheck disable=SC2086  # the server flags are words
"$BUILD/server/modskill-server" --port "$port" --threads 1 $server_flags > "$OUT/server.log" 2>&1 &
SERVERS+=($!)
"$BUILD/learner/modskill-learner" --servers "127.0.0.1:$port" --run_dir "$OUT/run" --family "$clip" "${params[@]}" \
    --time_budget_min "$minutes" --iterations 1000000 --seed 1 --family_eval "$eval_values" $resume "$@" \
    > "$OUT/train.log" 2>&1 || { echo "error: the learner failed; see $OUT/train.log" >&2; exit 1; }

/usr/bin/python3 - "$OUT" <<'EOF'
import csv, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
out = sys.argv[1]
rows = list(csv.DictReader(open(f"{out}/run/progress.csv")))
minutes = [float(r["wall_s"]) / 60 for r in rows]
fig, axes = plt.subplots(1, 2, figsize=(10, 3.5))
axes[0].plot(minutes, [float(r["coverage"]) for r in rows])
axes[0].set_xlabel("training time (min)"); axes[0].set_ylabel("share of the range covered by elites")
axes[1].plot(minutes, [float(r["mean_fitness"]) for r in rows], label="mean episode F")
axes[1].plot(minutes, [float(r["mean_length"]) / 100 for r in rows], label="mean episode length / 100")
axes[1].set_xlabel("training time (min)"); axes[1].legend()
fig.tight_layout(); fig.savefig(f"{out}/coverage.png", dpi=100)
last = rows[-1]
print(f"after {minutes[-1]:.1f} min, {last['env_steps']} env steps: coverage {float(last['coverage']):.3f}, "
      f"{last['elites']} elites, mean F {float(last['mean_fitness']):.3f}")
EOF
cat "$OUT/run/family_eval.csv"

# The exported policy on the server, at the same values.
first_param="${params[1]%%=*}"
client="$BUILD/client/modskill-client"
html=(--html "$OUT/rollout.html")
for value in ${eval_values//,/ }; do
  "$client" --server "127.0.0.1:$port" rollout --checkpoint "$OUT/run/policy.pt" --param "$first_param=$value" \
      --frames --out "$OUT/rollout_$value.json" "${html[@]}" | grep -E "^family at|wrote"
  html=()
done
"$client" --server "127.0.0.1:$port" family --checkpoint "$OUT/run/policy.pt" --out "$OUT/family_query.json"

# What the motion did at each value, from the server's frames: the root's apex and mean height,
# the distance it travelled and its speed, the flight time and F (DIR/rollouts.md).
/usr/bin/python3 - "$OUT" "$first_param" ${eval_values//,/ } <<'PY'
import json, math, sys
out, name, values = sys.argv[1], sys.argv[2], sys.argv[3:]
lines = [f"| {name} | root apex (m) | mean root height (m) | root travel (m) | speed (m/s) | flight (s) | F | clip frames played |",
         "|---|---|---|---|---|---|---|---|"]
for value in values:
    clip = json.load(open(f"{out}/rollout_{value}.json"))["clips"][0]
    root = [frame["sim_body_pos"][0] for frame in clip["frames"]]
    travel = math.dist(root[0][:2], root[-1][:2])
    seconds = max(len(root) - 1, 1) / 30.0
    family = clip["family"]
    lines.append(f"| {value} | {family['apex_height_m']:.3f} | {sum(p[2] for p in root) / len(root):.3f} | {travel:.3f} | "
                 f"{travel / seconds:.2f} | {family['flight_s']:.2f} | {family['fitness']:.3f} | {family['final_phase']:.1f} |")
open(f"{out}/rollouts.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
