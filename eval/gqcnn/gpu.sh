#!/usr/bin/env bash
# One lent GPU machine's session, as one timed command: the CUDA tests, a dataset generated on the
# machine's cores, and GQ-CNNs trained on its GPU until a deadline. Usage, from the repository root
# of a machine with a CUDA GPU, torch and the project's dependencies importable:
#   eval/gqcnn/gpu.sh OUT [BUDGET_S]
# Steps (each logged with its second since the start to OUT/log.txt):
#   1. `pytest -m gpu`: the bfloat16 CUDA training path (tests/test_learning.py).
#   2. The 1,500-object training corpus (seed 0, as the shipped model's), a rate probe on its first
#      32 objects, then `generate` with as many datapoints as the probe's rate fills GEN_S seconds
#      with (a multiple of DP_STEP, within DP_MIN-1,200,000), assembled on every core.
#   3. ARCHS trained at once on the GPU, each one epoch at a time until the deadline
#      (eval/gqcnn/train_until.py: soft target, weights' average 0.9995, object-wise split).
#   4. Held-out accuracy and AP of the shipped default and of each trained model on the dataset's
#      object-wise validation split (eval/bin/heldout.py).
# OUT gets log.txt, heldout.jsonl, dataset_card.json, and per arch <arch>.json (its model card); the
# first arch's weights and PR curve too (<arch>.safetensors, <arch>_pr.png).
# The lent H200 had torch 2.11 but not the project's dependencies and no network. They went along as
# cp312 manylinux wheels (trimesh, embreex, rtree, manifold3d, qpsolvers, clarabel, cffi, pycparser,
# tomli-w, mujoco 3.17.0 without its mujoco/experimental folder, pyopengl, glfw, gymnasium,
# farama-notifications, typer, pydantic, pydantic-core, annotated-types, typing-inspection) with the
# EGL loader packages (libegl1, libglvnd0, libopengl0, libgl1, libglx0, libgles2), set up before
# this script ran with: `dpkg -x` of each .deb into /, ldconfig, __EGL_VENDOR_LIBRARY_FILENAMES at
# the driver's 10_nvidia.json, each wheel unpacked (`python3 -m zipfile -e`) into /tmp/site,
# PYTHONPATH=/tmp/site MUJOCO_GL=egl, `pip install --no-deps --no-build-isolation --no-index -e .`.
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

log "1. CUDA tests"
timeout 150 $PY -m pytest -q -p no:cacheprovider -m gpu tests/test_learning.py 2>&1 | tail -n 6

log "2. corpus of $COUNT objects on $WORKERS workers"
$PY -m suctionbench objects generate --count "$COUNT" --seed 0 --out "$WORK/corpus" --workers "$WORKERS" \
  >/dev/null || { log "corpus failed"; exit 1; }
mkdir -p "$WORK/probe_objects"
find "$WORK/corpus" -mindepth 2 -maxdepth 2 -type d | sort | head -n 32 | xargs -I{} cp -r {} "$WORK/probe_objects/"
PER_OBJECT=320
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
cp "$WORK/models/$first/precision_recall.png" "$OUT/${first}_pr.png" 2>/dev/null

log "4. held-out scores"
models=(assets/models/gqcnn-context-pose-avg)  # the shipped default, as the reference
for arch in $ARCHS; do models+=("$WORK/models/$arch"); done
timeout 40 $PY eval/bin/heldout.py "$WORK/data" "${models[@]}" | tee "$OUT/heldout.jsonl"
log "done"
