#!/usr/bin/env bash
# The main job: set up and build, start a simulation server on the shipped motion library,
# train the small ModSkill preset against it for a few minutes (MODSKILL_TRAIN_MIN, default 5),
# then evaluate the trained policy on every clip and print the table. The run (checkpoints,
# exported policy.pt, progress.csv, TensorBoard events, eval.json/eval.md and the viewer page
# eval.html: the policy's character beside its reference on every clip) lands in runs/demo.
# Extra arguments go to modskill-learner (e.g. --motions deepmimic_walk).
set -euo pipefail
cd "$(dirname "$0")/.."
deploy/setup.sh
BUILD="${MODSKILL_BUILD_DIR:-build}"
RUN_DIR="${MODSKILL_RUN_DIR:-runs/demo}"
PORT="${MODSKILL_PORT:-$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')}"
"$BUILD/server/modskill-server" --port "$PORT" --threads 1 &
SERVER_PID=$!
trap 'kill -TERM $SERVER_PID 2>/dev/null; wait $SERVER_PID 2>/dev/null || true' EXIT
"$BUILD/client/modskill-client" --server "127.0.0.1:$PORT" --timeout_s 20 describe
"$BUILD/learner/modskill-learner" --servers "127.0.0.1:$PORT" --run_dir "$RUN_DIR" --preset small \
    --iterations 100000 --time_budget_min "${MODSKILL_TRAIN_MIN:-5}" --envs_per_server 256 "$@"
rm -f "$RUN_DIR/eval.html"  # a page from an earlier run must not pass for this one's
"$BUILD/learner/modskill-learner" --eval --checkpoint "$RUN_DIR/policy.pt" --servers "127.0.0.1:$PORT"
# The eval table above ends with the open-loop reference baseline on the same clips; the curve:
if /usr/bin/python3 client/python/examples/plot_learning_curve.py "$RUN_DIR/progress.csv" \
    --out "$RUN_DIR/learning_curve.png" > /dev/null 2>&1; then
  echo "learning curve: $RUN_DIR/learning_curve.png"
fi
echo "evaluation: $RUN_DIR/eval.md (policy and open-loop reference baseline)"
if [ -f "$RUN_DIR/eval.html" ]; then
  echo "viewer: $(cd "$RUN_DIR" && pwd)/eval.html (open it in a browser; offline, one file)"
fi
