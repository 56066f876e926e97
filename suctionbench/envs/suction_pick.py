"""`suctionbench/SuctionPick-v4`: the benchmark's simulated pick as a gymnasium environment.

The environment is a thin layer over `suctionbench.sim.pick.PickRunner`: the runner builds the
scene, places the object, renders the observation and executes the pick; this module only maps
gymnasium's reset/step onto it, converts the action from the camera frame to the world, and labels
the executed grasp analytically the way `PickRunner.run_after_reset` does, so that an agent's
grasps are scored exactly as the CLI's `suctionbench pick` scores a policy's.
"""

from __future__ import annotations

from typing import Any

import gymnasium
import mujoco
import numpy as np
from gymnasium import spaces
from gymnasium.error import ResetNeeded

from suctionbench.config import cup_preset
from suctionbench.errors import InputError
from suctionbench.objects.registry import list_objects
from suctionbench.sensing.camera import resolve_camera
from suctionbench.sim.episode_config import EpisodeResult
from suctionbench.sim.pick import NO_LABELS, PickRequest, PickRunner

ACTION_LOW = np.array([-1.0, -1.0, 0.0, -1.0, -1.0, -1.0], dtype=np.float32)
"""Lower action bounds: grasp point x, y, z (m, camera frame), approach vx, vy, vz. The camera
stands 0.5-0.7 m from the workspace centre, so [-1, 1] x [-1, 1] x [0, 2] m holds everything it
sees with a wide margin; unit approach components lie in [-1, 1]."""

ACTION_HIGH = np.array([1.0, 1.0, 2.0, 1.0, 1.0, 1.0], dtype=np.float32)
"""Upper action bounds (see ACTION_LOW)."""

MIN_APPROACH_NORM = 1e-9
"""An approach vector shorter than this has no direction: the action is invalid."""


def image_spaces(intrinsics: Any) -> dict[str, spaces.Space]:
    """The observation's image entries (see the class docstring): depth, intrinsics, camera pose, mask."""
    shape = (intrinsics.height, intrinsics.width)
    return {
        "depth": spaces.Box(0.0, np.inf, shape, np.float32),
        "intrinsics": spaces.Box(-np.inf, np.inf, (3, 3), np.float32),
        "camera_pose": spaces.Box(-np.inf, np.inf, (4, 4), np.float32),
        "mask": spaces.MultiBinary(shape),
    }


class _Diverged(Exception):
    """The simulation went unstable while the object re-settled."""


RESET_TRIES = 5
"""Placements tried per reset before giving up; a drop whose simulation goes unstable (rare) is
redrawn with the next seed from np_random, so every reset still depends on its seed alone."""

_SEED_BOUND = 2**31
"""Seeds handed to PickRunner (placement, sensor noise, label perturbations) are drawn from np_random
in [0, _SEED_BOUND)."""


