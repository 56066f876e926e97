#!/usr/bin/env bash
# The bin-picking benchmark behind eval/bin/: every built-in image policy and the known-state
# analytic policy on the bin tasks (bin-basic, bin-typical, bin-mixed: 10 bins each, the same bins
# for every policy), with object regions from depth segmentation; planarity-centroid and gqcnn
# again with the renderer's instance masks (oracle segmentation); the GQ-CNN fine-tuned on clutter
# data (--model assets/models/gqcnn-bin); then the report.
# Usage: eval/bin/benchmark.sh [RUNS_DIR] [REPORT_DIR]
set -euo pipefail
RUNS=${1:-runs/bin}
REPORT=${2:-eval/bin}
SB=${SB:-suctionbench}
mkdir -p "$RUNS"
run() {  # name, eval options...; a finished run (its .done marker) is kept
  local name=$1; shift
  [ -f "$RUNS/$name.done" ] && return
  $SB eval "$@" --workers 2 --out "$RUNS/$name" --overwrite --json > "$RUNS/$name.json"
  touch "$RUNS/$name.done"
}
for task in bin-basic bin-typical bin-mixed; do
  for policy in gqcnn fc-gqcnn planarity-centroid centroid random analytic; do
    run "${policy}_${task}" --policy "$policy" --task "$task"
  done
  for policy in planarity-centroid gqcnn; do
    run "${policy}_${task}_oracle" --policy "$policy" --task "$task" --masks oracle
  done
  # the GQ-CNN fine-tuned on clutter data (assets/models/gqcnn-bin/README.md)
  run "gqcnn-bin_${task}" --policy gqcnn --model assets/models/gqcnn-bin --task "$task"
done
$SB report "$RUNS" --out "$REPORT/report"
