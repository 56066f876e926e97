"""Held-out accuracy and AP per kind of object: which of the corpus's generators a model's errors lie on.

Usage: python eval/gqcnn/by_kind.py DATASET MODEL [MODEL ...]
On DATASET's whole object-wise validation split, each MODEL scored as `suctionbench model score`
scores it (q above its decision threshold against the dataset's label), the datapoints grouped by
the kind their object's key ends in (`objects generate` names them train_NNNNN_KIND: household,
primitive, blob, composite, superquadric, adversarial). A kind the network does worse on than the
rest, and a fine-tune that mends it at the others' cost, say what the one network cannot hold at once.
"""

from __future__ import annotations

import sys

import numpy as np
import torch

from suctionbench.dataset.storage import read_card
from suctionbench.learning.checkpoint import load_model
from suctionbench.learning.data import label_threshold
from suctionbench.learning.metrics import average_precision
from suctionbench.learning.train import score_model


def main(dataset: str, models: list[str]) -> None:
    card = read_card(dataset)
    threshold, keys = label_threshold(card), card.get("objects") or []
    if not keys:
        raise SystemExit(f"{dataset}: its card names no objects, so there are no kinds to group by")
    rows: dict[str, dict[str, tuple[int, float, float]]] = {}
    for path in models:
        model = load_model(path)
        data = model.split_data(dataset, "object_wise", "val")
        scored = score_model(model, data, threshold)
        q, labels, cut = scored["scores"], scored["labels"], scored["decision_threshold"]
        kinds = np.array([str(keys[i]).rsplit("_", 1)[-1] for i in data.values("object_labels")])
        rows[path] = {"all": (len(q), scored["accuracy"], scored["ap"])}
        for kind in sorted(set(kinds.tolist())):
            part = kinds == kind
            rows[path][kind] = (int(part.sum()), float(np.mean((q[part] > cut) == (labels[part] == 1))),
                                average_precision(labels[part], q[part]))
    kinds = list(next(iter(rows.values())))
    print(f"held-out datapoints of {dataset} by kind: accuracy / AP")
    print("| model | " + " | ".join(f"{k} ({rows[models[0]][k][0]})" for k in kinds) + " |")
    print("|---" * (len(kinds) + 1) + "|")
    for path, by_kind in rows.items():
        print(f"| {path} | " + " | ".join(f"{by_kind[k][1]:.4f} / {by_kind[k][2]:.4f}" for k in kinds) + " |")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    torch.set_num_threads(2)
    main(sys.argv[1], sys.argv[2:])
