"""Point-cloud heuristics of the paper's novel-object experiment (Dex-Net 3.0, "Performance on Novel
Objects"): random, centroid, planarity and planarity-centroid.

All four plan from the same candidates: `HeuristicConfig.num_candidates` distinct pixels drawn
uniformly (from the `rng` passed to `plan`) among the valid grasp pixels of `base.scene_cloud`,
i.e. object pixels whose approach (minus the smoothed-image surface normal) lies within 60 deg of
the optical axis and within 80 deg of straight down, the seed sampler of the GQ-CNN policy. Each
heuristic maps its metric monotonically into q in [0, 1] and returns the candidate with the
highest q (the first one on ties).

- `random`: one valid pixel, uniformly; q = NaN (it has no quality).
- `centroid`: the paper's "inverse distance to the object centroid". The centroid is the mean of
  the object's observed points (the segmented point cloud). With d the distance from a candidate's
  point to it, q = s / (s + d), s = the cup radius: 1 on the centroid, 1/2 a cup radius away.
- `planarity`: "the inverse sum of squared errors from an approach plane for points within a disc
  with radius equal to that of the suction cup". The plane passes through the candidate point,
  normal to its approach; the points are the image points whose distance from the approach axis
  is at most the cup radius, all read from the 1 px-smoothed image (`base.disc_errors`). With SSE
  that sum (m^2), q = 1 / (1 + SSE / `planarity_scale`): the paper's inverse SSE, squashed into
  [0, 1] by x / (1 + x) of x = `planarity_scale` / SSE.
- `planarity-centroid`: "the inverse distance to the centroid for sufficiently planar patches".
  A patch is sufficiently planar when the root-mean-square distance of its disc points from the
  approach plane, sqrt(SSE / count), is at most `max_planar_rms` (1.5 mm: the RMS, unlike the sum,
  does not depend on how many pixels the disc covers, i.e. on camera distance and resolution).
  Planar candidates get q = 1/2 + q_centroid / 2 and the others q = q_planarity / 2, so every
  planar candidate ranks above every non-planar one, and with no planar candidate at all the
  policy falls back to planarity.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from suctionbench.config import CUP_DEFAULT
from suctionbench.errors import InputError
from suctionbench.policies.base import (
    GraspAction,
    Observation,
    SamplerConfig,
    SceneCloud,
    configured,
    disc_errors,
    scene_cloud,
)


@dataclass(frozen=True)
class HeuristicConfig:
    """Parameters of the point-cloud heuristics."""

    num_candidates: int = 250
    """Candidate pixels scored per plan (the GQ-CNN policy's seed count, so that every policy sees
    the same number of uniformly drawn candidates before ranking)."""

    sampler: SamplerConfig = field(default_factory=SamplerConfig)
    """Valid grasp pixels and normal estimation (gqcnn's Dex-Net 3.0 seed sampler)."""

    cup_radius: float = CUP_DEFAULT.radius
    """Radius (m) of the disc whose planarity is measured (the paper's 15 mm cup: 7.5 mm); also
    the distance at which the centroid heuristic's q is 1/2."""

    planarity_scale: float = 1e-5
    """Sum of squared plane errors (m^2) at which the planarity q is 1/2: about 100 disc points
    0.3 mm off the plane. Rendered at 0.55 m with the Primesense preset (no noise), a flat face
    gives ~1e-13, the curved side of typical/mug_classic lying down 1.2-1.8e-5, a disc over a box
    edge or a gear's teeth 1e-4 to 1e-1."""

    max_planar_rms: float = 0.0015
    """Largest RMS distance (m) of the disc points from the approach plane for a patch to count as
    planar in planarity-centroid: 1.5 mm, just below the ~1.7 mm (10 % of the 16.8 mm spring rest
    length) that the default cup's lip may stretch to follow the surface. Sensor noise counts too:
    on a flat box top rendered at 0.55 m, 84 % of the candidates pass without noise and 72 % with
    the simulated sensor's 1.2 mm per-pixel noise (whose main effect is a noisier normal, hence a
    tilted approach plane); on adversarial/narrow_gear 42 % and 31 %."""

    def __post_init__(self) -> None:
        n = self.num_candidates
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise InputError(f"heuristic config: num_candidates = {n!r} must be a positive integer")
        if not isinstance(self.sampler, SamplerConfig):
            raise InputError(f"heuristic config: sampler = {self.sampler!r} must be a SamplerConfig")
        for key in ("cup_radius", "planarity_scale", "max_planar_rms"):
            value = getattr(self, key)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise InputError(f"heuristic config: {key} = {value!r} must be a positive number")


def centroid_quality(distance: np.ndarray, scale: float) -> np.ndarray:
    """Inverse distance mapped into (0, 1]: scale / (scale + d)."""
    return scale / (scale + np.asarray(distance, dtype=float))


def planarity_quality(sse: np.ndarray, scale: float) -> np.ndarray:
    """Inverse sum of squared errors mapped into (0, 1]: 1 / (1 + SSE / scale)."""
    return 1.0 / (1.0 + np.asarray(sse, dtype=float) / scale)


class _HeuristicPolicy:
    """Shared plan(): sample candidates, score them (`_score`), return the best."""

    name: ClassVar[str]

    def __init__(self, config: HeuristicConfig | None = None, **overrides: Any) -> None:
        self.config = configured(config or HeuristicConfig(), overrides)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.config})"

    def _score(
        self, cloud: SceneCloud, rows: np.ndarray, cols: np.ndarray, points: np.ndarray, approaches: np.ndarray
    ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        raise NotImplementedError

    def _count(self) -> int:
        return self.config.num_candidates

    def plan(self, observation: Observation, rng: np.random.Generator) -> GraspAction:
        start = time.perf_counter()
        cloud = scene_cloud(observation, self.config.sampler)
        rows, cols = cloud.sample(self._count(), rng)
        pixels, points, approaches = cloud.grasps_at(rows, cols)
        q, extra = self._score(cloud, rows, cols, points, approaches)
        best = int(np.nanargmax(q)) if np.isfinite(q).any() else 0
        candidates = {"pixels": pixels, "points": points, "approaches": approaches, "q": q, **extra}
        return GraspAction(
            point=points[best].copy(), approach=approaches[best].copy(), pixel=pixels[best].copy(),
            q=float(q[best]), camera_pose=observation.camera_pose.copy(), policy=self.name,
            candidates=candidates,
            info={"plan_time": time.perf_counter() - start, "relaxed": cloud.relaxed, "chosen": best},
        )


class RandomPolicy(_HeuristicPolicy):
    """One valid object pixel drawn uniformly; approach = minus the surface normal; q = NaN."""

    name = "random"

    def _count(self) -> int:
        return 1

    def _score(self, cloud, rows, cols, points, approaches):
        return np.full(len(rows), np.nan), {}


class CentroidPolicy(_HeuristicPolicy):
    """The candidate nearest the object's point-cloud centroid (candidates also log
    `centroid_distance` (N,) in metres)."""

    name = "centroid"

    def _score(self, cloud, rows, cols, points, approaches):
        distance = np.linalg.norm(points - cloud.object_points.mean(axis=0), axis=1)
        return centroid_quality(distance, self.config.cup_radius), {"centroid_distance": distance}


class PlanarityPolicy(_HeuristicPolicy):
    """The candidate whose cup disc is flattest (candidates also log `sse` (N,) m^2 and `count` (N,))."""

    name = "planarity"

    def _score(self, cloud, rows, cols, points, approaches):
        sse, count = disc_errors(cloud, rows, cols, approaches, self.config.cup_radius)
        return planarity_quality(sse, self.config.planarity_scale), {"sse": sse, "count": count}


class PlanarityCentroidPolicy(_HeuristicPolicy):
    """The sufficiently planar candidate nearest the centroid, else the flattest (candidates also
    log `sse`, `count`, `rms` (m), `planar` (bool) and `centroid_distance`)."""

    name = "planarity-centroid"

    def _score(self, cloud, rows, cols, points, approaches):
        cfg = self.config
        sse, count = disc_errors(cloud, rows, cols, approaches, cfg.cup_radius)
        rms = np.sqrt(sse / np.maximum(count, 1))
        planar = rms <= cfg.max_planar_rms
        distance = np.linalg.norm(points - cloud.object_points.mean(axis=0), axis=1)
        q = np.where(
            planar,
            0.5 + 0.5 * centroid_quality(distance, cfg.cup_radius),
            0.5 * planarity_quality(sse, cfg.planarity_scale),
        )
        return q, {"sse": sse, "count": count, "rms": rms, "planar": planar, "centroid_distance": distance}
