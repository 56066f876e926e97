"""Where a GQ-CNN's held-out errors lie: by what the nominal grasp does (seals? resists the load?).

Usage: python eval/gqcnn/error_cells.py MODEL_DIR DATASET_DIR [MAX_DATAPOINTS] [SEED]
Scores the model on the dataset's object-wise validation split (the subset `suctionbench model
score --max-datapoints N --seed S` scores) and splits datapoints by the dataset's `seal_flags` (the
unperturbed grasp seals) and `wrench_resistance` (it seals and resists the pick's loads). Per
cell: share of the datapoints, the robust label's positive rate, the model's accuracy at its
decision threshold (`learning.train_config.decision_threshold`) and its share of all errors. Seal is a
matter of the surface under the cup (what the grasp thumbnail shows); resistance, once sealed, of
the load: the object's weight and its moment about the grasp (mass and centre of mass, which a
depth image shows only in part).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from suctionbench.dataset.storage import read_card
from suctionbench.learning.checkpoint import load_model
from suctionbench.learning.data import label_threshold
from suctionbench.learning.train import score_model


def main(model_dir: Path, dataset: Path, count: int, seed: int) -> None:
    model = load_model(model_dir)
    threshold = label_threshold(read_card(dataset))
    data = model.split_data(dataset, "object_wise", "val", max_datapoints=count, subset_rng=np.random.default_rng(seed))
    scored = score_model(model, data, threshold)  # scores and labels in index order: shard by shard, row by row
    q, label, cut = scored["scores"], scored["labels"] == 1, scored["decision_threshold"]
    seal, resists = data.values("seal_flags"), data.values("wrench_resistance")
    wrong = (q > cut) != label
    print(f"{model_dir} on {dataset} (object_wise/val, {len(q)} datapoints): accuracy {scored['accuracy']:.4f} "
          f"at q > {cut:g}, {scored['accuracy_at_half']:.4f} at q > 0.5")
    print("| nominal grasp | share | positive rate | accuracy | share of the errors | mean q |")
    print("|---|---|---|---|---|---|")
    for name, cell in (("no seal", seal == 0), ("seals, load not resisted", (seal == 1) & (resists == 0)),
                       ("seals and resists", (seal == 1) & (resists == 1))):
        if cell.any():
            print(f"| {name} | {cell.mean():.3f} | {label[cell].mean():.3f} | {np.mean(~wrong[cell]):.3f} | "
                  f"{wrong[cell].sum() / max(wrong.sum(), 1):.3f} | {q[cell].mean():.3f} |")


if __name__ == "__main__":
    if len(sys.argv) not in (3, 4, 5):
        sys.exit(__doc__)
    main(Path(sys.argv[1]), Path(sys.argv[2]), int(sys.argv[3]) if len(sys.argv) > 3 else 50000,
         int(sys.argv[4]) if len(sys.argv) > 4 else 0)
