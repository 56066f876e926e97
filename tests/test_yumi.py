"""The YuMi model (assets/yumi/yumi.xml) and the DLS inverse kinematics (suctionbench.sim.ik)."""

from __future__ import annotations

import itertools

import mujoco
import numpy as np
import pytest

from suctionbench.sim.ik import solve_ik, solve_ik_position_axis
from suctionbench.sim.yumi import (
    HOME_RIGHT,
    JOINT_SPEED_LIMITS,
    LEFT_ARM_JOINTS,
    RIGHT_ARM_JOINTS,
    RIGHT_FLANGE_SITE,
    flange_pose,
    load_yumi_spec,
    yumi_xml_path,
)

# Right arm of the BSD-licensed OrebroUniversity/yumi URDF, in chain order
# j1 -> j2 -> j7 -> j3 -> j4 -> j5 -> j6: joint origin xyz (m) and rpy (rad) in the parent link,
# then the fixed flange frame (0.007 m along link-7 z, rotated pi about z).
HALF_PI = np.pi / 2
URDF_RIGHT_CHAIN = [
    ((0.05355, -0.0725, 0.41492), (-0.9795, -0.5682, -2.3155)),
    ((0.03, 0.0, 0.1), (HALF_PI, 0.0, 0.0)),
    ((-0.03, 0.17283, 0.0), (-HALF_PI, 0.0, 0.0)),
    ((-0.04188, 0.0, 0.07873), (HALF_PI, -HALF_PI, 0.0)),
    ((0.0405, 0.16461, 0.0), (-HALF_PI, 0.0, 0.0)),
    ((-0.027, 0.0, 0.10039), (HALF_PI, 0.0, 0.0)),
    ((0.027, 0.029, 0.0), (-HALF_PI, 0.0, 0.0)),
]
URDF_FLANGE = ((0.0, 0.0, 0.007), (0.0, 0.0, np.pi))
URDF_LIMITS_DEG = [(-168.5, 168.5), (-143.5, 43.5), (-168.5, 168.5), (-123.5, 80.0),
                   (-290.0, 290.0), (-88.0, 138.0), (-229.0, 229.0)]

DOWN = np.array([0.0, 0.0, -1.0])


