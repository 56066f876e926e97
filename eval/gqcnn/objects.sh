#!/usr/bin/env bash
# The held-out accuracy's learning curve over object diversity: the shipped architecture trained
# from scratch on the datapoints of N random training objects, the datapoint count held fixed
# within a group (--max-objects N --max-datapoints D), so only how many different objects the
# views come from changes. Same epochs, seed, recipe and held-out objects (the object-wise split's
# 300) in every arm. Usage:
#   eval/gqcnn/objects.sh DATASET OUT_DIR D:N[,N...] [D:N[,N...] ...]
# e.g. eval/gqcnn/objects.sh data/sensor48_s2_1m6 runs/objects 280000:300,600,1200 560000:600,1200
# SEED=S (default 0) draws other objects, initial weights and data order: a replicate, named
# d<D>_n<N>_s<S>. INIT=MODEL fine-tunes MODEL instead of training from scratch (train --init, its
# schedule restarting at gqcnn's rate): arms named init_d<D>_n<N>[_s<S>]. Writes OUT_DIR/<name>.json
# (train --json; the per-epoch history is in OUT_DIR/<name>/model.json); a finished arm (its .json)
# is kept. eval/gqcnn/objects.py OUT_DIR prints the table.
set -euo pipefail
DATASET=${1:?dataset directory}
OUT=${2:?output directory}
shift 2
EPOCHS=${EPOCHS:-4}
MAX_VAL=${MAX_VAL:-50000}  # validation subset scored after every epoch: the same one in every arm of a seed
SB=${SB:-suctionbench}
SEED=${SEED:-0}
INIT=${INIT:-}
init_args=()
prefix=""
if [ -n "$INIT" ]; then init_args=(--init "$INIT"); prefix="init_"; fi
mkdir -p "$OUT"
for group in "$@"; do
  D=${group%%:*}
  IFS=, read -r -a counts <<< "${group#*:}"
  for N in "${counts[@]}"; do
    name="${prefix}d${D}_n${N}"
    [ "$SEED" != 0 ] && name="${name}_s${SEED}"
    [ -f "$OUT/$name.json" ] && continue
    $SB train --dataset "$DATASET" --out "$OUT/$name" --arch context-pose-wide --epochs "$EPOCHS" --device cpu \
      --split object_wise --batch-size 64 --max-objects "$N" --max-datapoints "$D" --max-val-datapoints "$MAX_VAL" \
      --augment --no-augment-noise --target soft --seed "$SEED" --average 0.9995 --load-threads 1 "${init_args[@]}" --json \
      | tail -n 1 > "$OUT/$name.json.tmp"
    mv "$OUT/$name.json.tmp" "$OUT/$name.json"
  done
done