class SuctionPickEnv(gymnasium.Env):
    """Pick one object with a suction cup on a simulated ABB YuMi, choosing the grasp from an
    overhead depth image (Dex-Net 3.0's physical benchmark, in MuJoCo).

    ## Description

    Each episode drops one object of an object set onto the table from a uniformly random
    orientation, lets it settle and shows it to a fixed overhead depth camera. The agent answers
    with one suction grasp (a point and an approach direction); the YuMi moves to it along the
    approach, switches on the vacuum once the bellow touches, lifts, carries the object to the bin
    and holds it there (`suctionbench.sim.episode`). One step is one grasp attempt. This is the
    episode of `suctionbench pick`, with the agent in place of the policy.

    ## Action space

    `Box(low=[-1, -1, 0, -1, -1, -1], high=[1, 1, 2, 1, 1, 1], shape=(6,), dtype=float32)`:

    | index | meaning                                                    | unit / frame      |
    |-------|------------------------------------------------------------|-------------------|
    | 0-2   | grasp point (x, y, z): where the cup's centre touches      | metres, camera    |
    | 3-5   | approach direction (vx, vy, vz), from the cup into the object | camera        |

    The camera frame is the OpenCV optical frame of the observation's camera (x right, y down, z
    forward along the optical axis), so a pixel (u, v) of depth d is the point
    ((u - cx) d / fx, (v - cy) d / fy, d), and straight down is `camera_pose[:3, :3].T @ (0, 0, -1)`.
    The approach is normalised inside `step`, so its length does not matter. A zero (or
    non-finite) action has no direction: it is not executed, gives reward 0 and
    `info["failure"] == "invalid_action"`, and uses up an attempt. The box bounds are what
    `action_space.sample()` draws from; actions outside them are executed as given, and a grasp
    the arm cannot reach fails with `"unreachable"`.

    ## Observation space

    `Dict` of (H, W = height, width of the camera preset; 480 x 640 for "primesense"):

    - `"depth"`: `Box(0, inf, (H, W), float32)`, z-depth in metres along the optical axis, 0 where
      nothing returns, with the simulated sensor's axial noise (see `observation_noise`).
    - `"intrinsics"`: `Box(-inf, inf, (3, 3), float32)`, the calibration matrix K.
    - `"camera_pose"`: `Box(-inf, inf, (4, 4), float32)`, world-from-camera transform in the OpenCV
      frame (world z up, table top at z = 0).
    - `"mask"`: `MultiBinary((H, W))` (int8), 1 on the object's pixels (from a segmentation
      rendering: exact, with no sensor model).

    ## Rewards

    1.0 for a successful pick - the object lifted clear of the table, carried over the bin and
    still held at the end of the hold - else 0.0. The analytic label of the executed grasp is in
    `info` but never in the reward: the simulation judges the analytic model, not the reverse.

    ## Starting state

    The object is drawn uniformly from `object_set` with the environment's `np_random` (or given
    by `options={"object": "SET/NAME"}`, which may name any built object), dropped from a uniformly
    random orientation above a random point near the workspace centre, and left to settle; the arm
    waits out of the camera's view. The camera does not move between episodes: it is drawn once,
    from the paper's camera-pose distribution with `camera_seed`, and is the same for every object.

    ## Episode end

    The episode terminates after a successful attempt, after `max_attempts` attempts, after an
    attempt whose simulation became invalid (`info["valid"]` False: non-finite, exploding or
    interpenetrating state) or went unstable while the object settled after it (said in
    `info["detail"]`; the attempt's own outcome stands), or when the object has left the camera's
    view. `truncated` is always
    False: episodes last at most `max_attempts` steps, so no time limit is registered.

    After every executed attempt the vacuum vents, the arm returns to its waiting configuration
    and the object settles where it fell; the next observation shows that scene (no reset). The
    return of the arm is done by setting its joints directly, a simulation shortcut standing for a
    retract that does not touch the object; the fall and settling of the object are simulated.
    When the scene has gone unstable it cannot be rendered, so the observation repeats the
    previous one; after an invalid action nothing moved, and the observation is the same image again.

    ## Info

    `reset` returns `{"object": "SET/NAME"}`. `step` returns:

    - `object`, `attempt` (1 for the first attempt of the episode).
    - `success`, `valid`, `failure` (None, one of `suctionbench.sim.episode_config.FAILURES`, or
      `"invalid_action"`) and `detail` (what made an attempt invalid).
    - `label_seal`, `label_wr`, `label_rwr`: the analytic labels (seal formed, wrench resisted,
      robust wrench resistance) of the executed grasp in the true object state at the moment of
      the grasp, with the environment's cup; `label_seal_failure`, why the labeller's seal fails
      (None where it seals, else one of `suctionbench.contact.FAILURES`, e.g. "pushed_away");
      `label_scores` (the score of every 3D metric: pc3d, ss, wr, rwr); `grasp_world`, the
      executed point and unit approach in the world frame (6,). All six are None for an invalid
      action.
    - `seal_time` (s from the start of the attempt, None without a seal), `sim_time` (simulated
      seconds of the attempt), `peak_slip` (m), `lifted`, `in_bin`, `phases` (simulated time at
      which each phase ended).
    - `object_visible`: whether the returned observation shows any of the object.
    - `wall_time` (s of real time of the attempt), only with `info_wall_time=True`: it differs
      from run to run, so by default it is kept out of `info` to keep same seed, same actions,
      same info (gymnasium's `check_env` asserts it); `last_wall_time` always has it.

    ## Arguments

    ```python
    gymnasium.make(
        "suctionbench/SuctionPick-v4",
        object_set="basic",         # basic, typical, adversarial, or a user set (suctionbench objects list)
        cup="default",              # cup preset (suctionbench.config.CUP_PRESETS), shared by sim and label
        camera="primesense",        # camera preset or intrinsics TOML file; sets H, W of the images
        max_attempts=1,             # grasp attempts per episode
        render_mode=None,           # or "rgb_array": the overhead camera's colour image (H, W, 3) uint8
        camera_seed=0,              # which camera pose of the paper's distribution to use
        observation_noise=True,     # the simulated sensor's axial depth noise
        info_wall_time=False,       # add the attempt's real time to info (makes info nondeterministic)
    )
    ```

    ## Reset

    `reset(seed=..., options={"object": "SET/NAME"})`: the same seed (and options) gives the same
    object, placement and observation, bit for bit on one machine, and the same actions then give
    the same rewards and infos. Scenes are built once per object and reused (`PickRunner` cache).

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
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 1}
    """One frame per attempt: each step is several simulated seconds of motion."""

    def __init__(
        self,
        object_set: str = "basic",
        cup: str = "default",
        camera: str = "primesense",
        max_attempts: int = 1,
        render_mode: str | None = None,
        camera_seed: int = 0,
        observation_noise: bool = True,
        info_wall_time: bool = False,
    ):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise InputError(f"render_mode '{render_mode}': expected None or one of {self.metadata['render_modes']}")
        if isinstance(max_attempts, bool) or not isinstance(max_attempts, int | np.integer) or max_attempts < 1:
            raise InputError(f"max_attempts = {max_attempts!r}: must be a positive integer")
        self.render_mode = render_mode
        self.max_attempts = int(max_attempts)
        self.cup = cup_preset(cup)
        self.camera = str(camera)
        self.intrinsics = resolve_camera(camera)
        self.camera_seed = int(camera_seed)
        self.observation_noise = bool(observation_noise)
        self.info_wall_time = bool(info_wall_time)
        self.records = {record.key: record for record in list_objects(object_set)}
        if not self.records:
            raise InputError(f"object set '{object_set}' has no built objects (see `suctionbench objects build`)")
        self.object_keys = sorted(self.records)
        """Keys of the objects an episode is drawn from, in a fixed order (the draw depends on it)."""

        self.observation_space = spaces.Dict(image_spaces(self.intrinsics))
        self.action_space = spaces.Box(ACTION_LOW, ACTION_HIGH, dtype=np.float32)

        self.last_wall_time: float | None = None
        """Real time (s) of the last executed attempt, None before one or after an invalid action."""
        self._runners: dict[str, PickRunner] = {}
        self._runner: PickRunner | None = None
        self._observation: dict[str, np.ndarray] | None = None
        self._ready: tuple[np.ndarray, np.ndarray] | None = None
        self._attempt = 0
        self._done = True

    # -- gymnasium API --------------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Draw the object (unless given), drop it, let it settle and observe it."""
        super().reset(seed=seed)
        options = options or {}
        unknown = sorted(set(options) - {"object"})
        if unknown:
            raise InputError(f"reset options {unknown}: unknown (known: 'object')")
        key = options.get("object")
        if key is None:
            key = self.object_keys[int(self.np_random.integers(len(self.object_keys)))]
        runner = self._runner_for(str(key))
        for _ in range(RESET_TRIES):
            runner.request.seed = self._draw_seed()
            runner.reset()
            if runner.episode.placement_error is None:
                break
        else:
            error = runner.episode.placement_error
            raise RuntimeError(f"object '{key}': {RESET_TRIES} drops in a row went unstable (last: {error})")
        data = runner.episode.data
        self._ready = (data.qpos.copy(), data.ctrl.copy())
        self._runner, self._attempt, self._done = runner, 0, False
        self._observation = self._observe()
        return self._copy_observation(), {"object": runner.request.object_key}

    def step(self, action: np.ndarray) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        """Execute one grasp attempt given in the camera frame (see the class docstring)."""
        if self._runner is None or self._done:
            raise ResetNeeded("call reset() before step() (and after an episode has terminated)")
        runner = self._runner
        self._attempt += 1
        runner.request.seed = self._draw_seed()  # label perturbations and the next observation's noise
        action = np.asarray(action, dtype=float).reshape(6)
        norm = float(np.linalg.norm(action[3:]))
        info: dict[str, Any] = {"object": runner.request.object_key, "attempt": self._attempt}
        broken = False  # the scene can no longer be simulated or rendered
        if not (np.all(np.isfinite(action)) and norm >= MIN_APPROACH_NORM):
            self.last_wall_time = None
            outcome = EpisodeResult.not_executed("invalid_action").to_dict()
            del outcome["wall_time"]  # nothing ran; kept out of info as for executed attempts
            info.update(outcome, **NO_LABELS, grasp_world=None)
        else:
            rotation, origin = runner.camera_pose[:3, :3], runner.camera_pose[:3, 3]
            point = rotation @ action[:3] + origin
            approach = rotation @ (action[3:] / norm)
            info.update(self._runner.label_grasp(point, approach))
            info["grasp_world"] = np.concatenate([point, approach])
            result = runner.episode.execute(point, approach)
            self.last_wall_time = result.wall_time
            outcome = result.to_dict()
            wall_time = outcome.pop("wall_time")
            info.update(outcome)
            if self.info_wall_time:
                info["wall_time"] = wall_time
            if result.valid and self._retract():
                self._observation = self._observe()
            else:  # the state cannot be rendered: repeat the last image and end the episode
                broken = True
                if result.valid:  # the attempt's outcome stands; only the settling after it broke
                    info["detail"] = "unstable while the object settled after the attempt"
        visible = bool(self._observation["mask"].any())
        info["object_visible"] = visible
        terminated = bool(info["success"] or broken or self._attempt >= self.max_attempts or not visible)
        self._done = terminated
        return self._copy_observation(), 1.0 if info["success"] else 0.0, terminated, False, info

    def render(self) -> np.ndarray | None:
        """The overhead camera's colour image (H, W, 3) uint8 of the current state ("rgb_array").

        The OpenGL context is made and freed per call (about 0.2 s) rather than kept: a context
        left for the garbage collector at interpreter exit fails noisily, and an environment that
        is never closed is common.
        """
        if self.render_mode is None:
            gymnasium.logger.warn("render() called with render_mode=None; pass render_mode='rgb_array' to make()")
            return None
        if self._runner is None:
            raise ResetNeeded("call reset() before render()")
        return self._runner.render_rgb()

    def close(self) -> None:
        """Drop the cached scenes (idempotent); the environment can be reset again afterwards."""
        self._runners.clear()
        self._runner, self._observation, self._done = None, None, True

    # -- helpers --------------------------------------------------------------------------------
    def _draw_seed(self) -> int:
        return int(self.np_random.integers(_SEED_BOUND))

    def _runner_for(self, key: str) -> PickRunner:
        """The cached runner (built scene) of an object: building the scene is the expensive part
        of a reset. Every runner uses `camera_seed`, so all objects share one camera pose."""
        if key not in self._runners:
            request = PickRequest(
                key, seed=self.camera_seed, cup=self.cup, camera=self.camera, record=self.records.get(key),
                observation_noise=self.observation_noise,
            )
            self._runners[key] = PickRunner(request)  # unknown keys raise InputError naming the known ones
        return self._runners[key]

    def _observe(self) -> dict[str, np.ndarray]:
        """The runner's observation (noise seeded by its request's seed) as the space's arrays."""
        observation = self._runner.observe()
        return {
            "depth": np.asarray(observation.depth, dtype=np.float32),
            "intrinsics": observation.intrinsics.matrix.astype(np.float32),
            "camera_pose": np.asarray(observation.camera_pose).astype(np.float32),
            "mask": np.asarray(observation.mask).astype(np.int8),
        }

    def _copy_observation(self) -> dict[str, np.ndarray]:
        """Fresh arrays on every return: users keep observations, and one may be returned twice."""
        return {name: array.copy() for name, array in self._observation.items()}

    def _retract(self) -> bool:
        """Vent, put the robot back in its waiting state (as after the reset) and let the object
        settle where it is; False if the simulation goes unstable meanwhile.

        Only the object's free joint keeps its state: the arm, bellow and vacuum are set directly,
        standing for a retract that does not disturb the object (the object is then free, so
        whatever it was doing - pressed, hanging from a broken seal - it falls and settles).
        """
        episode = self._runner.episode
        model, data = episode.model, episode.data
        qpos_ready, ctrl_ready = self._ready
        qpos, qvel = episode.qpos_of(episode.object), episode.object_dofs
        object_qpos, object_qvel = data.qpos[qpos].copy(), data.qvel[qvel].copy()
        data.qpos[:], data.qvel[:], data.ctrl[:] = qpos_ready, 0.0, ctrl_ready
        data.qpos[qpos], data.qvel[qvel] = object_qpos, object_qvel
        episode.cup.release(data)
        mujoco.mj_forward(model, data)
        def step() -> None:
            mujoco.mj_step(model, data)
            if not (np.all(np.isfinite(data.qpos)) and np.linalg.norm(data.qvel[qvel]) < episode.config.max_speed):
                raise _Diverged

        try:  # the placement's settling rule (PickEpisode.settle); still creeping at its end is fine here
            episode.settle(step)
        except _Diverged:
            return False
        return True
