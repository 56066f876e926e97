"""Grasp-quality metrics on 3D meshes, one registry: the paper's PC3D, SS, WR and RWR.

Every metric maps labelled grasps to a score in [0, 1], higher meaning more likely to succeed, so
all of them can be ranked, thresholded at 0.5 for accuracy, and scored by average precision.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from suctionbench.config import LabelConfig
from suctionbench.contact.seal import SealResult


@dataclass
class GraspLabels:
    """Everything the labeller computed for a batch of N grasps."""

    points: np.ndarray
    """(N, 3) target points."""

    approaches: np.ndarray
    """(N, 3) unit approach directions."""

    seal: SealResult
    """Nominal seal-model outcome."""

    wr: np.ndarray
    """(N,) nominal wrench resistance (seal, and resist the weight - plus the lift and transport
    loads when the perturbation model has an inertial load - with the vacuum the seal holds; no
    perturbation)."""

    rwr: np.ndarray | None
    """(N,) robust wrench resistance, the fraction of J perturbed samples that seal and resist."""

    samples: np.ndarray | None
    """(N, J) the per-sample outcomes behind `rwr`."""

    com: np.ndarray
    """(3,) centre of mass used."""

    config: LabelConfig
    """Cup, seal, perturbation and metric configuration used."""

    @property
    def centroid_distance(self) -> np.ndarray:
        """Distance (m) from the surface target to the centre of mass (inf if no surface there)."""
        d = np.linalg.norm(self.seal.surface_point - self.com, axis=1)
        return np.where(np.isfinite(d), d, np.inf)

    def score(self, metric: str) -> np.ndarray:
        """Scores of one registered metric."""
        return METRICS[metric].score(self)


def planarity_centroid(labels: GraspLabels) -> np.ndarray:
    """PC3D: 1 / (1 + d / L) on sufficiently planar patches, 0 elsewhere (d: distance to COM)."""
    cfg = labels.config.metric
    planar = labels.seal.planarity_rms <= cfg.planarity_rms_max
    return np.where(planar, 1.0 / (1.0 + labels.centroid_distance / cfg.centroid_length), 0.0)


def spring_stretch(labels: GraspLabels) -> np.ndarray:
    """SS: 1 / (1 + s / s_max) for max spring stretch s; 0.5 exactly at the stretch limit."""
    limit = labels.config.cup.stretch_limit
    return 1.0 / (1.0 + labels.seal.max_stretch / limit)


def wrench_resistance(labels: GraspLabels) -> np.ndarray:
    """WR: 1 if the nominal grasp seals and resists its load (see GraspLabels.wr), else 0."""
    return labels.wr.astype(float)


def robust_wrench_resistance(labels: GraspLabels) -> np.ndarray:
    """RWR: the robust label (requires the labeller to have run the robust model)."""
    if labels.rwr is None:
        raise ValueError("rwr was not computed for these labels")
    return labels.rwr


@dataclass(frozen=True)
class Metric:
    """A registered grasp-quality metric."""

    name: str
    """Short name used on the command line and in files."""

    description: str
    """One-line description for help texts and reports."""

    score: Callable[[GraspLabels], np.ndarray]
    """Function from labels to scores in [0, 1]."""


METRICS: dict[str, Metric] = {
    m.name: m
    for m in (
        Metric("pc3d", "planarity-centroid on the 3D mesh", planarity_centroid),
        Metric("ss", "maximum spring stretch of the seal model", spring_stretch),
        Metric("wr", "wrench resistance without perturbations", wrench_resistance),
        Metric("rwr", "robust wrench resistance (Monte-Carlo)", robust_wrench_resistance),
    )
}
"""All metrics by name, in the paper's order."""
