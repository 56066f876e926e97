#!/usr/bin/env bash
# The GQ-CNN ablation and capacity sweep behind the model card: every architecture trained on the
# same data (a seeded random subset of the paper-scale dataset's training split, object-wise split
# so validation objects are never seen), the same epochs and seed; then each one's plan time with
# the CEM and dense policies on 2 cores. Usage:
#   eval/gqcnn/sweep.sh DATASET [OUT_DIR] [MAX_TRAIN] [EPOCHS] [ARCHS...]
# Writes OUT_DIR/<arch>.json (train --json) and OUT_DIR/<arch>_plan.json (bench plan --json);
# eval/gqcnn/summarise.py OUT_DIR prints the table. A finished arch (its .json) is kept.
set -euo pipefail
DATASET=${1:?dataset directory}
OUT=${2:-runs/gqcnn_sweep}
MAX_TRAIN=${3:-400000}
EPOCHS=${4:-5}
MAX_VAL=${MAX_VAL:-50000}  # validation subset scored after every epoch (held-out objects)
shift $(( $# < 4 ? $# : 4 ))
ARCHS=${*:-compact context context-wide}
SB=${SB:-suctionbench}
mkdir -p "$OUT"
for arch in $ARCHS; do
  if [ ! -f "$OUT/$arch.json" ]; then
    $SB train --dataset "$DATASET" --out "$OUT/$arch" --arch "$arch" --epochs "$EPOCHS" --split object_wise \
      --max-datapoints "$MAX_TRAIN" --max-val-datapoints "$MAX_VAL" --seed 0 --json | tail -n 1 > "$OUT/$arch.json.tmp"
    mv "$OUT/$arch.json.tmp" "$OUT/$arch.json"
  fi
  if [ ! -f "$OUT/${arch}_plan.json" ]; then
    $SB bench plan --policies gqcnn,fc-gqcnn --model "$OUT/$arch" --scenes 5 --cores 2 --seed 0 --json \
      | tail -n 1 > "$OUT/${arch}_plan.json.tmp"
    mv "$OUT/${arch}_plan.json.tmp" "$OUT/${arch}_plan.json"
  fi
done
