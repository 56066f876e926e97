#!/usr/bin/env bash
# The full benchmark behind eval/benchmark/: every image policy on basic / typical / adversarial
# (gqcnn and fc-gqcnn with the shipped default model, gqcnn-adv and fc-gqcnn-adv with the one
# trained on the adversarial objects only) and the known-state analytic policy (best rwr grasp with shape and
# pose known: the upper bound perfect perception would reach), the known-objects task with the analytic policy (one run per 3D
# metric) and 300 random known-state grasps for the random-grasp classification table, then the
# report. Usage: eval/benchmark.sh [RUNS_DIR] [REPORT_DIR]   (about 35 min on 2 cores)
set -euo pipefail
RUNS=${1:-runs/full}
REPORT=${2:-eval/benchmark}
SB=${SB:-suctionbench}
mkdir -p "$RUNS"
run() {  # name, eval options...; a finished run (its .done marker) is kept
  local name=$1; shift
  [ -f "$RUNS/$name.done" ] && return
  rm -rf "${RUNS:?}/$name"
  $SB eval "$@" --workers 2 --seed 0 --out "$RUNS/$name" --resume --json > "$RUNS/$name.json"
  touch "$RUNS/$name.done"
}
for set in basic typical adversarial; do
  for policy in gqcnn fc-gqcnn gqcnn-adv fc-gqcnn-adv planarity-centroid centroid planarity random analytic; do
    run "${policy}_${set}" --policy "$policy" --task "$set"
  done
done
run analytic_known --policy analytic --task known_objects
run random-surface_known --policy random-surface --task known_objects --trials 300
$SB report "$RUNS" --out "$REPORT"
