#!/bin/bash
# Evaluates the cmu exports the interrupted bench left (its eval phase died when the learner
# binary was relinked under it); same protocol: one server with the bench's flags, --eval per export.
cd "$(dirname "$0")/../../../.."
OUT=runs/frames_cmu
build/server/modskill-server --port 0 --threads 1 --no_generative > $OUT/reeval_server.log 2>&1 &
pid=$!
trap 'kill $pid' EXIT
for _ in $(seq 100); do grep -q "listening on" $OUT/reeval_server.log && break; sleep 0.2; done
port=$(sed -n 's/.*listening on [^:]*:\([0-9]*\) .*/\1/p' $OUT/reeval_server.log | head -1)
for name in base_s2 frames3_s2; do
  for policy in "$OUT/$name"/policy*.pt; do
    tag=$(basename "$policy" .pt); tag="${tag#policy}"
    [ -f "$OUT/$name/eval$tag/eval.json" ] && continue
    build/learner/modskill-learner --eval --checkpoint "$policy" --servers "127.0.0.1:$port" \
        --clips cmu_02_01 --eval_out "$OUT/$name/eval$tag" > "$OUT/$name/eval$tag.log" 2>&1
  done
done
build/learner/modskill-learner --eval --baseline --servers "127.0.0.1:$port" --clips cmu_02_01 \
    --eval_out "$OUT/baseline" > "$OUT/baseline.log" 2>&1
/usr/bin/python3 bench/learning_table.py "$OUT" base frames3 base_s2 frames3_s2 > "$OUT/table.md"
/usr/bin/python3 client/python/examples/plot_learning_curve.py $OUT/{base,frames3,base_s2,frames3_s2}/progress.csv --out "$OUT/curves.png"
echo done
