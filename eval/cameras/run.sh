#!/usr/bin/env bash
# Cross-camera table: the shipped GQ-CNN (trained on PrimeSense images) and planarity-centroid on the
# basic set with every camera preset, same seeded trials, then the report. The scene's camera pose
# comes from the paper's distribution fitted into each preset's working range.
# Usage: eval/cameras/run.sh [RUNS_DIR] [REPORT_DIR] [TRIALS]   (~5 min on 2 cores with 25 trials)
set -euo pipefail
RUNS=${1:-runs/cameras}
REPORT=${2:-eval/cameras}
TRIALS=${3:-25}
SB=${SB:-suctionbench}
mkdir -p "$RUNS"
for camera in primesense realsense-d415 realsense-d435 zivid-2; do
  for policy in gqcnn planarity-centroid; do
    name="${policy}_${camera}"
    [ -f "$RUNS/$name.done" ] && continue
    rm -rf "${RUNS:?}/$name"
    $SB eval --policy "$policy" --set basic --trials "$TRIALS" --camera "$camera" --workers 2 --seed 0 \
      --out "$RUNS/$name" --json > "$RUNS/$name.json"
    touch "$RUNS/$name.done"
  done
done
$SB report "$RUNS" --out "$REPORT/report" > /dev/null
${PYTHON:-python3} - "$RUNS" > "$REPORT/table.md" <<'PY'
import json, sys, pathlib
from suctionbench.learning.checkpoint import load_model
from suctionbench.policies.gqcnn import default_model_dir
runs = pathlib.Path(sys.argv[1])
CROP = load_model(default_model_dir()).thumbnail.crop_size  # the shipped model's grasp crop (px)
FX = {"primesense": 525.0, "realsense-d415": 1004.6, "realsense-d435": 446.8, "zivid-2": 1800.0}
print("| camera | fx (px) | GQ-CNN crop at 0.6 m (cm) | policy | trials | success % | AP % "
      "| label precision % | picks/hour |")
print("|---|---|---|---|---|---|---|---|---|")
for camera, fx in FX.items():
    for policy in ("gqcnn", "planarity-centroid"):
        r = json.loads((runs / f"{policy}_{camera}.json").read_text().strip().splitlines()[-1])
        pct = lambda v: "-" if v is None else f"{100 * v:.0f}"
        print(f"| {camera} | {fx:g} | {CROP * 0.6 / fx * 100:.1f} | {policy} | {r['trials']} | "
              f"{pct(r['success_rate'])} | {pct(r['ap'])} | {pct(r['label_precision'])} | {r['picks_per_hour']} |")
PY
cat "$REPORT/table.md"
