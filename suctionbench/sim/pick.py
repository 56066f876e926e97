"""One pick, end to end: build the scene for an object, place it, choose the grasp, run the
episode, and label the executed grasp analytically in the true state (so simulation and model
can be compared grasp by grasp)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from suctionbench.config import CUP_DEFAULT, CupConfig, LabelConfig, PerturbationConfig
from suctionbench.contact import SuctionLabeller
from suctionbench.contact.metrics import METRICS
from suctionbench.errors import InputError
from suctionbench.objects.build import ObjectRecord
from suctionbench.objects.registry import load_object
from suctionbench.policies.base import (
    IMAGE_KNOWN_STATE_POLICIES,
    KNOWN_STATE_POLICIES,
    UNIFORM_DENSITY_POLICIES,
    NoGraspError,
)
from suctionbench.sensing.camera import resolve_camera
from suctionbench.sensing.camera_pose import CameraPoseConfig, sample_camera_pose
from suctionbench.sim.cup import SIM_CUP_DEFAULT, SimCupConfig
from suctionbench.sim.episode import PickEpisode
from suctionbench.sim.episode_config import EpisodeConfig, EpisodeResult
from suctionbench.sim.scene import SceneConfig, build_scene

NO_LABELS: dict[str, Any] = dict.fromkeys(("label_seal", "label_seal_failure", "label_wr", "label_rwr",
                                           "label_scores"))
"""The label fields of a record when no grasp was executed (`PickRunner.label_grasp` fills them)."""

PLACEMENTS = ("drop", "stable")
"""How the object is placed: dropped from a random orientation, or in its most probable stable pose."""


@dataclass
class PickRequest:
    """Everything that defines one pick episode."""

    object_key: str
    """SET/NAME of the object."""

    seed: int = 0
    """Seed of the placement, camera pose and policy."""

    grasp: np.ndarray | None = None
    """Grasp (x, y, z, vx, vy, vz) in the object's own frame; None: use `policy`."""

    policy: str = "analytic"
    """Policy choosing the grasp when none is given (known-state: `KNOWN_STATE_POLICIES`), or any policy spec
    `suctionbench.policies.plugins` loads (a plug-in name, PATH.py:FACTORY, package.module:FACTORY)."""

    policy_args: dict[str, Any] = field(default_factory=dict)
    """Keyword options of the image policy's factory (`--policy-arg key=value`)."""

    placement: str = "drop"
    """'drop' (random orientation, settled) or 'stable' (most probable stable pose at the centre)."""

    cup: CupConfig = field(default_factory=lambda: CUP_DEFAULT)
    """Cup preset, shared by the simulated cup and the analytic label."""

    camera: str = "primesense"
    """Camera preset of the overhead camera."""

    episode: EpisodeConfig = field(default_factory=EpisodeConfig)
    """Timing and geometry of the pick."""

    sim_cup: SimCupConfig = SIM_CUP_DEFAULT
    """What the simulation adds to the cup: the compliant, leak-aware cup (default) or
    `SimCupConfig.rigid()`, the speed reference of `bench episode`."""

    record: ObjectRecord | None = None
    """An object record to use instead of looking up `object_key` (e.g. a freshly built one)."""

    model: str | None = None
    """GQ-CNN model directory for the gqcnn policy (default: the shipped model)."""

    metric: str = "rwr"
    """3D metric the known-state analytic policy ranks by: rwr, wr, ss or pc3d."""

    stable_pose: int = 0
    """Which stable pose (0 = most probable) the 'stable' placement uses."""

    observation_noise: bool = True
    """Apply the simulated sensor's axial noise (sensing.noise.AxialNoiseConfig) to observations."""


_POLICY_CACHE: dict[tuple[str, str | None, str], Any] = {}
"""Image policies by (spec, model directory, options), built once per process."""


def cached_policy(spec: str, model: str | None, options: dict[str, Any]) -> Any:
    """The image policy a spec names with `options` (and the GQ-CNN `model` for the policies that
    read one), built once per process: policies are stateless between plans, models load once."""
    from suctionbench.policies.base import MODEL_POLICIES, make_policy
    from suctionbench.policies.plugins import canonical_spec

    key = (spec, model, repr(sorted(options.items())))
    if key not in _POLICY_CACHE:
        kwargs = dict(options)
        if canonical_spec(spec) in MODEL_POLICIES and model:
            kwargs["model"] = model
        _POLICY_CACHE[key] = make_policy(spec, **kwargs)
    return _POLICY_CACHE[key]


