"""Physics validation of the simulated pick (MuJoCo YuMi + compliant suction cup).

Default cup: radius r = 7.5 mm, vacuum V = 50 kPa x pi r^2 = 8.84 N (payload 0.90 kg). The
simulated cup is calibrated to physics, never to the analytic labeller.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest
import trimesh

from suctionbench.config import CUP_DEFAULT, STANDARD_GRAVITY
from suctionbench.objects.build import build_object
from suctionbench.objects.registry import list_objects, load_object
from suctionbench.objects.spec import SETS, ObjectSpec
from suctionbench.sim.ik import solve_ik
from suctionbench.sim.pick import PickRequest, PickRunner
from suctionbench.sim.yumi import HOME_RIGHT, RIGHT_ARM_JOINTS


def pick(key=None, grasp=None, placement="stable", seed=0, record=None):
    request = PickRequest(
        key or record.key, seed=seed, grasp=None if grasp is None else np.asarray(grasp, float),
        placement=placement, record=record,
    )
    runner = PickRunner(request)
    return runner, runner.run()


def with_mass(record, mass):
    """The same object with another mass (inertia scaled with it)."""
    factor = mass / record.mass
    return dataclasses.replace(record, mass=mass, inertia=(np.asarray(record.inertia) * factor).tolist())


def test_top_face_centre_of_a_box_seals_lifts_and_reaches_the_bin():
    # Flat top face, COM on the cup axis: every lip sphere touches the face, the pull needed is
    # m g = 2.7 N < V = 8.84 N and there is no torque: the box is lifted, carried and held.
    record = load_object("basic/box_tea")  # 14 x 7 x 7 cm, 0.27 kg; top face at z = +0.035
    _, result = pick(record=record, grasp=[0, 0, 0.035, 0, 0, -1])
    assert result["valid"] and result["success"], result
    assert result["lifted"] and result["in_bin"] and result["seal_time"] is not None
    assert result["peak_slip"] < 0.005


def test_grasp_across_a_box_edge_never_seals():
    # Straight down on the edge of the top face: half of the lip ring hangs beyond the box, so
    # not every lip sphere can touch it - no seal, whatever the vacuum does.
    _, result = pick(record=load_object("basic/box_tea"), grasp=[0.07, 0, 0.035, 0, 0, -1])
    assert result["valid"] and not result["success"]
    assert result["failure"] == "no_seal"


def test_sphere_smaller_than_the_cup_cannot_be_sealed(tmp_path):
    # A 6 mm sphere lies entirely within 6 mm of its vertical axis, so a lip ring of radius
    # 7.5 mm centred on that axis cannot touch it all around (it ends up around it).
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.006)
    spec = ObjectSpec(name="small_sphere", set="custom", generator="import", density=1000.0)
    record = build_object(sphere, spec, tmp_path / "small_sphere")
    rot = record.most_probable_pose()[:3, :3]  # world top and straight down, in the object frame
    _, result = pick(record=record, grasp=[*(rot.T @ [0, 0, 0.006]), *(rot.T @ [0, 0, -1.0])])
    assert result["valid"] and result["failure"] == "no_seal"


def test_object_heavier_than_the_vacuum_can_hold_drops():
    # 1.3 kg weighs 12.7 N > V = 8.84 N: the seal forms on contact, but the lift tears it off.
    heavy = with_mass(load_object("basic/box_tea"), 1.3)
    assert heavy.mass * STANDARD_GRAVITY > CUP_DEFAULT.vacuum_force
    _, result = pick(record=heavy, grasp=[0, 0, 0.035, 0, 0, -1])
    assert result["valid"] and not result["success"]
    assert result["failure"] in ("seal_lost_lift", "not_lifted")


def test_long_bar_drops_when_gripped_far_from_its_centre_of_mass():
    # A 20 cm bar of 0.3 kg on its side face. Centred: pull 2.9 N < V, no torque: held.
    # 8 cm off-centre: gravity exerts 0.08 m x 2.9 N = 0.24 N m about the cup, while the vacuum can
    # hold an object against tipping about the lip's edge only up to V r = 0.066 N m (the pull
    # acts at the ring's centre, r from the pivot): the bar peels off or rotates away.
    bar = with_mass(load_object("basic/box_stick"), 0.3)  # 0.20 x 0.025 x 0.025 m
    pose = bar.most_probable_pose()
    up_axis = np.argmax(np.abs(pose[2, :3]))  # object axis that points up in the stable pose
    direction = -np.sign(pose[2, up_axis])
    long_axis = int(np.argmax(bar.extents))
    def grasp(offset):
        point = np.zeros(3)
        point[up_axis] = -direction * bar.extents[up_axis] / 2
        point[long_axis] = offset
        approach = np.zeros(3)
        approach[up_axis] = direction
        return [*point, *approach]
    _, centred = pick(record=bar, grasp=grasp(0.0))
    _, far = pick(record=bar, grasp=grasp(0.08))
    assert centred["valid"] and centred["success"], centred
    assert far["valid"] and not far["success"], far
    assert far["failure"] in ("seal_lost_lift", "seal_lost_transport", "seal_lost_hold", "not_lifted")


def test_tool_reaches_a_grid_of_workspace_points_within_joint_limits():
    # The workspace of the benchmark: objects up to 10 cm tall within 10 cm of the workspace
    # centre (0.45, -0.15); the tool tip must reach every grid point pointing straight down.
    runner = PickRunner(PickRequest("basic/box_tea"))
    model = runner.scene.model
    data = mujoco.MjData(model)
    data.qpos[:] = runner.scene.home_qpos
    q = np.asarray(HOME_RIGHT)
    limits = np.array([model.jnt_range[model.joint(j).id] for j in RIGHT_ARM_JOINTS])
    for x in (0.35, 0.45, 0.55):
        for y in (-0.25, -0.15, -0.05):
            for z in (0.0, 0.05, 0.10):
                result = solve_ik(model, data, runner.scene.cup.tip_site, RIGHT_ARM_JOINTS, np.array([x, y, z]),
                                  np.array([0.0, 0.0, -1.0]), q, axis_only=True, rest=np.asarray(HOME_RIGHT))
                assert result.success, (x, y, z)
                assert np.all(result.q >= limits[:, 0] - 1e-9) and np.all(result.q <= limits[:, 1] + 1e-9)


def test_same_seed_same_trajectory():
    first, a = pick("basic/cylinder_can", placement="drop", seed=4)
    second, b = pick("basic/cylinder_can", placement="drop", seed=4)
    np.testing.assert_array_equal(np.array(first.episode.trajectory), np.array(second.episode.trajectory))
    wall_clock = ("wall_time", "plan_time", "sensing_time")  # timings of this machine, not of the episode
    assert {k: v for k, v in a.items() if k not in wall_clock} == {k: v for k, v in b.items() if k not in wall_clock}
    third, _ = pick("basic/cylinder_can", placement="drop", seed=5)
    assert len(third.episode.trajectory) != len(first.episode.trajectory) or not np.array_equal(
        np.array(first.episode.trajectory), np.array(third.episode.trajectory)
    )


def test_scene_model_hygiene_everything_is_named():
    model = PickRunner(PickRequest("typical/mug_classic")).scene.model
    kinds = {
        mujoco.mjtObj.mjOBJ_BODY: model.nbody, mujoco.mjtObj.mjOBJ_GEOM: model.ngeom,
        mujoco.mjtObj.mjOBJ_JOINT: model.njnt, mujoco.mjtObj.mjOBJ_SITE: model.nsite,
        mujoco.mjtObj.mjOBJ_ACTUATOR: model.nu, mujoco.mjtObj.mjOBJ_CAMERA: model.ncam,
        mujoco.mjtObj.mjOBJ_LIGHT: model.nlight,
    }
    for kind, count in kinds.items():
        names = [mujoco.mj_id2name(model, kind, i) for i in range(count)]
        start = 1 if kind == mujoco.mjtObj.mjOBJ_BODY else 0  # body 0 is MuJoCo's world
        assert all(names[start:]), (kind, names)
        assert len(set(names[start:])) == len(names[start:]), kind


ALL = [r.key for s in SETS for r in list_objects(s)]


@pytest.mark.slow
@pytest.mark.parametrize("key", ALL)
def test_every_object_rests_and_produces_a_valid_episode(key):
    _, result = pick(key, placement="stable", seed=0)
    assert result["valid"], result


@pytest.mark.parametrize("key", ["basic/tube_pipe", "typical/bottle_wine", "adversarial/narrow_gear"])
def test_sample_objects_produce_valid_episodes(key):
    # The fast-suite share of test_every_object_rests_and_produces_a_valid_episode.
    _, result = pick(key, placement="drop", seed=1)
    assert result["valid"], result


def test_pick_writes_a_readable_mcap_log(tmp_path):
    from suctionbench.runlog.reader import iter_messages, read_episode

    runner = PickRunner(PickRequest("basic/box_tea", placement="stable", seed=2))
    result = runner.run(log=tmp_path / "episode.mcap")
    logged = read_episode(tmp_path / "episode.mcap")
    assert logged["result"]["success"] == result["success"]
    assert logged["metadata"]["seed"] == 2 and logged["metadata"]["object"] == "basic/box_tea"
    for topic in ("/camera/depth", "/camera/calibration", "/tf", "/joint_states", "/suction", "/grasps/candidates"):
        assert logged["topics"].get(topic, 0) >= 1, topic
    times = [t for t, _ in iter_messages(tmp_path / "episode.mcap", "/suction")]
    assert times == sorted(times) and times[-1] <= logged["duration"] + times[0] + 1e-6
