"""The benchmark's simulated pick as a dm_control task, for the DeepMind ecosystem (dm_env API).

    >>> from suctionbench.envs.dm_control_task import load
    >>> env = load(object_set="basic", random=0)          # a dm_control.rl.control.Environment
    >>> timestep = env.reset()                            # dm_env.TimeStep, StepType.FIRST
    >>> env.observation_spec()["depth"].shape, env.action_spec().shape
    ((480, 640), (6,))
    >>> timestep = env.step(action)                       # one grasp attempt

It is the same task as the gymnasium environment ``suctionbench/SuctionPick-v4``
(`suctionbench.envs.suction_pick.SuctionPickEnv`) and runs the same episode code: `SuctionPickTask`
drives a `SuctionPickEnv` (which drives `suctionbench.sim.pick.PickRunner` and
`suctionbench.sim.episode.PickEpisode`), so an object, placement, observation, grasp execution,
analytic label and reward are computed once, in one place, for both APIs; a seed gives the same
episode through either.

dm_control mapping
------------------
* **Physics.** `PickPhysics` wraps the episode's own ``mujoco.MjData`` (no copy): dm_control's named
  indexing reads the scene by name (``physics.named.data.qpos["yumi_joint_1_r"]``,
  ``physics.named.data.site_xpos[tip]``, ``physics.named.data.xpos["object"]``). Each episode may draw
  a different object, whose scene is another MuJoCo model; the task points the environment's
  physics at that scene's data when the episode starts (dm_control's ``_reload_from_data``, the
  hook its own ``reload_from_*`` constructors use).
* **Step.** One `step` is one grasp attempt, several simulated seconds of motion: the attempt runs
  in `SuctionPickTask.before_step`; the environment is built with ``n_sub_steps=0`` so that
  dm_control adds no physics steps of its own.
* **Action spec.** ``BoundedArray((6,), float32, [-1, -1, 0, -1, -1, -1], [1, 1, 2, 1, 1, 1])``: the
  grasp point (m) and approach direction in the camera frame, exactly the gymnasium action (see
  `SuctionPickEnv`; a zero approach is an invalid attempt, reward 0).
* **Observation spec.** The gymnasium observation, plus two proprioceptive read-outs of the arm
  taken with named indexing: ``depth`` (H, W) float32 metres, ``intrinsics`` (3, 3) float32,
  ``camera_pose`` (4, 4) float32 world-from-camera (OpenCV frame), ``mask`` (H, W) int8,
  ``arm_qpos`` (7,) float64 right-arm joint angles (rad), ``tool_tip`` (3,) float64 cup tip
  position in the world (m).
* **Reward, discount.** Reward 1.0 for a successful pick (lifted, carried, held) else 0.0. The
  episode ends (``StepType.LAST``, discount 0.0) when the gymnasium episode terminates: a success,
  ``max_attempts`` attempts, an invalid simulation, or the object out of view. No time limit.
* **Info.** dm_env has no info channel: `SuctionPickTask.info` holds the last step's gymnasium
  info (failure reason, analytic labels, phases, ...) plus ``object_position``, the object's
  position after the attempt (named ``xpos``).

Arguments of `load` are those of ``gymnasium.make("suctionbench/SuctionPick-v4", ...)`` (object_set,
cup, camera, max_attempts, camera_seed, observation_noise), ``random`` (an int seed or a
``numpy.random.RandomState``) for the episodes' seeds, and ``object`` ("SET/NAME") to pick that
object in every episode (the gymnasium ``reset(options={"object": ...})``).
"""

from __future__ import annotations

import contextlib
from typing import Any

import numpy as np
from dm_control import mujoco
from dm_control.mujoco import wrapper
from dm_control.rl import control
from dm_env import specs

from suctionbench.envs.suction_pick import ACTION_HIGH, ACTION_LOW, SuctionPickEnv
from suctionbench.sim.yumi import RIGHT_ARM_JOINTS

_SEED_BOUND = 2**31
"""Episode seeds handed to the gymnasium environment are drawn from the task's random state in [0, _SEED_BOUND)."""


class PickPhysics(mujoco.Physics):
    """Named read-outs of a pick scene (dm_control's habit: physics read-outs apart from task logic)."""

    @contextlib.contextmanager
    def reset_context(self):
        """No reset or forward pass around the task's episode start: the episode's own reset (drop and
        settle, `PickEpisode.reset`) sets the whole state, exactly as the gymnasium environment's
        does. dm_control's default would recompute the kinematics after it, and the two APIs'
        episodes would then differ in the last bits (measured: a 1e-5 change in a label score)."""
        yield

    def after_reset(self) -> None:
        """No forward pass when the physics is pointed at an episode's data (see `reset_context`):
        the episode's state, kinematics included, stays as its reset left it."""

    def arm_joint_positions(self) -> np.ndarray:
        """Right-arm joint angles (rad), in RIGHT_ARM_JOINTS order."""
        return np.array(self.named.data.qpos[list(RIGHT_ARM_JOINTS)], dtype=np.float64)

    def site_position(self, site: str) -> np.ndarray:
        """World position of a named site (m)."""
        return np.array(self.named.data.site_xpos[site], dtype=np.float64)

    def body_position(self, body: str) -> np.ndarray:
        """World position of a named body's frame (m)."""
        return np.array(self.named.data.xpos[body], dtype=np.float64)