def _pose(position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """4x4 transform from a position and a flat 3x3 rotation."""
    pose = np.eye(4)
    pose[:3, :3] = np.asarray(rotation).reshape(3, 3)
    pose[:3, 3] = position
    return pose


def grasp_labels(mesh: Any, com: np.ndarray, mass: float, cup: CupConfig, point: np.ndarray, approach: np.ndarray,
                 seed: int, transport: tuple[np.ndarray, float, float] | None = None) -> dict[str, Any]:
    """The label fields of a trial record (`NO_LABELS`' keys) for one world grasp on an object
    whose world mesh, centre of mass and mass are given, labelled for the pick episode's loads:
    with its planned `transport` (world direction, duration, length: `PickEpisode.planned_transport`)
    where known, else a transport of unknown direction and length."""
    extra = {} if transport is None else {
        "transport_direction": tuple(float(v) for v in transport[0]), "transport_time": float(transport[1]),
        "transport_length": float(transport[2]), "transport_time_max": None}
    config = LabelConfig(cup=cup, perturbation=PerturbationConfig.for_episode(cup, **extra))
    labeller = SuctionLabeller(mesh, config, mass=mass, com=com)
    labels = labeller.label(np.asarray(point)[None], np.asarray(approach)[None], seed, metrics=tuple(METRICS))
    return {
        "label_seal": bool(labels.seal.seal[0]),
        "label_seal_failure": labels.seal.failure_names[0],
        "label_wr": bool(labels.wr[0]),
        "label_rwr": float(labels.rwr[0]),
        "label_scores": {name: float(labels.score(name)[0]) for name in METRICS},
    }


class PickRunner:
    """Builds the scene once per object and runs seeded episodes in it."""

    def __init__(self, request: PickRequest):
        if request.placement not in PLACEMENTS:
            raise InputError(f"--placement '{request.placement}': expected one of {', '.join(PLACEMENTS)}")
        self.request = request
        self.record = request.record or load_object(request.object_key)
        self.intrinsics = resolve_camera(request.camera)
        rng = np.random.default_rng((request.seed, 1))
        centre = np.array([*SceneConfig().workspace_centre, 0.0])
        self.camera_pose = sample_camera_pose(rng, centre, CameraPoseConfig().for_camera(self.intrinsics))
        self.scene = build_scene(self.record, request.cup, self.intrinsics, self.camera_pose, sim_cup=request.sim_cup)
        self.episode = PickEpisode(self.scene, request.episode)
        self.mesh = self.record.mesh()
        """The object's surface mesh in its own frame (loaded once; posed copies per episode)."""
        self.observation: Any = None
        """The last observation an image policy planned from (what the run log records)."""

    def object_pose(self) -> np.ndarray:
        """Current world transform of the object (its mesh frame)."""
        d, body = self.episode.data, self.episode.object
        return _pose(d.xpos[body], d.xmat[body])

    def run(self, render: Path | None = None, log: Path | None = None) -> dict[str, Any]:
        """Place, choose, execute; returns a JSON-ready record of the episode. With `log`, the
        episode is also written to that MCAP file (suctionbench.runlog)."""
        if log is None:
            self.reset()
            return self.run_after_reset(render)
        from suctionbench.runlog.writer import EpisodeLog

        with EpisodeLog(log, self.log_metadata()) as episode_log:
            self.reset()
            return self.run_after_reset(render, episode_log)

    def log_metadata(self) -> dict[str, Any]:
        """Run configuration, versions and seed, for the run log's metadata record."""
        from suctionbench import __version__
        from suctionbench.config import to_dict

        req = self.request
        return {
            "suctionbench_version": __version__, "mujoco_version": mujoco.__version__, "object": req.object_key,
            "seed": req.seed, "policy": req.policy if req.grasp is None else "given",
            "policy_args": req.policy_args if req.grasp is None else {}, "placement": req.placement,
            "cup": to_dict(req.cup), "camera": to_dict(self.intrinsics), "episode": to_dict(req.episode),
        }

    def reset(self) -> None:
        """Place the object (seeded) and let it settle, the arm out of the camera's view."""
        req = self.request
        stable = None
        if req.placement == "stable":
            poses = self.record.stable_poses
            stable = np.asarray(poses[min(req.stable_pose, len(poses) - 1)]["transform"], dtype=float)
        self.episode.reset(np.random.default_rng((req.seed, 0)), stable_pose=stable)

    def run_after_reset(self, render: Path | None = None, log: Any = None) -> dict[str, Any]:
        """Choose the grasp in the settled scene and execute it (logging to `log` if given)."""
        req = self.request
        placement_time = float(self.episode.data.time)
        pose = self.object_pose()
        mesh, com = self.posed_object(pose)
        chosen, self.observation = None, None
        self._sensing_time = 0.0
        if self.episode.placement_error:  # nothing to plan on: the trial is not executed
            result = EpisodeResult.not_executed("unstable", self.episode.placement_error, valid=False)
            return self._record(None, None, NO_LABELS, placement_time, 0.0, result, log)
        plan_start = time.perf_counter()
        try:
            if req.grasp is not None:
                point = pose[:3, :3] @ req.grasp[:3] + pose[:3, 3]
                approach = pose[:3, :3] @ (req.grasp[3:] / np.linalg.norm(req.grasp[3:]))
            elif req.policy in KNOWN_STATE_POLICIES:
                from suctionbench.policies.analytic import analytic_grasp, random_surface_grasp, uniform_density_com

                if req.policy == "analytic":
                    chosen = analytic_grasp(mesh, com, self.record.mass, req.cup, req.seed, metric=req.metric)
                elif req.policy in IMAGE_KNOWN_STATE_POLICIES:
                    belief = uniform_density_com(mesh) if req.policy in UNIFORM_DENSITY_POLICIES else com
                    chosen = self._rank_image_candidates(mesh, belief)
                else:
                    chosen = random_surface_grasp(mesh, req.seed)
            else:
                chosen = self._plan_from_image()
        except NoGraspError as exc:  # the policy's failure: recorded, nothing executed
            result = EpisodeResult.not_executed("no_grasp", str(exc))
            plan_time = time.perf_counter() - plan_start - self._sensing_time
            return self._record(None, None, NO_LABELS, placement_time, plan_time, result, log)
        if chosen is not None:
            point, approach = chosen.point, chosen.approach
        q = None if chosen is None or np.isnan(chosen.score) else chosen.score
        plan_time = time.perf_counter() - plan_start - self._sensing_time
        labels = self.label_grasp(point, approach, mesh, com)
        if render is not None:
            self.render_png(render)
        if log is not None:
            self._log_start(log, point, approach, chosen)
        result = self.episode.execute(point, approach)
        self.episode.recorder = None
        grasp = [*point.tolist(), *approach.tolist()]
        return self._record(grasp, q, labels, placement_time, plan_time, result, log)

    def _record(self, grasp: list[float] | None, q: float | None, labels: dict[str, Any], placement_time: float,
                plan_time: float, result: EpisodeResult, log: Any) -> dict[str, Any]:
        """The JSON-ready record of the trial (grasp None: nothing was executed), logged if `log`."""
        req = self.request
        record = {
            "object": req.object_key, "seed": req.seed, "placement": req.placement, "grasp_world": grasp,
            "policy_q": q, **labels, "placement_time": placement_time, "sensing_time": self._sensing_time,
            "plan_time": plan_time, **result.to_dict(),
        }
        if log is not None:
            log.log_result(float(self.episode.data.time), record)
        return record

    def posed_object(self, pose: np.ndarray | None = None) -> tuple[Any, np.ndarray]:
        """The object's mesh and centre of mass in the world, at `pose` (default: its current one).
        The centre of mass is the simulated body's: with a liquid, as levelled when the object last
        came to rest (`sim.liquids`)."""
        pose = self.object_pose() if pose is None else pose
        mesh = self.mesh.copy()
        mesh.apply_transform(pose)
        com = self.episode.model.body_ipos[self.episode.object]
        return mesh, pose[:3, :3] @ com + pose[:3, 3]

    def label_grasp(self, point: np.ndarray, approach: np.ndarray, mesh: Any = None,
                    com: np.ndarray | None = None) -> dict[str, Any]:
        """Analytic labels of one grasp on the object in its true current pose: seal, nominal wrench
        resistance, robust label, and every 3D metric's score (the known-objects tables rank by them).
        The disturbing wrench includes the inertial load of the episode's peak acceleration."""
        if mesh is None:
            mesh, com = self.posed_object()
        return grasp_labels(mesh, com, self.record.mass, self.request.cup, point, approach, self.request.seed,
                            self.episode.planned_transport(point, approach))

    def observe(self) -> Any:
        """The policy's view: the overhead depth image (with sensor noise), the camera, and the
        object's pixels (MuJoCo segmentation of the same view, from the same OpenGL context)."""
        from suctionbench.policies.base import Observation
        from suctionbench.sensing.camera import DepthRenderer
        from suctionbench.sensing.noise import apply_axial_noise

        with DepthRenderer(self.scene.model, self.intrinsics) as renderer:
            depth = renderer.render(self.episode.data, self.scene.camera)
            mask = self.object_pixels(renderer.segment(self.episode.data, self.scene.camera))
        if self.request.observation_noise:
            depth = apply_axial_noise(depth, np.random.default_rng((self.request.seed, 2)))
        return Observation(depth=depth, intrinsics=self.intrinsics, camera_pose=self.camera_pose, mask=mask)

    def object_pixels(self, segmentation: np.ndarray) -> np.ndarray:
        """Pixels (H, W) bool where a segmentation image (DepthRenderer.segment) shows the object."""
        from suctionbench.sensing.camera import body_image

        return body_image(self.scene.model, segmentation) == self.episode.object

    def _sense(self) -> Any:
        """Take the observation a plan reads (`observe`), keep it for the log, and time it apart
        from planning (`_sensing_time`)."""
        start = time.perf_counter()
        self.observation = self.observe()
        self._sensing_time = time.perf_counter() - start
        return self.observation

    def _rank_image_candidates(self, mesh: Any, com: np.ndarray) -> Any:
        """`analytic-image`: the grasps an image policy could choose from (drawn as the image
        policies draw theirs, from the same generator), ranked in the true state (`com`: where the
        ranking believes the centre of mass; `UNIFORM_DENSITY_POLICIES` pass the shape's)."""
        from suctionbench.policies.analytic import CANDIDATES, image_candidates, rank_grasps

        req = self.request
        points, approaches = image_candidates(self._sense(), CANDIDATES, np.random.default_rng((req.seed, 3)))
        return rank_grasps(mesh, com, self.record.mass, req.cup, req.seed, points, approaches, metric=req.metric)

    def _plan_from_image(self) -> Any:
        """Run an image policy from the registry on the current observation (world-frame result)."""
        from suctionbench.policies.analytic import RankedGrasp

        req = self.request
        policy = cached_policy(req.policy, req.model, req.policy_args)
        action = policy.plan(self._sense(), np.random.default_rng((self.request.seed, 3)))
        rot, origin = self.camera_pose[:3, :3], self.camera_pose[:3, 3]
        cands = action.candidates
        if "points" not in cands:  # a policy that reports no candidates: the grasp is the only one
            return RankedGrasp(action.point_world, action.approach_world, float(action.q),
                               action.point_world[None], action.approach_world[None], None, 0)
        return RankedGrasp(
            action.point_world, action.approach_world, float(action.q), cands["points"] @ rot.T + origin,
            cands["approaches"] @ rot.T, cands.get("q"), int(action.info["chosen"]), action.info.get("quality_map"),
        )

    def _log_start(self, log: Any, point: np.ndarray, approach: np.ndarray, chosen: Any) -> None:
        """Observation, candidates and chosen grasp; then state every `record_every` steps."""
        from suctionbench.sensing.camera import DepthRenderer

        t = float(self.episode.data.time)
        if self.observation is not None:  # log exactly what the policy saw (noise and all)
            depth = self.observation.depth
        else:
            with DepthRenderer(self.scene.model, self.intrinsics) as renderer:
                depth = renderer.render(self.episode.data, self.scene.camera)
        log.log_observation(t, depth, self.intrinsics.matrix, self.intrinsics.width, self.intrinsics.height,
                            self.camera_pose)
        if chosen is not None:
            log.log_grasps(t, chosen.candidate_points, chosen.candidate_approaches, chosen.candidate_scores,
                           chosen.chosen_index)
            if chosen.quality_map is not None:
                log.log_quality_map(t, chosen.quality_map)
        else:
            log.log_grasps(t, point[None], approach[None], None, 0)
        model, tip, body = self.scene.model, self.episode.tip, self.episode.object
        joints = [model.joint(j).name for j in range(model.njnt) if model.jnt_type[j] != mujoco.mjtJoint.mjJNT_FREE]
        adr = [model.jnt_qposadr[model.joint(j).id] for j in joints]

        def record(d: mujoco.MjData, cup: Any) -> None:
            now = float(d.time)
            log.log_transforms(now, {
                "camera": self.camera_pose, "cup_tip": _pose(d.site_xpos[tip], d.site_xmat[tip]),
                "object": _pose(d.xpos[body], d.xmat[body]),
            })
            log.log_joint_states(now, joints, d.qpos[adr].tolist())
            log.log_suction(now, cup.vacuum_on(d), cup.sealed >= 0, cup.compression(d))

        self.episode.recorder = record

    def render_rgb(self) -> np.ndarray:
        """The overhead camera's colour view of the current state, (H, W, 3) uint8."""
        from suctionbench.sensing.camera import render_colour

        return render_colour(self.scene.model, self.episode.data, self.scene.camera, self.intrinsics)

    def render_png(self, path: Path) -> None:
        """Save `render_rgb` as a PNG."""
        from suctionbench.sensing.image import save_png

        save_png(path, self.render_rgb())
