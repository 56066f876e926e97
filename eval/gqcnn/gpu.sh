#!/usr/bin/env bash
# One lent GPU machine's session, as one timed command: the CUDA tests, a dataset generated on the
# machine's cores, and GQ-CNNs trained on its GPU until a deadline. Usage, from the repository root
# of a machine with a CUDA GPU, torch and the project's dependencies importable:
#   eval/gqcnn/gpu.sh OUT [BUDGET_S]
# Steps (each logged with its second since the start to OUT/log.txt):
#   1. `pytest -m gpu`: the bfloat16 CUDA training path (tests/test_learning.py); `suctionbench
#      bench train`: training images/s on the GPU against the machine's CPU (batch 64 and 1024).
#   2. The 1,500-object training corpus (seed 0, as the shipped model's), a rate probe on its first
#      32 objects (on 1 worker, the scaling reference, and on WORKERS), then `generate` with as many
#      datapoints as the probe's rate fills GEN_S seconds with (a multiple of DP_STEP, within
#      DP_MIN-1,200,000), assembled on every core. SKIP_CHECKS=1 skips step 1.
#   3. ARCHS trained at once on the GPU, each one epoch at a time until the deadline
#      (eval/gqcnn/train_until.py: soft target, weights' average 0.9995, object-wise split).
#   4. Held-out accuracy and AP of the shipped default and of each trained model on the dataset's
#      object-wise validation split (eval/bin/heldout.py).
# OUT gets log.txt, bench_train.jsonl, heldout.jsonl, dataset_card.json, and per arch <arch>.json
# (its model card); the first arch's weights too (<arch>.safetensors): 8 files, what a lease returns.
# A lent machine has torch but not the project's other dependencies, and no network: run
# eval/gqcnn/gpu_wheels.sh here first (wheels and EGL loaders into .whl/ and .gl/, carried), then
# there `source eval/gqcnn/gpu_setup.sh` before this script.
set -u
OUT=${1:?output directory}
BUDGET=${2:-560}
GEN_S=${GEN_S:-150}
WORKERS=${WORKERS:-$(nproc)}
COUNT=${COUNT:-1500}
DP_MIN=${DP_MIN:-120000}
DP_STEP=${DP_STEP:-30000}
ARCHS=${ARCHS:-context-pose context-pose-wide dn3}
DEVICE=${DEVICE:-cuda}
WORK=${WORK:-/tmp/sb_gpu}
PY=${PY:-python3}
T0=$(date +%s)
mkdir -p "$OUT" "$WORK"
exec > >(tee -a "$OUT/log.txt") 2>&1
log() { echo "[$(( $(date +%s) - T0 )) s] $*"; }

if [ -z "${SKIP_CHECKS:-}" ]; then
  log "1. CUDA tests"
  timeout 150 $PY -m pytest -q -p no:cacheprovider -m gpu tests/test_learning.py 2>&1 | tail -n 6
  for batch in 64 1024; do
    timeout 90 $PY -m suctionbench bench train --archs dn3,context-pose --datapoints 40000 \
      --reference-datapoints 4000 --batch-size "$batch" --device "$DEVICE" --json | tail -n 1 \
      | tee -a "$OUT/bench_train.jsonl"
  done
fi

log "2. corpus of $COUNT objects on $WORKERS workers"
$PY -m suctionbench objects generate --count "$COUNT" --seed 0 --out "$WORK/corpus" --workers "$WORKERS" \
  >/dev/null || { log "corpus failed"; exit 1; }
mkdir -p "$WORK/probe_objects"
find "$WORK/corpus" -mindepth 2 -maxdepth 2 -type d | sort | head -n 32 | xargs -I{} cp -r {} "$WORK/probe_objects/"
PER_OBJECT=320
$PY -m suctionbench generate --objects "$WORK/probe_objects" --datapoints $((32 * PER_OBJECT / 4)) --out "$WORK/probe1" \
  --workers 1 --seed 1 --overwrite --json | tail -n 1
$PY -m suctionbench generate --objects "$WORK/probe_objects" --datapoints $((32 * PER_OBJECT)) --out "$WORK/probe" \
  --workers "$WORKERS" --seed 1 --overwrite --json | tail -n 1
RATE=$($PY -c "import json; print(json.load(open('$WORK/probe/config.json'))['generation']['datapoints_per_s'])")
DATAPOINTS=$($PY -c "print(max($DP_MIN, min(1200000, int($RATE * $GEN_S) // $DP_STEP * $DP_STEP)))")
log "probe: $RATE datapoints/s; generating $DATAPOINTS"
$PY -m suctionbench generate --objects "$WORK/corpus" --datapoints "$DATAPOINTS" --out "$WORK/data" \
  --workers "$WORKERS" --seed 0 --overwrite --json | tail -n 1 || { log "generate failed"; exit 1; }
cp "$WORK/data/config.json" "$OUT/dataset_card.json"

REMAIN=$(( BUDGET - ($(date +%s) - T0) ))
DEADLINE=$(( $(date +%s) + REMAIN - 45 ))  # 45 s left for the held-out scores and the copies
log "3. training $ARCHS until $(( DEADLINE - T0 )) s"
THREADS=$(( WORKERS / $(echo $ARCHS | wc -w) ))
pids=()
for arch in $ARCHS; do
  OMP_NUM_THREADS=$THREADS $PY eval/gqcnn/train_until.py "$WORK/data" "$WORK/models/$arch" --arch "$arch" \
    --device "$DEVICE" --deadline "$DEADLINE" --load-threads "$THREADS" > "$WORK/$arch.jsonl" 2>&1 &
  pids+=($!)
done
wait "${pids[@]}"  # not a bare wait: that would also wait for the log's tee
for arch in $ARCHS; do tail -n 3 "$WORK/$arch.jsonl"; cp "$WORK/models/$arch/model.json" "$OUT/$arch.json"; done
first=${ARCHS%% *}
cp "$WORK/models/$first/model.safetensors" "$OUT/$first.safetensors"

log "4. held-out scores"
models=(assets/models/gqcnn-context-pose-avg)  # the earlier default, trained on data cut as this script cuts it (96 px, paper noise)
for arch in $ARCHS; do models+=("$WORK/models/$arch"); done
timeout 40 $PY eval/bin/heldout.py "$WORK/data" "${models[@]}" | tee "$OUT/heldout.jsonl"
log "done"
