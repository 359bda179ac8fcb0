#!/usr/bin/env bash
# ModSkill Table 3 on this machine: the same learner trained for the same wall-clock budget
# against two servers that differ only in active skill learning:
#   full:     adaptive sampling (failure_count) + generative resampling (built-in generator)
#   ablation: --no_adaptive --no_generative (uniform sampling over the fixed library)
# Both runs train at the same time (side by side, so machine noise hits both alike), each with
# one server thread and one learner thread; then both policies are evaluated on the shipped
# library by the same server and the tables are printed side by side.
#
#   bench/active_learning_bench.sh [--minutes 25] [--out runs/active_learning] [--envs 256] [--seed 1]
#                                  [-- extra learner flags]
#
# Writes OUT/{full,ablation}/ (runs, eval.json, eval.md), OUT/*_server.log, OUT/*_stats.txt
# (server stats at the end of training: sampler weights, generated clips) and OUT/table3.md.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD="${MODSKILL_BUILD_DIR:-build}"
PYTHON=/usr/bin/python3
MINUTES=25
OUT=runs/active_learning
ENVS=256
SEED=1
while [ $# -gt 0 ]; do
  case "$1" in
    --minutes) MINUTES="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    --envs) ENVS="$2"; shift 2 ;;
    --seed) SEED="$2"; shift 2 ;;
    --) shift; break ;;
    *) echo "active_learning_bench: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
for binary in server/modskill-server learner/modskill-learner client/modskill-client; do
  [ -x "$BUILD/$binary" ] || { echo "active_learning_bench: build $BUILD/$binary first" >&2; exit 1; }
done
mkdir -p "$OUT"
free_port() { "$PYTHON" -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }

PIDS=()
cleanup() { for pid in "${PIDS[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done; wait 2>/dev/null || true; }
trap cleanup EXIT

declare -A PORT
PORT[full]=$(free_port)
"$BUILD/server/modskill-server" --port "${PORT[full]}" --threads 1 >"$OUT/full_server.log" 2>&1 &
PIDS+=($!)
PORT[ablation]=$(free_port)
"$BUILD/server/modskill-server" --port "${PORT[ablation]}" --threads 1 --no_adaptive --no_generative \
  >"$OUT/ablation_server.log" 2>&1 &
PIDS+=($!)
for run in full ablation; do
  "$BUILD/client/modskill-client" --server "127.0.0.1:${PORT[$run]}" --timeout_s 20 describe >/dev/null
done

echo "training both for $MINUTES min (logs: $OUT/{full,ablation}/learner.log)"
LEARNERS=()
for run in full ablation; do
  mkdir -p "$OUT/$run"
  "$BUILD/learner/modskill-learner" --servers "127.0.0.1:${PORT[$run]}" --run_dir "$OUT/$run" --preset small \
    --iterations 1000000 --time_budget_min "$MINUTES" --envs_per_server "$ENVS" --seed "$SEED" "$@" \
    >"$OUT/$run/learner.log" 2>&1 &
  LEARNERS+=($!)
done
# Server stats (sampler weights, generated clips) every 30 s while the sessions live: the last
# snapshot before the learners finish is kept in OUT/<run>_stats.txt.
(
  while true; do
    sleep 30
    for run in full ablation; do
      if "$BUILD/client/modskill-client" --server "127.0.0.1:${PORT[$run]}" stats >"$OUT/${run}_stats.tmp" 2>&1 &&
         grep -q "^live sessions" "$OUT/${run}_stats.tmp"; then
        mv "$OUT/${run}_stats.tmp" "$OUT/${run}_stats.txt"
      fi
    done
  done
) &
SNAPSHOTS=$!
PIDS+=($SNAPSHOTS)
status=0
for pid in "${LEARNERS[@]}"; do wait "$pid" || status=$?; done
kill "$SNAPSHOTS" 2>/dev/null || true
[ "$status" = 0 ] || { echo "active_learning_bench: a learner failed; see $OUT/*/learner.log" >&2; exit 1; }

# Both policies are evaluated by the same server, one after the other.
for run in full ablation; do
  "$BUILD/learner/modskill-learner" --eval --checkpoint "$OUT/$run/policy.pt" --servers "127.0.0.1:${PORT[full]}" \
    --eval_out "$OUT/$run" >"$OUT/$run/eval.log" 2>&1
done

"$PYTHON" - "$OUT" "$MINUTES" <<'EOF'
import csv, json, os, statistics, sys
out, minutes = sys.argv[1], sys.argv[2]
rows = []
for run, label in (("full", "adaptive + generative"), ("ablation", "no adaptive, no generative")):
    ev = json.load(open(os.path.join(out, run, "eval.json")))
    progress = list(csv.DictReader(open(os.path.join(out, run, "progress.csv"))))
    tail = progress[-10:]
    rows.append((label, ev, progress[-1], statistics.median(float(r["episode_length"]) for r in tail),
                 statistics.median(float(r["episode_return"]) for r in tail),
                 statistics.mean(c["steps"] for c in ev["clips"])))
distances = sorted(rows[0][1]["success_at_distance"], reverse=True)
md = [f"Same learner (`small`), same seed, {minutes} min each, trained side by side on one 2-core machine; "
      "evaluated on the shipped library (evaluation termination 0.5 m).", "",
      "| Method | env steps | Succ ↑ | E_g-mpjpe ↓ | E_mpjpe ↓ | E_acc ↓ | E_vel ↓ | steps tracked (eval) | episode length (train) | episode return (train) |",
      "|---|---|---|---|---|---|---|---|---|---|"]
for label, ev, last, length, ret, tracked in rows:
    md.append(f"| {label} | {int(last['env_steps']):,} | {100 * ev['success_rate']:.1f} % | {ev['g_mpjpe_mm']:.1f} | "
              f"{ev['mpjpe_mm']:.1f} | {ev['acc_error_mm_per_frame2']:.1f} | {ev['vel_error_mm_per_frame']:.1f} | "
              f"{tracked:.1f} | {length:.2f} | {ret:.2f} |")
md += ["", "Success at looser termination distances (max over the clip of the mean body error <= d):", "",
       "| Method | " + " | ".join(f"{d} m" for d in distances) + " |", "|---|" + "---|" * len(distances)]
for label, ev, *_ in rows:
    md.append(f"| {label} | " + " | ".join(f"{100 * ev['success_at_distance'][d]:.0f} %" for d in distances) + " |")
md += ["", "steps tracked: mean control steps per clip before the evaluation termination (or the clip's end). "
       "Training columns: medians of the last 10 iterations of progress.csv, over the clips each run sampled."]
text = "\n".join(md) + "\n"
open(os.path.join(out, "table3.md"), "w").write(text)
print(text)
EOF
