"""Is the held-out accuracy's ~0.92 a variance limit? Score test-time flips and model ensembles.

Usage: python eval/gqcnn/ensemble.py DATASET MODEL [MODEL ...]
On DATASET's whole object-wise validation split, each MODEL's q (a) as trained, (b) averaged over
the four symmetries the trainer augments with (`learning.data.symmetrize`: identity, row flip,
column flip, 180 deg rotation; the network was trained to be invariant to them), and (c) averaged
with each other MODEL's q, and all MODELs together. Accuracy (q above the model's decision
threshold against the dataset's label), AP and the share of views whose top-q grasp is robust, as
`suctionbench model score` computes them. If errors were a single network's variance (how its
weights happened to land), averaging members would remove part of them; if the accuracy does not
move, what holds it is in the inputs and labels, not in any one set of weights.
"""

from __future__ import annotations

import sys
from itertools import combinations

import numpy as np
import torch

from suctionbench.dataset.storage import read_card
from suctionbench.learning.checkpoint import load_model
from suctionbench.learning.data import label_threshold, labels_of, symmetrize, to_tensors
from suctionbench.learning.metrics import average_precision, top_grasp_success
from suctionbench.learning.train import EVAL_BATCH
from suctionbench.learning.train_config import decision_threshold

FLIPS = ((False, False), (True, False), (False, True), (True, True))
"""(rows, columns) flipped: identity, up-down, left-right, both (the 180 deg rotation)."""


def flip_scores(models: dict, data, threshold: float) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Per model, q (4, N) of every datapoint under each of FLIPS; and the labels (N,); in the
    split's order, the split read once for all models."""
    scores: dict[str, list[list[np.ndarray]]] = {path: [[] for _ in FLIPS] for path in models}
    for model in models.values():
        model.network.eval()
    labels = []
    with torch.no_grad():
        for batch in data.batches(EVAL_BATCH):
            labels.append(labels_of(batch.metric, threshold))
            images, poses = to_tensors(batch, torch.device("cpu"))
            n = len(images)
            for k, (rows, cols) in enumerate(FLIPS):
                flipped, angles = symmetrize(images, poses[:, 1], torch.full((n,), rows), torch.full((n,), cols))
                flipped_poses = torch.cat([poses[:, :1], angles[:, None], poses[:, 2:]], dim=1)
                for path, model in models.items():
                    logits = model.network(*model.stats.normalise(flipped, flipped_poses)).float()
                    scores[path][k].append(torch.softmax(logits, dim=1)[:, 1].numpy())
    return {path: np.stack([np.concatenate(s) for s in per_flip]) for path, per_flip in scores.items()}, \
        np.concatenate(labels)


def main(dataset: str, models: list[str]) -> None:
    threshold = label_threshold(read_card(dataset))
    loaded = {path: load_model(path, device="cpu") for path in models}
    cut = decision_threshold(loaded[models[0]].target, threshold)
    first = loaded[models[0]]
    for path, model in loaded.items():
        if decision_threshold(model.target, threshold) != cut:
            raise SystemExit(f"{path}: another target than {models[0]}'s; their q are not averaged here")
        if (model.image_channels, model.pose_dim, model.thumbnail) != (first.image_channels, first.pose_dim,
                                                                       first.thumbnail):
            raise SystemExit(f"{path}: reads other inputs than {models[0]}; the split is read once for all")
    data = first.split_data(dataset, "object_wise", "val")
    scored, labels = flip_scores(loaded, data, threshold)
    views = data.values("image_labels")
    print(f"{data.num_datapoints} held-out datapoints of {dataset}; decision threshold {cut}")
    print("| q | accuracy | AP | top-q robust |")
    print("|---|---|---|---|")

    def row(name: str, q: np.ndarray) -> None:
        top = top_grasp_success(labels, q, views)["top_grasp_success"]
        print(f"| {name} | {np.mean((q > cut) == (labels == 1)):.4f} | {average_precision(labels, q):.4f} | "
              f"{100 * top:.1f} % |")

    for path, q in scored.items():
        row(path, q[0])
        row(f"{path}, mean over the four flips", q.mean(axis=0))
    for a, b in combinations(models, 2):
        row(f"mean of {a} and {b}", (scored[a][0] + scored[b][0]) / 2)
    if len(models) > 2:
        row("mean of all", np.mean([q[0] for q in scored.values()], axis=0))
        row("mean of all, each over the four flips", np.mean([q.mean(axis=0) for q in scored.values()], axis=0))


if __name__ == "__main__":
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    torch.set_num_threads(2)
    main(sys.argv[1], sys.argv[2:])
