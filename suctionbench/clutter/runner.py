"""One bin-picking episode end to end: fill the bin, then observe, plan, attempt, until the bin is
clear, K attempts in a row have failed, or the attempt limit is reached. Every attempt is labelled
analytically on the object under the grasp point in its true pose (as single-object trials are),
carrying what its neighbours press onto it (`BinEpisode.loaded`), so the labels, the policy's q
and the simulated outcome sit side by side."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from suctionbench.clutter.episode import AttemptResult, BinEpisode
from suctionbench.clutter.planning import analytic_in_bin, plan_in_regions
from suctionbench.clutter.scene import BIN_CAMERA, PickBinConfig, build_bin_scene
from suctionbench.clutter.tasks import BinTask
from suctionbench.config import CUP_DEFAULT, CupConfig
from suctionbench.objects.registry import list_objects, load_object
from suctionbench.policies.base import NoGraspError, Observation
from suctionbench.sensing.camera import body_image, resolve_camera
from suctionbench.sensing.camera_pose import sample_camera_pose
from suctionbench.sensing.segmentation import segment_regions, workspace_mask
from suctionbench.sim.pick import KNOWN_STATE_POLICIES, NO_LABELS, cached_policy, grasp_labels

MASK_SOURCES = ("depth", "oracle")
"""Where the object regions come from: segmentation of the depth image, or the renderer's
instance masks (an oracle: what perfect segmentation would give)."""


@dataclass
class BinRequest:
    """Everything that defines one bin episode."""

    task: BinTask
    """The task (object sets, counts, K)."""

    trial: int = 0
    """Which bin of the task (its objects, their drops, the camera pose and the policy's seeds)."""

    policy: str = "planarity-centroid"
    """Image policy spec (a built-in name, a plug-in, PATH.py:FACTORY) or a known-state policy
    ('analytic', 'random-surface')."""

    policy_args: dict[str, Any] = field(default_factory=dict)
    """Options of the image policy's factory."""

    model: str | None = None
    """GQ-CNN model directory for the policies that read one (default: the shipped model)."""

    masks: str = "depth"
    """Object regions from 'depth' segmentation or the 'oracle' instance masks."""

    per_region: bool | None = None
    """Plan once per region and keep the best (default: for built-in policies; a plug-in gets the
    whole bin as its observation)."""

    cup: CupConfig = field(default_factory=lambda: CUP_DEFAULT)
    """Cup preset, shared by the simulated cup and the labels."""

    camera: str = "primesense"
    """Camera preset or intrinsics TOML."""

    observation_noise: bool = True
    """The simulated sensor's axial depth noise."""

    keys: list[str] | None = None
    """The bin's objects (SET/NAME, drop order) instead of the task's draw."""


class BinRunner:
    """Builds one bin's scene and runs its episode."""

    def __init__(self, request: BinRequest):
        from suctionbench.errors import InputError
        from suctionbench.policies.plugins import builtin_name

        if request.masks not in MASK_SOURCES:
            raise InputError(f"--masks '{request.masks}': expected one of {', '.join(MASK_SOURCES)}")
        self.request = request
        task = request.task
        if request.keys is None:
            available = [f"{s}/{r.name}" for s in task.sets for r in list_objects(s)]
            if not available:
                raise InputError(f"task '{task.name}': its sets {', '.join(task.sets)} hold no objects")
            self.keys = task.draw(request.trial, available)
        else:
            self.keys = list(request.keys)
        self.records = [load_object(k) for k in self.keys]
        self.intrinsics = resolve_camera(request.camera)
        self.bin = PickBinConfig()
        rng = np.random.default_rng((task.seed, request.trial, 1))
        centre = np.array([*self.bin.centre, 0.0])
        self.camera_pose = sample_camera_pose(rng, centre, BIN_CAMERA.for_camera(self.intrinsics))
        self.scene = build_bin_scene(self.records, request.cup, self.intrinsics, self.camera_pose, bin_config=self.bin)
        self.episode = BinEpisode(self.scene, self.bin)
        self.objects = {b: (r, r.mesh()) for b, r in zip(self.episode.bodies, self.records, strict=True)}
        self.known_state = request.policy in KNOWN_STATE_POLICIES
        self.per_region = (bool(builtin_name(request.policy)) if request.per_region is None
                           else request.per_region) and not self.known_state
        self.observation: Observation | None = None
        self.failed: list[np.ndarray] = []
        """World points of the episode's failed grasps, which the built-in planning passes over
        (`clutter.planning.AVOID_RADIUS`)."""

    # -- sensing ----------------------------------------------------------------------------------
    def observe(self, attempt: int) -> tuple[Observation, list[np.ndarray]]:
        """The overhead depth image (with noise), the bin's pixels as its mask, and the object regions."""
        from suctionbench.sensing.camera import DepthRenderer
        from suctionbench.sensing.noise import apply_axial_noise

        req, ep = self.request, self.episode
        with DepthRenderer(self.scene.model, self.intrinsics) as renderer:
            depth = renderer.render(ep.data, self.scene.camera)
            segmentation = renderer.segment(ep.data, self.scene.camera) if req.masks == "oracle" else None
        if req.observation_noise:
            depth = apply_axial_noise(depth, np.random.default_rng((req.task.seed, req.trial, attempt, 2)))
        inside = workspace_mask(depth, self.intrinsics, self.camera_pose, *self.bin.workspace())
        if segmentation is None:
            regions = segment_regions(depth, self.intrinsics, inside)
        else:
            regions = self._instance_masks(segmentation, depth > 0)
        observation = Observation(depth=depth, intrinsics=self.intrinsics, camera_pose=self.camera_pose, mask=inside)
        return observation, regions

    def _instance_masks(self, segmentation: np.ndarray, has_depth: np.ndarray) -> list[np.ndarray]:
        """One mask per object in the bin from the renderer's segmentation, largest first."""
        body = body_image(self.scene.model, segmentation)
        masks = [(body == b) & has_depth for b in self.episode.present]
        masks = [m for m in masks if m.sum() >= 20]
        return sorted(masks, key=lambda m: -int(m.sum()))

    # -- one attempt --------------------------------------------------------------------------------
    def plan(self, attempt: int) -> tuple[np.ndarray, np.ndarray, float | None, dict[str, Any]]:
        """World grasp point and approach, the policy's q, and what the choice saw; NoGraspError."""
        req = self.request
        seed = int(np.random.default_rng((req.task.seed, req.trial, attempt, 3)).integers(2**31))
        if self.known_state:
            if req.policy == "analytic":
                chosen, _ = analytic_in_bin(self.episode, {b: self.objects[b] for b in self.episode.present},
                                            req.cup, seed, avoid=self._avoid())
                return chosen.point, chosen.approach, chosen.score, {}
            from suctionbench.policies.analytic import random_surface_grasp

            rng = np.random.default_rng(seed)
            body = self.episode.present[int(rng.integers(len(self.episode.present)))]
            record, mesh = self.objects[body]
            chosen = random_surface_grasp(self.episode.posed_mesh(body, mesh)[0], seed)
            return chosen.point, chosen.approach, None, {}
        policy = cached_policy(req.policy, req.model, req.policy_args)
        self.observation, regions = self.observe(attempt)
        action, info = plan_in_regions(policy, self.observation, regions, np.random.default_rng(seed),
                                       per_region=self.per_region, avoid=self._avoid())
        q = float(action.q)
        return action.point_world, action.approach_world, (None if np.isnan(q) else q), info

    def _avoid(self) -> np.ndarray | None:
        return np.array(self.failed) if self.failed else None

    def label(self, body: int, point: np.ndarray, approach: np.ndarray, attempt: int) -> dict[str, Any]:
        """Analytic labels of the grasp on object `body`, the one under it (NO_LABELS for -1: none)."""
        if body < 0:
            return dict(NO_LABELS)
        record, mesh = self.objects[body]
        world_mesh, com = self.episode.posed_mesh(body, mesh)
        mass, com = self.episode.loaded(body, record.mass, com)
        seed = int(np.random.default_rng((self.request.task.seed, self.request.trial, attempt, 4)).integers(2**31))
        return grasp_labels(world_mesh, com, mass, self.request.cup, point, approach, seed,
                            self.episode.planned_transport(point, approach))

    def run(self, log: Any = None) -> dict[str, Any]:
        """Fill the bin and pick until it is clear, K failures in a row, or the attempt limit; the
        JSON-ready record of the bin."""
        req, ep, task = self.request, self.episode, self.request.task
        ep.reset(np.random.default_rng((task.seed, req.trial, 0)))
        self.failed = []
        start = {"objects": self.keys, "in_bin": [ep.names[b] for b in ep.present], "spilled": list(ep.spilled)}
        attempts: list[dict[str, Any]] = []
        failures_in_row = 0
        limit = task.attempts_for(len(ep.present))
        ended = "clear"
        while ep.present:
            if ep.placement_error:
                ended = "unstable"
                break
            if failures_in_row >= task.max_failures:
                ended = "failures"
                break
            if len(attempts) >= limit:
                ended = "attempt_limit"
                break
            record = self.attempt(len(attempts))
            attempts.append(record)
            if log is not None:
                log(record)
            failures_in_row = 0 if record["success"] else failures_in_row + 1
        count = len(start["in_bin"])
        transported = sum(len(a["transported"]) for a in attempts)
        return {
            "task": task.name, "trial": req.trial, "seed": task.seed, "policy": req.policy, "masks": req.masks,
            **start, "ended": ended, "attempts": attempts, "transported": transported,
            "clearance": transported / count if count else None,
            "successes": sum(bool(a["success"]) for a in attempts), "unsettled": ep.unsettled,
        }

    def attempt(self, index: int) -> dict[str, Any]:
        """Plan (the request's policy) and execute attempt `index`; its record."""
        plan_start = time.perf_counter()
        try:
            point, approach, q, info = self.plan(index)
        except NoGraspError as exc:
            from suctionbench.sim.episode_config import EpisodeResult

            result = AttemptResult(EpisodeResult.not_executed("no_grasp", str(exc)), None, None)
            return self._record(index, None, None, dict(NO_LABELS), time.perf_counter() - plan_start, {}, result)
        return self.attempt_grasp(index, point, approach, q, info, time.perf_counter() - plan_start)

    def attempt_grasp(self, index: int, point: np.ndarray, approach: np.ndarray, q: float | None = None,
                      info: dict[str, Any] | None = None, plan_time: float = 0.0) -> dict[str, Any]:
        """Label and execute a world grasp as attempt `index` (an agent's, or the policy's); its record."""
        ep = self.episode
        approach = np.asarray(approach, float) / np.linalg.norm(approach)
        target = ep.target_at(point, approach)
        labels = self.label(target, point, approach, index)
        result = ep.attempt(point, approach, target)
        if not result.success:
            self.failed.append(np.asarray(point, float))
        grasp = [*np.asarray(point, float).tolist(), *approach.tolist()]
        return self._record(index, grasp, q, labels, plan_time, info or {}, result)

    def _record(self, index: int, grasp: list[float] | None, q: float | None, labels: dict[str, Any],
                plan_time: float, info: dict[str, Any], result: AttemptResult) -> dict[str, Any]:
        episode = result.episode.to_dict()
        return {
            "attempt": index, "grasp_world": grasp, "policy_q": q, **labels, "plan_time": plan_time, **info,
            "target": result.target, "held": result.held, "transported": result.transported, "lost": result.lost,
            "remaining": len(self.episode.present), **episode,
        }


def plans_of(attempt: dict[str, Any]) -> int:
    """How many times the policy planned for an attempt: once per region it planned on (per-region
    planning), once otherwise (a plug-in on the whole bin, a known-state policy)."""
    if attempt.get("region") is None and not attempt.get("region_q"):
        return 1
    return int(attempt.get("planned") or attempt.get("regions") or 1)


def bin_metrics(bins: list[dict[str, Any]], compute: dict[str, float]) -> dict[str, Any]:
    """Per-task figures over bins: clearance (objects removed / objects in the bins), success per
    attempt, picks per hour (objects removed over simulated motion plus the modelled compute of
    each attempt: one depth frame, `compute["sensing_s"]`, and `compute["planning_s"]` per plan,
    `plans_of`), mean attempts per object removed, and failure reasons."""
    attempts = [a for b in bins for a in b["attempts"]]
    objects = sum(len(b["in_bin"]) for b in bins)
    transported = sum(b["transported"] for b in bins)
    successes = sum(bool(a["success"]) for a in attempts)
    motion = sum(float(a["sim_time"]) for a in attempts)
    cycle = motion + sum(compute["sensing_s"] + compute["planning_s"] * plans_of(a) for a in attempts)
    reasons: dict[str, int] = {}
    for a in attempts:
        if a["failure"]:
            reasons[a["failure"]] = reasons.get(a["failure"], 0) + 1
    robust = [a for a in attempts if a.get("label_rwr") is not None and a["label_rwr"] > 0.5]
    return {
        "bins": len(bins), "objects": objects, "transported": transported,
        "clearance": round(transported / objects, 4) if objects else None,
        "attempts": len(attempts), "success_per_attempt": round(successes / len(attempts), 4) if attempts else None,
        "picks_per_hour": round(3600.0 * transported / cycle, 1) if cycle > 0 else None,
        "attempts_per_object": round(len(attempts) / transported, 3) if transported else None,
        "label_precision": (round(sum(bool(a["success"]) for a in robust) / len(robust), 4) if robust else None),
        "failures": dict(sorted(reasons.items())),
        "ended": {k: sum(b["ended"] == k for b in bins) for k in sorted({b["ended"] for b in bins})},
    }
