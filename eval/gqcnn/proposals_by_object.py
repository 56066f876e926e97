"""Per object, how trained GQ-CNNs rank the grasps of a dataset made with `generate --proposals`:
the proposing model's own best grasps apart from the uniform surface grasps of the same images.

Usage: python eval/gqcnn/proposals_by_object.py DATASET MODEL [MODEL ...]

Every datapoint of the dataset is scored (both sides of any split: meant for a small dataset of new
images, e.g. `generate ... --seed 1 --proposals MODEL`). Per object and subset: datapoints, the
share labelled positive (rwr > the dataset's label threshold; for the proposals this is the
proposing policy's precision where it acts), the model's AP and its largest q. "top-1" is per image:
the share of images whose highest-scored uniform candidate is positive, beside the share of images
that have any positive candidate at all (what a perfect ranker would reach).
"""

from __future__ import annotations

import sys

import numpy as np

from suctionbench.dataset.storage import read_card
from suctionbench.learning.checkpoint import load_model
from suctionbench.learning.metrics import average_precision


def scored(dataset: str, directory: str) -> dict[str, np.ndarray]:
    """q, metric, proposal flag, object and image index of every datapoint, as `directory`'s model
    reads the dataset."""
    model = load_model(directory)
    columns: dict[str, list[np.ndarray]] = {"q": [], "metric": [], "proposed": [], "object": [], "image": []}
    for part in ("train", "val"):
        data = model.split_data(dataset, "image_wise", part)
        for shard in data.shards:
            batch = data.load_shard(shard)
            fields = data.reader.shard(shard, fields=["grasp_labels", "object_labels", "image_labels"])
            rows = data.rows(shard)
            columns["q"].append(model.predict(batch.images, batch.poses))
            columns["metric"].append(batch.metric)
            columns["proposed"].append(fields["grasp_labels"][rows] < 0)  # proposals carry negative grasp ids
            columns["object"].append(fields["object_labels"][rows])
            columns["image"].append(fields["image_labels"][rows])
    return {name: np.concatenate(parts) for name, parts in columns.items()}


def top1(label: np.ndarray, q: np.ndarray, image: np.ndarray) -> tuple[float, float]:
    """Share of images whose highest-q datapoint is positive, and share with any positive."""
    hits, any_positive = [], []
    for i in np.unique(image):
        here = image == i
        hits.append(label[here][np.argmax(q[here])])
        any_positive.append(label[here].any())
    return float(np.mean(hits)), float(np.mean(any_positive))


def main(dataset: str, models: list[str]) -> None:
    threshold = float(read_card(dataset).get("config", {}).get("label_threshold", 0.2))
    names = read_card(dataset).get("objects") or []
    print("| model | object | proposals: n / positive % / AP / max q | uniform: n / positive % / AP / max q "
          "| images: top-1 positive % / any positive % |")
    print("|---|---|---|---|---|")
    for directory in models:
        s = scored(dataset, directory)
        label = s["metric"] > threshold
        for obj in [None, *np.unique(s["object"])]:
            here = np.ones(len(label), bool) if obj is None else s["object"] == obj
            cells = []
            for subset in (s["proposed"], ~s["proposed"]):
                k = here & subset
                if not k.any():
                    cells.append("-")
                    continue
                ap = f"{average_precision(label[k], s['q'][k]):.3f}" if label[k].any() else "-"
                cells.append(f"{int(k.sum()):,} / {100 * label[k].mean():.1f} / {ap} / {s['q'][k].max():.2f}")
            uniform = here & ~s["proposed"]
            hit, reachable = top1(label[uniform], s["q"][uniform], s["image"][uniform])
            name = "all" if obj is None else names[int(obj)].split("/")[-1] if int(obj) < len(names) else str(obj)
            print(f"| {directory.rstrip('/').split('/')[-1]} | {name} | {cells[0]} | {cells[1]} | "
                  f"{100 * hit:.0f} / {100 * reachable:.0f} |")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2:])