def _rot(axis: int, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    rot = np.eye(3)
    rot[i, i], rot[i, j], rot[j, i], rot[j, j] = c, -s, s, c
    return rot


def _urdf_transform(xyz, rpy, joint_angle: float = 0.0) -> np.ndarray:
    """URDF joint: origin rotation R = Rz(yaw) Ry(pitch) Rx(roll), then rotation about local z."""
    roll, pitch, yaw = rpy
    transform = np.eye(4)
    transform[:3, :3] = _rot(2, yaw) @ _rot(1, pitch) @ _rot(0, roll) @ _rot(2, joint_angle)
    transform[:3, 3] = xyz
    return transform


def urdf_flange_pose(q) -> np.ndarray:
    """Independent numpy forward kinematics of the URDF table (no MuJoCo, no euler conventions)."""
    pose = np.eye(4)
    for (xyz, rpy), angle in zip(URDF_RIGHT_CHAIN, q, strict=True):
        pose = pose @ _urdf_transform(xyz, rpy, angle)
    return pose @ _urdf_transform(*URDF_FLANGE)


@pytest.fixture(scope="module")
def model() -> mujoco.MjModel:
    return load_yumi_spec().compile()


@pytest.fixture
def data(model) -> mujoco.MjData:
    return mujoco.MjData(model)


def _right_limits(model) -> tuple[np.ndarray, np.ndarray]:
    return np.array([model.joint(name).range for name in RIGHT_ARM_JOINTS]).T


# -- forward kinematics ---------------------------------------------------------------------------

def test_zero_configuration_matches_facts():
    # The URDF's chain: all zeros put the right flange at about (0.568, 0.006, 0.415).
    np.testing.assert_allclose(flange_pose(np.zeros(7))[:3, 3], [0.568, 0.006, 0.415], atol=5e-3)


def test_home_configuration_points_down_at_facts_position():
    # The URDF's chain: joints [1.2144, -1.0321, -1.1007, 0.2987, -1.8526, 1.2536, -2.4218] (chain
    # order) "put the right flange at about (0.500, -0.200, 0.256) m pointing straight down".
    pose = flange_pose(HOME_RIGHT)
    np.testing.assert_allclose(pose[:3, 3], [0.500, -0.200, 0.256], atol=5e-3)
    tilt = np.arccos(np.clip(pose[:3, 2] @ DOWN, -1.0, 1.0))
    assert tilt < np.deg2rad(3.0)


def test_mjcf_euler_xyz_equals_urdf_rpy():
    # The MJCF writes URDF rpy as euler="r p y" under eulerseq="XYZ"; an independent product of
    # URDF transforms must give the same flange pose everywhere, not only at two configurations.
    rng = np.random.default_rng(7)
    lower, upper = np.deg2rad(URDF_LIMITS_DEG).T
    for q in rng.uniform(lower, upper, size=(20, 7)):
        np.testing.assert_allclose(flange_pose(q), urdf_flange_pose(q), atol=1e-5)


def test_joint_limits_actuators_and_speed_limits(model):
    lower, upper = _right_limits(model)
    np.testing.assert_allclose(np.rad2deg(np.stack([lower, upper], axis=1)), URDF_LIMITS_DEG, atol=1e-3)
    for name in RIGHT_ARM_JOINTS + LEFT_ARM_JOINTS:
        np.testing.assert_allclose(model.actuator(name).ctrlrange, model.joint(name).range, rtol=0, atol=1e-12)
        assert model.actuator(name).trntype == mujoco.mjtTrn.mjTRN_JOINT
        assert model.actuator(name).trnid[0] == model.joint(name).id
    speeds = np.rad2deg([JOINT_SPEED_LIMITS[name] for name in RIGHT_ARM_JOINTS])
    np.testing.assert_allclose(speeds, [180, 180, 180, 180, 400, 400, 400])


# -- model hygiene --------------------------------------------------------------------------------

NAMED_TYPES = [
    (mujoco.mjtObj.mjOBJ_BODY, "nbody"), (mujoco.mjtObj.mjOBJ_JOINT, "njnt"),
    (mujoco.mjtObj.mjOBJ_GEOM, "ngeom"), (mujoco.mjtObj.mjOBJ_SITE, "nsite"),
    (mujoco.mjtObj.mjOBJ_CAMERA, "ncam"), (mujoco.mjtObj.mjOBJ_LIGHT, "nlight"),
    (mujoco.mjtObj.mjOBJ_MESH, "nmesh"), (mujoco.mjtObj.mjOBJ_MATERIAL, "nmat"),
    (mujoco.mjtObj.mjOBJ_TENDON, "ntendon"), (mujoco.mjtObj.mjOBJ_ACTUATOR, "nu"),
    (mujoco.mjtObj.mjOBJ_SENSOR, "nsensor"), (mujoco.mjtObj.mjOBJ_EQUALITY, "neq"),
    (mujoco.mjtObj.mjOBJ_KEY, "nkey"),
]


@pytest.mark.parametrize(("obj_type", "count"), NAMED_TYPES, ids=[c for _, c in NAMED_TYPES])
def test_every_element_has_a_unique_name(model, obj_type, count):
    names = [mujoco.mj_id2name(model, obj_type, i) for i in range(getattr(model, count))]
    assert all(names), f"unnamed {obj_type}: {names}"
    assert len(set(names)) == len(names), f"duplicate {obj_type} names"


def test_collision_bitmasks_and_groups(model):
    for geom in range(model.ngeom):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, geom)
        if name.endswith("_collision"):
            assert (model.geom_contype[geom], model.geom_conaffinity[geom], model.geom_group[geom]) == (2, 1, 3)
        else:
            assert name.endswith("_visual")
            assert (model.geom_contype[geom], model.geom_conaffinity[geom], model.geom_group[geom]) == (0, 0, 1)


def test_no_self_collision(model, data):
    # The bitmasks switch self-collision off: no contacts even when the links overlap.
    rng = np.random.default_rng(3)
    lower, upper = model.jnt_range.T
    for q in rng.uniform(lower, upper, size=(20, model.nq)):
        data.qpos[:] = q
        mujoco.mj_forward(model, data)
        assert data.ncon == 0


def _geom_extent(model, data, geom: int, axis: int) -> tuple[float, float]:
    """Conservative bounds of a capsule or cylinder geom along a world axis."""
    radius, half_length = model.geom_size[geom, :2]
    centre, direction = data.geom_xpos[geom], data.geom_xmat[geom].reshape(3, 3)[:, 2]
    reach = abs(direction[axis]) * half_length + radius
    return centre[axis] - reach, centre[axis] + reach


def test_home_keyframe(model, data):
    key = model.key("home")
    right = [model.joint(name).qposadr[0] for name in RIGHT_ARM_JOINTS]
    np.testing.assert_array_equal(key.qpos[right], HOME_RIGHT)
    np.testing.assert_array_equal(key.ctrl, key.qpos)  # one actuator per joint, in joint order
    mujoco.mj_resetDataKeyframe(model, data, key.id)
    mujoco.mj_forward(model, data)
    for geom in range(model.ngeom):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, geom)
        if name.startswith("yumi_link") and name.endswith("_collision"):
            assert _geom_extent(model, data, geom, 2)[0] > 0.05, f"{name} near the table"
            if name.endswith("_l_collision"):  # the folded left arm stays on its own side
                assert _geom_extent(model, data, geom, 1)[0] > 0.0, f"{name} crosses y = 0"
    # The servos hold the keyframe: after 0.5 s the arm has not moved.
    for _ in range(250):
        mujoco.mj_step(model, data)
    np.testing.assert_allclose(data.qpos, key.qpos, atol=1e-4)


