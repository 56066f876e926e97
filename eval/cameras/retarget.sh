#!/usr/bin/env bash
# "Retarget to your camera", measured: two compact GQ-CNNs trained the same way (same corpus, labels,
# budget, epochs and seed), one on rendered PrimeSense images and one on RealSense D435 images,
# each then planning on the basic set with both cameras (same seeded trials). Writes
# retarget.md beside this script from the runs' JSON.
# Usage: eval/cameras/retarget.sh [RUNS_DIR] [DATAPOINTS] [TRIALS]   (20 min on 2 cores at 40000 / 25)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
RUNS=${1:-runs/retarget}
N=${2:-40000}
TRIALS=${3:-25}
SB=${SB:-suctionbench}
CAMERAS="primesense realsense-d435"
mkdir -p "$RUNS"
# the 1,500-object training corpus (cached: a rerun reuses it)
$SB objects generate --count 1500 --seed 0 --out "$RUNS/corpus" --json > "$RUNS/corpus.json"
for cam in $CAMERAS; do
  if [ ! -f "$RUNS/model_$cam.done" ]; then
    rm -rf "${RUNS:?}/data_$cam" "${RUNS:?}/model_$cam"
    $SB generate --objects "$RUNS/corpus" --datapoints "$N" --camera "$cam" --seed 0 --out "$RUNS/data_$cam" --json \
      > "$RUNS/data_$cam.json"
    $SB train --dataset "$RUNS/data_$cam" --out "$RUNS/model_$cam" --arch compact --epochs 15 \
      --split object_wise --seed 0 --json > "$RUNS/model_$cam.json"
    touch "$RUNS/model_$cam.done"
  fi
done
for model in $CAMERAS; do
  for cam in $CAMERAS; do
    name="m_${model}_c_${cam}"
    [ -f "$RUNS/$name.done" ] && continue
    rm -rf "${RUNS:?}/$name"
    $SB eval --policy gqcnn --model "$RUNS/model_$model" --set basic --trials "$TRIALS" --camera "$cam" \
      --workers 2 --seed 0 --out "$RUNS/$name" --json > "$RUNS/$name.json"
    touch "$RUNS/$name.done"
  done
done
python3 - "$RUNS" "$CAMERAS" > "$here/retarget.md" <<'PY'
import json, sys, pathlib
runs, cameras = pathlib.Path(sys.argv[1]), sys.argv[2].split()
def last(path):
    return json.loads(path.read_text().strip().splitlines()[-1])
print("| model trained on | held-out accuracy | held-out AP | camera at test | trials | success % | AP % |")
print("|---|---|---|---|---|---|---|")
for model in cameras:
    card = last(runs / f"model_{model}.json")  # `train --json`: the held-out metrics at its top level
    acc, ap = card.get("val_accuracy"), card.get("val_ap")
    for cam in cameras:
        s = last(runs / f"m_{model}_c_{cam}.json")
        s = s.get("summary", s)
        pct = lambda v: "-" if v is None else f"{100 * v:.1f}"
        print(f"| {model} | {acc if acc is None else round(acc, 3)} | {ap if ap is None else round(ap, 3)} "
              f"| {cam} | {s['trials']} | {pct(s['success_rate'])} | {pct(s['ap'])} |")
PY
