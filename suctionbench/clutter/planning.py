"""Choosing a grasp in a cluttered bin.

Image policies (`plan_in_regions`): the single-object policies (heuristics, GQ-CNN, dense) read
one object: its centroid, its planarity, its object context. In clutter they plan once per object
region of the image (`sensing.segmentation`, or the renderer's instance masks as an oracle), each
region given as the observation's mask, and the best grasp by the policy's own q wins; a policy
without a q (random) picks a region at random. A user's plug-in policy gets the whole bin instead
(`per_region=False`): the observation's mask is every pixel inside the bin, and it plans as it
likes.

Known state (`analytic_in_bin`): the true meshes and poses of every object in the bin; surface
grasps of each ranked by the robust wrench resistance with the load its neighbours press onto it
(`BinEpisode.loaded`), as the single-object analytic policy ranks them,
and the best whose cup path is clear: rays along the approach from the lip's rim and the axis, back
over the pregrasp distance, must meet nothing but the target (neither a neighbour nor a wall).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import mujoco
import numpy as np

from suctionbench.policies.base import GraspAction, NoGraspError, Observation
from suctionbench.sim.cup import SURFACE_GROUP

AVOID_RADIUS = 0.02
"""A grasp within this distance (m) of a grasp that failed earlier in the episode is passed over
while another region offers one (the pile may not have changed there: the same grasp would fail
the same way)."""


def near_any(point: np.ndarray, avoid: np.ndarray | None, radius: float = AVOID_RADIUS) -> bool:
    """Whether world `point` lies within `radius` of any row of `avoid` (K, 3)."""
    return avoid is not None and len(avoid) > 0 and bool(np.min(np.linalg.norm(avoid - point, axis=1)) < radius)


def plan_in_regions(policy: Any, observation: Observation, regions: list[np.ndarray], rng: np.random.Generator,
                    *, per_region: bool = True, max_regions: int = 10,
                    avoid: np.ndarray | None = None) -> tuple[GraspAction, dict[str, Any]]:
    """The policy's grasp in the bin and what the choice saw ({"regions", "region", "region_q",
    "avoided", "planned": how many regions it planned on}): the best region's grasp by q, passing
    over grasps near `avoid` (world points of failed grasps, `AVOID_RADIUS`) unless no region has
    another. NoGraspError when no region yields a grasp."""
    if not per_region:
        return policy.plan(observation, rng), {"regions": len(regions), "region": None, "region_q": [], "avoided": 0,
                                               "planned": 1}
    if not regions:
        raise NoGraspError("no object region in the bin (empty bin or nothing above its floor)")
    regions = regions[:max_regions]
    streams = rng.spawn(len(regions))
    qs: list[float | None] = [None] * len(regions)
    found: list[tuple[int, GraspAction]] = []
    planned = 0
    for i in rng.permutation(len(regions)):
        planned += 1
        try:
            action = policy.plan(replace(observation, mask=regions[i]), streams[i])
        except NoGraspError:
            continue
        q = float(action.q)
        qs[i] = None if math.isnan(q) else round(q, 4)
        found.append((int(i), action))
        if math.isnan(q) and not near_any(action.point_world, avoid):
            break  # a policy without a quality: the first region, in random order, that yields a grasp
    if not found:
        raise NoGraspError(f"no grasp in any of the {len(regions)} object regions")
    fresh = [(i, a) for i, a in found if not near_any(a.point_world, avoid)]
    pool = fresh or found

    def quality(item: tuple[int, GraspAction]) -> float:
        q = float(item[1].q)
        return -math.inf if math.isnan(q) else q

    index, best = max(pool, key=quality)  # max keeps the first of equals (the permutation's order)
    return best, {"regions": len(regions), "region": index, "region_q": qs, "avoided": len(found) - len(fresh),
                  "planned": planned}


WRIST_RING = (0.035, 0.10, 0.30)
"""(radius, start, end) m of the second ring of rays `path_is_clear` casts: the YuMi's wrist links
(about 7 cm across) behind the tool, from the flange (the tool is 10 cm long,
`sim.cup.SimCupConfig.tool_length`) to 30 cm back from the grasp."""


def path_is_clear(model: mujoco.MjModel, data: mujoco.MjData, point: np.ndarray, approach: np.ndarray,
                  target: int, radius: float, length: float, rays: int = 8) -> bool:
    """Whether the gripper's path to a grasp is free: rays back from the grasp along minus the
    approach - from the axis and the lip's rim circle (`radius`) over `length` (the cup and its
    tool), and from the wrist's ring (`WRIST_RING`) - meet no geom but the target body's (static
    geometry such as walls included)."""
    approach = np.asarray(approach, float) / np.linalg.norm(approach)
    a = np.cross(approach, [1.0, 0.0, 0.0])
    if np.linalg.norm(a) < 1e-6:
        a = np.cross(approach, [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(approach, a)
    back = -approach
    phi = 2.0 * np.pi * np.arange(rays) / rays
    ring = np.outer(np.cos(phi), a) + np.outer(np.sin(phi), b)
    point = np.asarray(point, float)
    wrist_radius, wrist_start, wrist_end = WRIST_RING
    casts = [(point, length)] + [(point + radius * r, length) for r in ring]
    casts += [(point + wrist_start * back + wrist_radius * r, wrist_end - wrist_start) for r in ring]
    group = np.zeros(6, dtype=np.uint8)  # world geometry (group 0) and the objects' collision parts; not visual (2)
    group[[0, SURFACE_GROUP]] = 1
    geom = np.zeros(1, dtype=np.int32)
    for start, reach in casts:  # start 2 mm off, towards the gripper
        dist = mujoco.mj_ray(model, data, start + 0.002 * back, back, group, 1, target, geom)
        if 0 <= dist <= reach:
            return False
    return True


def analytic_in_bin(episode: Any, objects: dict[int, tuple[Any, Any]], cup: Any, seed: int, *, metric: str = "rwr",
                    candidates: int = 200, clear_length: float = 0.08,
                    avoid: np.ndarray | None = None) -> tuple[Any, int]:
    """The known-state grasp in the bin: every object's best collision-free surface grasp by
    `metric` (`policies.analytic.analytic_grasp`'s ranking), and the best of those; with the body
    it is on. `objects`: body -> (ObjectRecord, its surface mesh in its own frame); grasps near
    `avoid` (failed ones) are passed over. NoGraspError when no object has a clear grasp."""
    from suctionbench.policies.analytic import analytic_grasp

    best, best_body = None, -1
    for body in episode.present:
        record, own_mesh = objects[body]
        mesh, com = episode.posed_mesh(body, own_mesh)
        mass, com = episode.loaded(body, record.mass, com)  # with what rests on it
        try:
            ranked = analytic_grasp(mesh, com, mass, cup, seed, metric=metric, candidates=candidates)
        except NoGraspError:
            continue
        scores = ranked.candidate_scores
        for i in np.argsort(-scores, kind="stable")[:20]:
            point, approach = ranked.candidate_points[i], ranked.candidate_approaches[i]
            if near_any(point, avoid):
                continue
            if path_is_clear(episode.model, episode.data, point, approach, body, cup.radius, clear_length):
                if best is None or scores[i] > best.score:
                    best = replace(ranked, point=point, approach=approach, score=float(scores[i]), chosen_index=int(i))
                    best_body = body
                break
    if best is None:
        raise NoGraspError("no object in the bin has a surface grasp with a clear path")
    return best, best_body
