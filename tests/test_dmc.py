"""The pick task as a dm_control task: dm_env's own conformance checks, a random rollout, the same
episode as the gymnasium environment for the same seed, a successful pick, named read-outs."""

from __future__ import annotations

import dm_env
import numpy as np
import pytest
from absl.testing import absltest
from dm_env import test_utils

from suctionbench.envs.dm_control_task import SuctionPickTask, load
from suctionbench.envs.suction_pick import SuctionPickEnv
from suctionbench.sim.yumi import RIGHT_ARM_JOINTS

BOX = "basic/box_tea"  # 14 x 7 x 7 cm box: a flat face up however it lands


class SuctionPickDmEnvTest(test_utils.EnvironmentTestMixin, absltest.TestCase):
    """dm_env's EnvironmentTestMixin: reset/step types, specs of every observation, reward, discount."""

    def make_object_under_test(self):
        return load("basic", random=3, max_attempts=2)

    def make_action_sequence(self):
        rng = np.random.default_rng(0)
        spec = self.environment.action_spec()
        for _ in range(5):  # two attempts per episode: FIRST, MID, LAST, FIRST, ...
            yield rng.uniform(spec.minimum, spec.maximum).astype(spec.dtype)


def top_down_at_visible_centre(obs) -> np.ndarray:
    """Action: the mean of the object's deprojected pixels, approached straight down."""
    K = obs["intrinsics"].astype(float)
    mask = obs["mask"].astype(bool) & (obs["depth"] > 0)
    v, u = np.nonzero(mask)
    z = obs["depth"][v, u].astype(float)
    points = np.stack([(u - K[0, 2]) * z / K[0, 0], (v - K[1, 2]) * z / K[1, 1], z], axis=1)
    down = obs["camera_pose"][:3, :3].astype(float).T @ [0.0, 0.0, -1.0]
    return np.concatenate([points.mean(axis=0), down]).astype(np.float32)


def test_random_rollout_keeps_to_the_specs():
    env = load("basic", random=1, max_attempts=3)
    spec, observation_spec = env.action_spec(), env.observation_spec()
    rng = np.random.default_rng(1)
    kinds, objects = [], set()
    timestep = env.reset()
    for _ in range(8):
        for name, array in timestep.observation.items():
            observation_spec[name].validate(array)
        kinds.append(timestep.step_type)
        if timestep.last():
            assert timestep.discount == 0.0
        timestep = env.step(rng.uniform(spec.minimum, spec.maximum).astype(np.float32))
        objects.add(env.task.info["object"])
        if not timestep.first():
            assert timestep.reward == (1.0 if env.task.info["success"] else 0.0)
    assert {dm_env.StepType.FIRST, dm_env.StepType.MID, dm_env.StepType.LAST} <= set(kinds)
    assert len(objects) >= 2  # objects are drawn per episode: the physics follows the drawn scene


def test_same_seed_same_episode_as_the_gymnasium_env():
    random = np.random.RandomState(7)
    seed = int(np.random.RandomState(7).randint(2**31))
    env = load("basic", random=random)
    first = env.reset()
    gym_env = SuctionPickEnv(object_set="basic")
    gym_obs, gym_info = gym_env.reset(seed=seed)
    assert env.task.info["object"] == gym_info["object"]
    for name in ("depth", "intrinsics", "camera_pose", "mask"):
        assert np.array_equal(first.observation[name], gym_obs[name]), name
    action = top_down_at_visible_centre(gym_obs)
    step = env.step(action)
    _, reward, terminated, _, info = gym_env.step(action)
    assert step.reward == reward and step.last() == terminated
    assert {k: v for k, v in env.task.info.items() if k not in ("object_position", "grasp_world")} == {
        k: v for k, v in info.items() if k != "grasp_world"
    }
    assert np.array_equal(env.task.info["grasp_world"], info["grasp_world"])


def test_a_top_down_pick_of_a_box_succeeds_and_ends_the_episode():
    env = load("basic", random=0, object=BOX)
    first = env.reset()
    assert first.first() and first.reward is None and first.discount is None
    step = env.step(top_down_at_visible_centre(first.observation))
    assert step.last() and step.reward == 1.0 and step.discount == 0.0, env.task.info
    assert env.task.info["success"] and env.task.info["lifted"] and env.task.info["in_bin"]
    assert env.step(np.zeros(6, np.float32)).first()  # dm_control resets after LAST


def test_named_read_outs_match_the_episode_state():
    task = SuctionPickTask(object_set="basic", object=BOX, random=0)
    env = load("basic", random=0, object=BOX)
    timestep = env.reset()
    physics, runner = env.physics, env.task.env._runner
    data, model = runner.episode.data, runner.episode.model
    assert physics.data.ptr is data  # the dm_control physics wraps the episode's own MjData
    qpos = [data.qpos[model.jnt_qposadr[model.joint(j).id]] for j in RIGHT_ARM_JOINTS]
    np.testing.assert_array_equal(timestep.observation["arm_qpos"], qpos)
    ready_tip = runner.episode.config.ready_tip
    np.testing.assert_allclose(timestep.observation["tool_tip"], ready_tip, atol=2e-3)
    np.testing.assert_array_equal(physics.body_position("object"), data.xpos[runner.episode.object])
    assert task.observation_spec()["depth"].shape == timestep.observation["depth"].shape


def test_bad_arguments_name_the_input():
    from suctionbench.errors import InputError

    with pytest.raises(InputError, match="max_attempts"):
        load("basic", max_attempts=0)
    with pytest.raises(InputError, match="object set 'nope'"):
        load("nope")
    env = load("basic", object="basic/no_such_thing")
    with pytest.raises(InputError, match="no_such_thing"):
        env.reset()
