"""Known-state policy: the object's mesh and pose are known, surface grasps are ranked by a 3D
metric of the analytic labeller (the paper's known-objects experiment)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from suctionbench.config import CupConfig, LabelConfig
from suctionbench.contact import SuctionLabeller
from suctionbench.errors import InputError
from suctionbench.geometry.sampling import sample_surface_grasps

MAX_APPROACH_FROM_VERTICAL = np.radians(60.0)
"""Candidates whose approach is more than this from straight down are skipped: the arm reaches
over the table, never from below it."""


@dataclass
class RankedGrasp:
    """The chosen grasp (world frame) and its metric value."""

    point: np.ndarray
    approach: np.ndarray
    score: float
    candidates: int


def analytic_grasp(
    mesh_world: trimesh.Trimesh,
    com_world: np.ndarray,
    mass: float,
    cup: CupConfig,
    seed: int,
    *,
    metric: str = "rwr",
    candidates: int = 300,
) -> RankedGrasp:
    """Sample surface grasps on the object in its world pose and return the best by `metric`."""
    labeller = SuctionLabeller(mesh_world, LabelConfig(cup=cup), mass=mass, com=com_world)
    rng = np.random.default_rng(seed)
    points, approaches = sample_surface_grasps(mesh_world, 4 * candidates, rng)
    downward = approaches[:, 2] <= -np.cos(MAX_APPROACH_FROM_VERTICAL)
    points, approaches = points[downward][:candidates], approaches[downward][:candidates]
    if len(points) == 0:
        raise InputError("analytic policy: no surface faces the gripper")
    labels = labeller.label(points, approaches, seed, metrics=("ss", "wr", metric))
    score = labels.score(metric)
    best = int(np.lexsort((labels.score("ss"), score))[-1])
    return RankedGrasp(points[best], approaches[best], float(score[best]), len(points))
