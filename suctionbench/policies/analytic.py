"""Known-state policies: the object's mesh, pose and mass are known, and grasps are ranked by a 3D
metric of the analytic labeller (the paper's known-objects experiment).

`analytic_grasp` ranks grasps drawn on the whole mesh: the known-state upper bound. `image_candidates`
draws them where the image policies draw theirs instead (valid pixels of the depth image, with the
normals the camera gives): ranked in the true state, that is the best any scorer of an image
policy's candidates could do, so the gap between the two bounds is what the view costs and the gap
below the second is what the scoring costs. Ranked believing the density uniform
(`uniform_density_com`, `analytic-image-uniform`), the part of the scoring gap that only the
invisible mass distribution decides separates from the rest."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from suctionbench.config import CupConfig, LabelConfig
from suctionbench.contact import SuctionLabeller
from suctionbench.geometry.sampling import sample_surface_grasps
from suctionbench.policies.base import NoGraspError, Observation, SamplerConfig, scene_cloud

CANDIDATES = 300
"""Grasps ranked per plan by the known-state policies (`analytic`, `analytic-image`,
`analytic-image-uniform`)."""

MAX_APPROACH_FROM_VERTICAL = np.radians(60.0)
"""Candidates whose approach is more than this from straight down are skipped: the arm reaches
over the table, never from below it."""


@dataclass
class RankedGrasp:
    """The chosen grasp (world frame), its metric value, and the candidates it was chosen from."""

    point: np.ndarray
    approach: np.ndarray
    score: float
    candidate_points: np.ndarray
    candidate_approaches: np.ndarray
    candidate_scores: np.ndarray | None
    chosen_index: int
    quality_map: np.ndarray | None = None
    """A dense policy's q per pixel of the depth image it planned on (NaN unscored), else None."""


def surface_candidates(
    mesh_world: trimesh.Trimesh, count: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Up to `count` uniform surface grasps whose approach the arm can take (from above)."""
    points, approaches = sample_surface_grasps(mesh_world, 4 * count, rng)
    downward = approaches[:, 2] <= -np.cos(MAX_APPROACH_FROM_VERTICAL)
    if not downward.any():
        raise NoGraspError("no surface of the object faces the gripper")
    return points[downward][:count], approaches[downward][:count]


def random_surface_grasp(mesh_world: trimesh.Trimesh, seed: int) -> RankedGrasp:
    """One grasp drawn uniformly among reachable surface grasps (known shape, no ranking)."""
    rng = np.random.default_rng(seed)
    points, approaches = surface_candidates(mesh_world, 64, rng)
    pick = int(rng.integers(len(points)))
    return RankedGrasp(points[pick], approaches[pick], float("nan"), points, approaches, None, pick)


def image_candidates(observation: Observation, count: int, rng: np.random.Generator
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Up to `count` grasps (world points and approaches) drawn uniformly among the depth image's
    valid grasp pixels, as the image policies draw theirs (`SamplerConfig`'s defaults: the seed
    sampler's angle limits, normals from the 1 px smoothed image of the noisy sensor);
    NoGraspError where the image has none."""
    cloud = scene_cloud(observation, SamplerConfig())
    rows, cols = cloud.sample(count, rng)
    _, points, approaches = cloud.grasps_at(rows, cols)
    rotation, origin = observation.camera_pose[:3, :3], observation.camera_pose[:3, 3]
    return points @ rotation.T + origin, approaches @ rotation.T


def uniform_density_com(mesh_world: trimesh.Trimesh) -> np.ndarray:
    """Where the centre of mass of `mesh_world` lies if its density were uniform (its volume's
    centroid): what `analytic-image-uniform` believes in place of the true one. A jar's paste, a
    bottle's liquid or a tool's steel blade moves the true centre away from it; no depth image shows
    that, so ranking with this belief takes from the image bound what only the mass distribution
    decides."""
    return np.asarray(mesh_world.center_mass, dtype=float)


def rank_grasps(
    mesh_world: trimesh.Trimesh,
    com_world: np.ndarray,
    mass: float,
    cup: CupConfig,
    seed: int,
    points: np.ndarray,
    approaches: np.ndarray,
    *,
    metric: str = "rwr",
) -> RankedGrasp:
    """The best of the grasps (world frame) by `metric` in the true state (labelled for the pick
    episode: the disturbing wrench includes the inertial load of its peak acceleration); ties go to
    the better seal score."""
    labeller = SuctionLabeller(mesh_world, LabelConfig.for_episode(cup), mass=mass, com=com_world)
    labels = labeller.label(points, approaches, seed, metrics=("ss", "wr", metric))
    score = labels.score(metric)
    best = int(np.lexsort((labels.score("ss"), score))[-1])
    return RankedGrasp(points[best], approaches[best], float(score[best]), points, approaches, score, best)


def analytic_grasp(
    mesh_world: trimesh.Trimesh,
    com_world: np.ndarray,
    mass: float,
    cup: CupConfig,
    seed: int,
    *,
    metric: str = "rwr",
    candidates: int = CANDIDATES,
) -> RankedGrasp:
    """Sample surface grasps on the object in its world pose and return the best by `metric`
    (`rank_grasps`): the known-state upper bound."""
    points, approaches = surface_candidates(mesh_world, candidates, np.random.default_rng(seed))
    return rank_grasps(mesh_world, com_world, mass, cup, seed, points, approaches, metric=metric)
