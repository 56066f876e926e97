"""`suctionbench/SuctionBin-v5`: picking a cluttered bin clear, one grasp attempt per step.

A thin layer over `suctionbench.clutter.runner.BinRunner` (the runner fills the bin, renders,
labels and executes; the benchmark's `eval --task bin-*` runs the same code with a policy in the
agent's place).
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces
from gymnasium.error import ResetNeeded

from suctionbench.clutter.runner import MASK_SOURCES, BinRequest, BinRunner
from suctionbench.config import cup_preset
from suctionbench.envs.suction_pick import ACTION_HIGH, ACTION_LOW, MIN_APPROACH_NORM, image_spaces
from suctionbench.errors import InputError
from suctionbench.sensing.camera import resolve_camera
from suctionbench.sim.episode_config import EpisodeResult
from suctionbench.sim.pick import NO_LABELS

_SEED_BOUND = 2**31
"""Bins are drawn as trials of the task with a trial number from np_random in [0, _SEED_BOUND)."""

MAX_REGIONS = 255
"""Most object regions the `regions` image numbers (uint8); more are merged into the last label."""


class SuctionBinEnv(gymnasium.Env):
    """Clear a bin of 5-15 objects with a suction cup on a simulated ABB YuMi, one grasp per step,
    choosing each grasp from an overhead depth image (the bin picking Dex-Net 3.0 names as its
    future work).

    ## Description

    Each episode fills the pick bin (34 x 30 cm, at the workspace centre) with the objects of one
    bin of a bin task (`tasks/bin-*.toml`: the object sets, the count range, K), dropped one after
    another from random orientations and settled (`suctionbench.clutter.episode`). The agent
    answers each observation with one suction grasp; the YuMi moves to it, seals on whatever its
    cup meets, lifts clear of the pile, carries the object to the receptacle at the side and
    releases it there, where it is taken out of the scene. Objects a failed grasp disturbs stay
    where they land. One step is one attempt.

    ## Action space

    The same as `SuctionPick-v4`: `Box(low=[-1, -1, 0, -1, -1, -1], high=[1, 1, 2, 1, 1, 1],
    (6,), float32)`, a grasp point (metres) and an approach direction (from the cup into the
    surface), both in the camera's OpenCV optical frame. A zero or non-finite approach is not
    executed: reward 0, `info["failure"] == "invalid_action"`, and it counts as a failed attempt.

    ## Observation space

    `Dict` of (H, W = the camera preset's image size):

    - `"depth"`: `Box(0, inf, (H, W), float32)`, z-depth in metres (0: no return), with the
      simulated sensor's noise.
    - `"intrinsics"`: `Box(-inf, inf, (3, 3), float32)`, the calibration matrix K.
    - `"camera_pose"`: `Box(-inf, inf, (4, 4), float32)`, world-from-camera (OpenCV frame; world
      z up, table top at z = 0).
    - `"mask"`: `MultiBinary((H, W))` (int8), 1 on the pixels inside the bin above its floor (the
      workspace bounds; no object knowledge).
    - `"regions"`: `Box(0, 255, (H, W), uint8)`, the object regions the benchmark's policies plan on
      (0: none; 1 the largest, 2 the next...): from segmenting the depth image
      (`sensing.segmentation`), or the renderer's instance masks with `masks="oracle"`.

    ## Rewards

    The number of objects that reached the receptacle in the attempt (1 for a clean pick; 2 when
    a second object came along, which is still the failure "two_lifted"). The analytic label of
    the grasp is in `info`, never in the reward.

    ## Episode end

    Terminated when the bin is empty, after K (`max_failures`) failed attempts in a row, after the
    task's attempt limit (twice the object count unless the task says), or when the simulation
    went unstable (`info["valid"]` False or `info["detail"]`). `truncated` is always False.

    ## Info

    `reset` returns `{"objects": [SET/NAME...], "in_bin": [...], "spilled": [...]}` (objects that
    would not stay in the bin while it was filled are not in the scene). `step` returns the
    attempt's record: `target` (the object body under the grasp point) and `held` (the body the cup
    sealed on), `transported` and `lost` (bodies that left the bin, to the receptacle or out of
    reach), `remaining` (objects in the bin), `success`, `failure` (None, one of
    `suctionbench.clutter.episode.CLUTTER_FAILURES`, or "invalid_action"), the analytic labels of
    the grasp on the target in its true pose (`label_seal`, `label_rwr`, ...; None without a target),
    `grasp_world`, `sim_time`, `phases`, `peak_acceleration`, and `failures_in_row`.

    ## Arguments

    ```python
    gymnasium.make(
        "suctionbench/SuctionBin-v5",
        task="bin-basic",        # bin-smoke, bin-basic, bin-typical, bin-mixed, or a bin-task TOML
        cup="default",           # cup preset, shared by the simulated cup and the labels
        camera="primesense",     # camera preset or intrinsics TOML
        masks="depth",           # "regions" from depth segmentation, or "oracle" instance masks
        render_mode=None,        # or "rgb_array": the overhead camera's colour image
        observation_noise=True,  # the simulated sensor's axial depth noise
    )
    ```

    ## Reset

    `reset(seed=..., options={"trial": i})` runs bin i of the task (the benchmark's bin i), or
    `options={"objects": ["basic/box_tea", ...]}` fills the bin with those objects; without options
    a bin is drawn from `np_random`. The same seed and options give the same bin, bit for bit on
    one machine, and the same actions then give the same rewards and infos.

    ## Version history

    - v0: initial version.
    - v1 (2026-11-26): the simulated vacuum pulls along the cup's axis however an object's collision
      geometry is decomposed.
    - v2 (2026-11-26): the leak test measures the object's real surface behind the convex parts
      the lip rests on, so concavities the parts span (drain ribs, tooth gaps) leak.
    - v3 (2026-11-27): a part-filled container's liquid (water, milk, shampoo, a can's soft drink)
      levels in the pose the object comes to rest in, moving its centre of mass (a lying bottle's
      to the middle of its length); the analytic labels use the same centre of mass.
    - v4 (2026-11-27): a levelled body built with an unrotated inertial frame (an upright can, a
      jug) has its inertial frame turned in the kinematics too; in v3 its inertia acted about the
      built axes and its collision bounding boxes sat turned, so parts missed contacts (a lying
      can's up to 17 mm; bins that ended in a deep interpenetration while filling).
    - v5 (2026-11-28): the same physics; the `regions` observation cuts an object only at concave
      creases and depth steps, no longer at its own convex edges (a box's top and side, a mug's
      top and wall are one region), so a policy planning per region reads the whole object's
      centroid and extent (`sensing.segmentation.convex`; eval/bin/README.md).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 1}

    def __init__(self, task: str = "bin-basic", cup: str = "default", camera: str = "primesense",
                 masks: str = "depth", render_mode: str | None = None, observation_noise: bool = True):
        from suctionbench.clutter.tasks import load_bin_task

        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise InputError(f"render_mode '{render_mode}': expected None or one of {self.metadata['render_modes']}")
        if masks not in MASK_SOURCES:
            raise InputError(f"masks '{masks}': expected one of {', '.join(MASK_SOURCES)}")
        self.task = load_bin_task(task)
        self.render_mode = render_mode
        self.cup, self.camera, self.masks = cup_preset(cup), str(camera), masks
        self.intrinsics = resolve_camera(camera)
        self.observation_noise = bool(observation_noise)
        shape = (self.intrinsics.height, self.intrinsics.width)
        self.observation_space = spaces.Dict({**image_spaces(self.intrinsics),
                                              "regions": spaces.Box(0, MAX_REGIONS, shape, np.uint8)})
        self.action_space = spaces.Box(ACTION_LOW, ACTION_HIGH, dtype=np.float32)
        self._runner: BinRunner | None = None
        self._observation: dict[str, np.ndarray] | None = None
        self._attempt, self._failures, self._done = 0, 0, True

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Fill a bin (the task's bin `trial`, the given `objects`, or one drawn) and observe it."""
        super().reset(seed=seed)
        options = options or {}
        unknown = sorted(set(options) - {"trial", "objects"})
        if unknown:
            raise InputError(f"reset options {unknown}: unknown (known: 'trial', 'objects')")
        trial = options.get("trial")
        if trial is None:
            trial = int(self.np_random.integers(_SEED_BOUND))
        elif isinstance(trial, bool) or not isinstance(trial, int | np.integer) or trial < 0:
            raise InputError(f"reset option trial = {trial!r}: must be a non-negative integer")
        objects = options.get("objects")
        if objects is not None and (isinstance(objects, str) or not all(isinstance(k, str) for k in objects)
                                    or not objects):
            raise InputError(f"reset option objects = {objects!r}: must be a non-empty list of SET/NAME keys")
        request = BinRequest(self.task, trial=int(trial), policy="agent", masks=self.masks, cup=self.cup,
                             camera=self.camera, observation_noise=self.observation_noise,
                             keys=None if objects is None else list(objects))
        self._runner = BinRunner(request)
        episode = self._runner.episode
        episode.reset(np.random.default_rng((self.task.seed, int(trial), 0)))
        self._attempt, self._failures = 0, 0
        self._done = episode.placement_error is not None or not episode.present
        self._observation = self._observe()
        return self._copy(), {"objects": self._runner.keys, "in_bin": [episode.names[b] for b in episode.present],
                              "spilled": list(episode.spilled)}

    def step(self, action: np.ndarray):
        """One grasp attempt given in the camera frame (see the class docstring)."""
        if self._runner is None or self._done:
            raise ResetNeeded("call reset() before step() (and after an episode has terminated)")
        runner, episode = self._runner, self._runner.episode
        action = np.asarray(action, dtype=float).reshape(6)
        norm = float(np.linalg.norm(action[3:]))
        if not (np.all(np.isfinite(action)) and norm >= MIN_APPROACH_NORM):
            outcome = EpisodeResult.not_executed("invalid_action").to_dict()
            del outcome["wall_time"]
            info = {"attempt": self._attempt, **outcome, **NO_LABELS, "grasp_world": None, "target": None,
                    "held": None, "transported": [], "lost": [], "remaining": len(episode.present)}
        else:
            rotation, origin = runner.camera_pose[:3, :3], runner.camera_pose[:3, 3]
            info = runner.attempt_grasp(self._attempt, rotation @ action[:3] + origin, rotation @ (action[3:] / norm))
            info.pop("wall_time", None)  # real time differs run to run; infos must not
        self._attempt += 1
        self._failures = 0 if info["success"] else self._failures + 1
        info["failures_in_row"] = self._failures
        broken = episode.placement_error is not None or not info["valid"]
        if broken and info["valid"]:
            info["detail"] = episode.placement_error
        terminated = bool(broken or not episode.present or self._failures >= self.task.max_failures
                          or self._attempt >= self.task.attempts_for(len(runner.keys)))
        self._done = terminated
        if not broken:
            self._observation = self._observe()
        return self._copy(), float(len(info["transported"])), terminated, False, info

    def render(self) -> np.ndarray | None:
        """The overhead camera's colour image (H, W, 3) uint8 ("rgb_array")."""
        if self.render_mode is None:
            gymnasium.logger.warn("render() called with render_mode=None; pass render_mode='rgb_array' to make()")
            return None
        if self._runner is None:
            raise ResetNeeded("call reset() before render()")
        from suctionbench.sensing.camera import render_colour

        runner = self._runner
        return render_colour(runner.scene.model, runner.episode.data, runner.scene.camera, self.intrinsics)

    def close(self) -> None:
        self._runner, self._observation, self._done = None, None, True

    def _observe(self) -> dict[str, np.ndarray]:
        observation, regions = self._runner.observe(self._attempt)
        labels = np.zeros(observation.depth.shape, dtype=np.uint8)
        for i, region in enumerate(regions[::-1]):  # the largest last, so it keeps label 1 where regions meet
            labels[region] = min(len(regions) - i, MAX_REGIONS)
        return {
            "depth": observation.depth.astype(np.float32),
            "intrinsics": observation.intrinsics.matrix.astype(np.float32),
            "camera_pose": observation.camera_pose.astype(np.float32),
            "mask": observation.mask.astype(np.int8),
            "regions": labels,
        }

    def _copy(self) -> dict[str, np.ndarray]:
        return {name: array.copy() for name, array in self._observation.items()}
