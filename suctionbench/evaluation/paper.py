"""The Dex-Net 3.0 paper's physical results, which reports put beside the simulated ones.

Source: J. Mahler, M. Matl, X. Liu, A. Li, D. Gealy, K. Goldberg, "Dex-Net 3.0: Computing Robust
Vacuum Suction Grasp Targets in Point Clouds using a New Analytic Model and Deep Learning", IEEE
International Conference on Robotics and Automation (ICRA), 2018; arXiv:1709.06670. ABB YuMi with
a 15 mm silicone suction cup and a Primesense Carmine depth camera; 125 trials per policy on the
Basic and Typical sets, 100 on Adversarial.

Numbers are percentages as printed in the paper: Table "Performance on Novel Objects" (success rate
and average precision per policy and object set), the known-objects experiment (adversarial set,
75 trials, the top-ranked grasp of each 3D metric) and the random-grasp classification of that
experiment (AP, accuracy and Spearman rank correlation of each metric's score against success).
"""

from __future__ import annotations

CITATION = ("Mahler et al., \"Dex-Net 3.0: Computing Robust Vacuum Suction Grasp Targets in Point Clouds "
            "using a New Analytic Model and Deep Learning\", ICRA 2018")
"""How reports cite the source of these numbers."""

PAPER_RESULTS: dict[str, dict[str, tuple[int, int]]] = {
    "planarity": {"basic": (74, 81), "typical": (67, 69), "adversarial": (47, 48)},
    "centroid": {"basic": (92, 89), "typical": (78, 80), "adversarial": (38, 47)},
    "planarity-centroid": {"basic": (94, 98), "typical": (86, 94), "adversarial": (62, 64)},
    "gqcnn": {"basic": (98, 99), "typical": (82, 97), "adversarial": (58, 61)},
    "gqcnn-adv": {"basic": (77, 83), "typical": (67, 75), "adversarial": (81, 86)},
}
"""Novel objects, physical trials: policy -> set -> (success rate %, AP %). gqcnn: the Dex-Net 3.0
model trained on the training corpus; gqcnn-adv: its "GQ-CNN (ADV)", trained on the adversarial
objects only."""

PAPER_KNOWN: dict[str, tuple[int, int]] = {"pc3d": (88, 80), "ss": (89, 84), "wr": (93, 80), "rwr": (100, 92)}
"""Known objects (adversarial set, shape and pose known, top-ranked grasp per metric): (AP %, success %)."""

PAPER_RANDOM: dict[str, tuple[int, int, float]] = {
    "pc3d": (71, 68, 0.36), "ss": (75, 74, 0.49), "wr": (78, 77, 0.52), "rwr": (80, 75, 0.62),
}
"""Known objects, random grasps classified by each metric's score: (AP %, accuracy %, Spearman)."""

PAPER_PLAN_TIME_S = 3.0
"""The paper's Dex-Net 3.0 GQ-CNN policy: about 3 s to plan a grasp (GeForce 980 desktop)."""
