"""Held-out scores of trained GQ-CNNs on a dataset's validation split: accuracy (q > 0.5 against
rwr > the dataset's label threshold) and AP, model by model on the same datapoints. What the bin
README's "what clutter data adds" table reads.

    .venv/bin/python eval/bin/heldout.py DATASET MODEL [MODEL ...] [--split object_wise]
        [--subset all|proposals|uniform]

--subset proposals scores only the datapoints a dataset made with `generate --proposals` labelled at
its proposing model's own best grasps (grasp ids < 0): how well a model ranks the grasps a dense
policy would pick, where a score over uniform grasps does not look.
"""

import argparse
import json

import numpy as np

from suctionbench.dataset.storage import read_card
from suctionbench.learning.checkpoint import load_model
from suctionbench.learning.metrics import average_precision


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset")
    parser.add_argument("models", nargs="+")
    parser.add_argument("--split", default="object_wise")
    parser.add_argument("--subset", choices=("all", "proposals", "uniform"), default="all")
    args = parser.parse_args()
    threshold = float(read_card(args.dataset).get("config", {}).get("label_threshold", 0.2))
    for directory in args.models:
        model = load_model(directory)
        data = model.split_data(args.dataset, args.split, "val")
        q, metric = [], []
        for shard in data.shards:
            batch = data.load_shard(shard)
            keep = np.ones(len(batch), dtype=bool)
            if args.subset != "all":
                proposed = data.reader.shard(shard, fields=["grasp_labels"])["grasp_labels"][data.rows(shard)] < 0
                keep = proposed if args.subset == "proposals" else ~proposed
                if not keep.any():
                    continue
            q.append(model.predict(batch.images[keep], batch.poses[keep]))
            metric.append(batch.metric[keep])
        q, metric = np.concatenate(q), np.concatenate(metric)
        label = metric > threshold
        print(json.dumps({"model": directory, "subset": args.subset, "datapoints": len(q),
                          "positive_rate": round(float(label.mean()), 4),
                          "accuracy": round(float(((q > 0.5) == label).mean()), 4),
                          "ap": round(float(average_precision(label, q)), 4)}))


if __name__ == "__main__":
    main()