class SuctionPickTask(control.Task):
    """Pick one object with the simulated YuMi's suction cup from an overhead depth image (see the
    module docstring for specs, reward and episode end)."""

    def __init__(
        self,
        object_set: str = "basic",
        cup: str = "default",
        camera: str = "primesense",
        max_attempts: int = 1,
        camera_seed: int = 0,
        observation_noise: bool = True,
        random: int | np.random.RandomState | None = None,
        object: str | None = None,
    ):
        self.random = random if isinstance(random, np.random.RandomState) else np.random.RandomState(random)
        """Where episode seeds come from (dm_control's convention: an int seed or a RandomState)."""
        self.env = SuctionPickEnv(
            object_set=object_set,
            cup=cup,
            camera=camera,
            max_attempts=max_attempts,
            camera_seed=camera_seed,
            observation_noise=observation_noise,
        )
        """The gymnasium environment whose reset and step this task drives (one copy of the episode)."""
        self.object = object
        """Pick this object (SET/NAME) in every episode instead of drawing one from `object_set`."""
        self.info: dict[str, Any] = {}
        """The last reset's or step's gymnasium info, plus ``object_position`` after a step."""
        self._observation: dict[str, np.ndarray] | None = None
        self._reward = 0.0
        self._terminated = False

    # -- dm_control Task -----------------------------------------------------------------------
    def initialize_episode(self, physics: PickPhysics) -> None:
        """Draw the episode's seed from the task's random state and reset the gymnasium episode on it;
        point `physics` at the scene of the object drawn."""
        options = None if self.object is None else {"object": self.object}
        self._observation, self.info = self.env.reset(seed=int(self.random.randint(_SEED_BOUND)), options=options)
        physics._reload_from_data(wrapper.MjData(self._runner.episode.data))
        self._reward, self._terminated = 0.0, False

    def before_step(self, action: np.ndarray, physics: PickPhysics) -> None:
        """Execute one grasp attempt (all of its simulated motion)."""
        self._observation, self._reward, self._terminated, _, self.info = self.env.step(np.asarray(action))
        self.info["object_position"] = physics.body_position(self._runner.scene.object_body)

    def action_spec(self, physics: PickPhysics | None = None) -> specs.BoundedArray:
        return specs.BoundedArray((6,), np.float32, ACTION_LOW, ACTION_HIGH, name="grasp")

    def observation_spec(self, physics: PickPhysics | None = None) -> dict[str, specs.Array]:
        shape = (self.env.intrinsics.height, self.env.intrinsics.width)
        return {
            "depth": specs.BoundedArray(shape, np.float32, 0.0, np.inf, name="depth"),
            "intrinsics": specs.Array((3, 3), np.float32, name="intrinsics"),
            "camera_pose": specs.Array((4, 4), np.float32, name="camera_pose"),
            "mask": specs.BoundedArray(shape, np.int8, 0, 1, name="mask"),
            "arm_qpos": specs.Array((len(RIGHT_ARM_JOINTS),), np.float64, name="arm_qpos"),
            "tool_tip": specs.Array((3,), np.float64, name="tool_tip"),
        }

    def get_observation(self, physics: PickPhysics) -> dict[str, np.ndarray]:
        observation = {name: array.copy() for name, array in self._observation.items()}
        observation["arm_qpos"] = physics.arm_joint_positions()
        observation["tool_tip"] = physics.site_position(self._runner.scene.cup.tip_site)
        return observation

    def get_reward(self, physics: PickPhysics) -> float:
        return self._reward

    def get_termination(self, physics: PickPhysics) -> float | None:
        """0.0 (a terminal step) once the gymnasium episode has terminated, else None."""
        return 0.0 if self._terminated else None

    # -- helpers --------------------------------------------------------------------------------
    @property
    def _runner(self):
        """The gymnasium environment's runner of the current object (scene, episode)."""
        return self.env._runner


def load(
    object_set: str = "basic",
    *,
    random: int | np.random.RandomState | None = None,
    **task_kwargs: Any,
) -> control.Environment:
    """The pick task as a ``dm_control.rl.control.Environment`` (dm_env API); `task_kwargs` are those
    of `SuctionPickTask` (cup, camera, max_attempts, camera_seed, observation_noise, object)."""
    task = SuctionPickTask(object_set=object_set, random=random, **task_kwargs)
    # A placeholder model until the first reset points the physics at the drawn object's scene.
    physics = PickPhysics.from_xml_string("<mujoco/>")
    return control.Environment(physics, task, n_sub_steps=0, legacy_step=False)
