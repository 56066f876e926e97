"""Classification metrics of a grasp-quality network: accuracy, precision-recall curve, average precision.

Written out here (no scikit-learn dependency) with the same definitions as sklearn's
``precision_recall_curve`` / ``average_precision_score``: one operating point per distinct score,
AP = sum over those points of (R_k - R_{k-1}) P_k, i.e. the step-wise area under the PR curve
without interpolation. Tied scores form one point, so the result does not depend on the order of
ties.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from suctionbench.io import atomic_path


def precision_recall_curve(labels: np.ndarray, scores: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Precision, recall and thresholds, one point per distinct score, from the highest score down.

    Point k predicts "positive" for scores >= thresholds[k]. With no positive labels recall is
    undefined and comes back as NaN.
    """
    labels = np.asarray(labels).astype(bool).ravel()
    scores = np.asarray(scores, dtype=np.float64).ravel()
    if labels.shape != scores.shape:
        raise ValueError(f"labels {labels.shape} and scores {scores.shape} differ in shape")
    if len(scores) == 0:
        return np.zeros(0), np.zeros(0), np.zeros(0)
    order = np.argsort(-scores, kind="stable")
    sorted_scores, sorted_labels = scores[order], labels[order]
    last_of_tie = np.r_[np.flatnonzero(np.diff(sorted_scores)), len(scores) - 1]
    true_pos = np.cumsum(sorted_labels)[last_of_tie].astype(np.float64)
    predicted = last_of_tie + 1.0
    precision = true_pos / predicted
    with np.errstate(invalid="ignore", divide="ignore"):
        recall = true_pos / true_pos[-1]
    return precision, recall, sorted_scores[last_of_tie]


def average_precision(labels: np.ndarray, scores: np.ndarray) -> float:
    """Step-wise area under the precision-recall curve (sklearn's definition); NaN without positives."""
    precision, recall, _ = precision_recall_curve(labels, scores)
    if len(recall) == 0 or not np.isfinite(recall[-1]):
        return math.nan
    return float(np.sum(np.diff(np.r_[0.0, recall]) * precision))


def top_grasp_success(labels: np.ndarray, scores: np.ndarray, groups: np.ndarray) -> dict[str, float]:
    """What a policy that executes each image's highest-scored grasp would get, on labelled data.

    The CEM and dense policies act on the top of the grasps they score an image (~250 for CEM, every
    valid pixel for the dense policy), so an error there costs a pick while an error on a grasp
    ranked low costs nothing; accuracy and AP over all grasps weigh both alike. Per group (image)
    with at least two scored grasps: the label of its highest score (tied highest scores: their
    mean label, the expectation of picking one at random). Returns the
    mean over those images (``top_grasp_success``), the share of them with any positive grasp (the
    ceiling, ``top_grasp_ceiling``), their mean positive rate (a random pick, ``top_grasp_random``)
    and their count (``images``); NaN figures with no such image."""
    labels = np.asarray(labels, dtype=np.float64).ravel()
    scores = np.asarray(scores, dtype=np.float64).ravel()
    groups = np.asarray(groups).ravel()
    if not labels.shape == scores.shape == groups.shape:
        raise ValueError(f"labels {labels.shape}, scores {scores.shape} and groups {groups.shape} differ in shape")
    _, inverse, counts = np.unique(groups, return_inverse=True, return_counts=True)
    ranked = counts >= 2
    if not ranked.any():
        return {"images": 0, "top_grasp_success": math.nan, "top_grasp_ceiling": math.nan,
                "top_grasp_random": math.nan}
    best = np.full(len(counts), -np.inf)
    np.maximum.at(best, inverse, scores)
    top = scores == best[inverse]
    top_label = np.bincount(inverse, weights=labels * top) / np.bincount(inverse, weights=top)
    any_positive = np.bincount(inverse, weights=labels > 0.5) > 0
    mean_label = np.bincount(inverse, weights=labels) / counts
    return {"images": int(ranked.sum()), "top_grasp_success": float(top_label[ranked].mean()),
            "top_grasp_ceiling": float(any_positive[ranked].mean()),
            "top_grasp_random": float(mean_label[ranked].mean())}


def plot_precision_recall(path: str | Path, precision: np.ndarray, recall: np.ndarray, *, ap: float,
                          positive_rate: float, title: str) -> Path:
    """Save the PR curve as a PNG (matplotlib, Agg backend: no display needed), atomically.

    The dashed line is the positive rate, the precision of guessing, so the plot shows at a glance
    how much the network adds over chance.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    fig, ax = plt.subplots(figsize=(5, 4), dpi=120)
    try:
        ax.step(np.r_[0.0, recall], np.r_[precision[:1] if len(precision) else [1.0], precision], where="post",
                label=f"AP = {ap:.3f}")
        ax.axhline(positive_rate, color="grey", linestyle="--", linewidth=1, label=f"positive rate {positive_rate:.3f}")
        ax.set(xlabel="recall", ylabel="precision", xlim=(0, 1), ylim=(0, 1.02), title=title)
        ax.grid(alpha=0.3)
        ax.legend(loc="lower left")
        fig.tight_layout()
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png")
    finally:
        plt.close(fig)
    return path