def test_yumi_xml_path_exists():
    assert yumi_xml_path().is_file()


# -- inverse kinematics ---------------------------------------------------------------------------

def _assert_within_limits(model, q):
    lower, upper = _right_limits(model)
    assert np.all(q >= lower) and np.all(q <= upper)


def test_ik_round_trip(model, data):
    # Random configurations over the full joint ranges (many far from home, some behind the body):
    # the flange pose they produce is reachable by construction. A single descent from home solves
    # about 70 % of them (66 % of these 50); deterministic restarts bring it to all 50.
    rng = np.random.default_rng(2024)
    lower, upper = _right_limits(model)
    successes = 0
    for q_true in rng.uniform(lower, upper, size=(50, 7)):
        target = flange_pose(q_true)
        result = solve_ik(model, data, RIGHT_FLANGE_SITE, RIGHT_ARM_JOINTS, target[:3, 3], target[:3, :3],
                          HOME_RIGHT, restarts=5)
        _assert_within_limits(model, result.q)
        if result.success:
            successes += 1
            reached = flange_pose(result.q)  # checked independently of the solver's own errors
            assert np.linalg.norm(reached[:3, 3] - target[:3, 3]) <= 1e-4
            cos_angle = (np.trace(reached[:3, :3].T @ target[:3, :3]) - 1.0) / 2.0
            assert np.arccos(np.clip(cos_angle, -1.0, 1.0)) <= 1.1e-3
    assert successes >= 48  # >= 95 %


# Flange pointing straight down over the picking area in front of the right arm. The reach with a
# vertical flange shrinks at low heights: x = 0.55 m is reachable at y = -0.30 only from z = 0.10,
# so the grid stops at x = 0.50 (every x in [0.15, 0.50] reaches z = 0.05 for y in [-0.35, 0.0]).
REACH_GRID = list(itertools.product(np.linspace(0.35, 0.50, 3), np.linspace(-0.30, 0.0, 4),
                                    np.linspace(0.05, 0.25, 3)))


def test_reach_grid_pointing_down(model, data):
    for point in REACH_GRID:
        result = solve_ik_position_axis(model, data, RIGHT_FLANGE_SITE, RIGHT_ARM_JOINTS, point, DOWN,
                                        HOME_RIGHT, rest=HOME_RIGHT)
        assert result.success, f"unreachable {point}: {result}"
        _assert_within_limits(model, result.q)
        reached = flange_pose(result.q)
        assert np.linalg.norm(reached[:3, 3] - point) <= 1e-4
        assert reached[:3, 2] @ DOWN >= np.cos(1e-3)


def test_axis_only_accepts_axis_or_rotation(model, data):
    # Only the z column of a rotation matters to the axis task.
    target = flange_pose(HOME_RIGHT)
    target[:3, 3] += [0.03, -0.05, -0.04]
    a = solve_ik_position_axis(model, data, RIGHT_FLANGE_SITE, RIGHT_ARM_JOINTS, target[:3, 3], target[:3, 2],
                               HOME_RIGHT)
    b = solve_ik(model, data, RIGHT_FLANGE_SITE, RIGHT_ARM_JOINTS, target[:3, 3], target[:3, :3], HOME_RIGHT,
                 axis_only=True)
    assert a.success and b.success
    np.testing.assert_array_equal(a.q, b.q)


def test_ik_is_deterministic_and_leaves_data_untouched(model, data):
    # Bit-identical output for identical inputs, including the state of `data`: the other joints
    # (here the left arm) enter the last bits of the Jacobian through the subtree centre of mass.
    other = mujoco.MjData(model)
    for d in (data, other):
        mujoco.mj_resetDataKeyframe(model, d, model.key("home").id)
        mujoco.mj_forward(model, d)
    qpos_before, xpos_before = data.qpos.copy(), data.xpos.copy()
    target = flange_pose(np.array([0.5, -0.8, -0.6, 0.2, -1.2, 1.0, 0.3]))
    args = (RIGHT_FLANGE_SITE, RIGHT_ARM_JOINTS, target[:3, 3], target[:3, :3], HOME_RIGHT)
    first = solve_ik(model, data, *args, rest=HOME_RIGHT, restarts=2)
    again = solve_ik(model, data, *args, rest=HOME_RIGHT, restarts=2)
    elsewhere = solve_ik(model, other, *args, rest=HOME_RIGHT, restarts=2)
    assert first.success
    for result in (again, elsewhere):
        np.testing.assert_array_equal(result.q, first.q)
        assert (result.pos_error, result.rot_error, result.iterations) == (
            first.pos_error, first.rot_error, first.iterations)
    np.testing.assert_array_equal(data.qpos, qpos_before)
    np.testing.assert_array_equal(data.xpos, xpos_before)
