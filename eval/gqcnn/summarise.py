"""Print the GQ-CNN sweep's table (Markdown) from the JSON files eval/gqcnn/sweep.sh writes.

Usage: python eval/gqcnn/summarise.py OUT_DIR
Columns: parameters and multiply-accumulates per grasp; the fit check (training datapoints scored
without augmentation) beside held-out-object validation; training throughput; plan time per grasp
of the CEM (gqcnn) and dense (fc-gqcnn) policies on 2 cores.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def main(out: Path) -> None:
    print("| arch | parameters | MACs / grasp | train datapoints | epochs | fit acc | val acc | fit - val | "
          "val AP | train images/s | CEM plan s | dense plan s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for path in sorted(out.glob("*.json")):
        if path.stem.endswith("_plan"):
            continue
        run = json.loads(path.read_text())
        plan_path = out / f"{path.stem}_plan.json"
        plan = json.loads(plan_path.read_text()) if plan_path.is_file() else {}
        cem, dense = plan.get("gqcnn_s_per_grasp"), plan.get("fc-gqcnn_s_per_grasp")
        print(f"| {run['arch']} | {run['parameters']:,} | {run['macs_per_grasp'] / 1e6:.2f} M | {run['num_train']:,} | "
              f"{run['epochs']} | {run['fit_accuracy']:.3f} | {run['val_accuracy']:.3f} | "
              f"{run['fit_accuracy'] - run['val_accuracy']:+.3f} | {run['val_ap']:.3f} | "
              f"{run['train_images_per_s']:,.0f} | {'-' if cem is None else f'{cem:.3f}'} | "
              f"{'-' if dense is None else f'{dense:.3f}'} |")


if __name__ == "__main__":
    if len(sys.argv) != 2 or not Path(sys.argv[1]).is_dir():
        sys.exit("usage: python eval/gqcnn/summarise.py OUT_DIR (the directory eval/gqcnn/sweep.sh wrote)")
    main(Path(sys.argv[1]))
