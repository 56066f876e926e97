"""The ABB YuMi (IRB 14000) model: its MJCF, joint names, speed limits, home pose and flange pose.

The kinematics come from the BSD-licensed OrebroUniversity/yumi URDF (see assets/yumi/yumi.xml for
the conventions: URDF joint and link names, chain order j1 -> j2 -> j7 -> j3 -> j4 -> j5 -> j6,
collision bitmasks). Arm configurations are always given in chain order, as in the URDF.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType

import mujoco
import numpy as np

from suctionbench.resources import asset_path

CHAIN_JOINT_NUMBERS = (1, 2, 7, 3, 4, 5, 6)
"""URDF joint numbers along the chain from shoulder to flange (URDF "joint 7" is the third)."""

RIGHT_ARM_JOINTS = tuple(f"yumi_joint_{k}_r" for k in CHAIN_JOINT_NUMBERS)
"""Right-arm joint (and actuator) names in chain order: the order of every right-arm q vector."""

LEFT_ARM_JOINTS = tuple(f"yumi_joint_{k}_l" for k in CHAIN_JOINT_NUMBERS)
"""Left-arm joint (and actuator) names in chain order."""

RIGHT_FLANGE_SITE = "yumi_flange_r"
"""Site at the right tool flange (z axis out of the flange): where the suction tool mounts."""



def _read_only(values) -> np.ndarray:
    array = np.array(values, dtype=float)
    array.setflags(write=False)
    return array


JOINT_SPEED_LIMITS: Mapping[str, float] = MappingProxyType({
    name: float(np.deg2rad(180.0 if number in (1, 2, 7, 3) else 400.0))
    for arm in (RIGHT_ARM_JOINTS, LEFT_ARM_JOINTS)
    for name, number in zip(arm, CHAIN_JOINT_NUMBERS, strict=True)
})
"""Maximum speed (rad/s) of each joint, by joint name (both arms): 180 deg/s for j1, j2, j7, j3
and 400 deg/s for j4, j5, j6 (ABB IRB 14000 data, as in the URDF velocity limits). Read-only."""

HOME_RIGHT = _read_only([1.2144, -1.0321, -1.1007, 0.2987, -1.8526, 1.2536, -2.4218])
"""Right-arm home configuration (rad, chain order): flange at about (0.500, -0.200, 0.256) m with
its z axis straight down (forward kinematics of the public OrebroUniversity/yumi URDF); the keyframe
"home" of yumi.xml uses it."""


def yumi_xml_path() -> Path:
    """Path of the YuMi MJCF, valid in a checkout and in an installed wheel."""
    return asset_path("yumi", "yumi.xml")


def load_yumi_spec() -> mujoco.MjSpec:
    """A fresh, editable MjSpec of the YuMi, for a scene to attach tools and objects to."""
    return mujoco.MjSpec.from_file(str(yumi_xml_path()))


@functools.cache
def _yumi_model() -> mujoco.MjModel:
    """The compiled robot alone, compiled once: MjModel is read-only here, so sharing it is safe."""
    return load_yumi_spec().compile()


def flange_pose(q_right) -> np.ndarray:
    """World pose (4x4 homogeneous matrix) of the right flange site for configuration `q_right`.

    Pure kinematics on the robot model alone (mj_kinematics), so it is the ground truth that IK
    and scene code are tested against; a fresh MjData per call keeps it thread-safe.
    """
    q_right = np.asarray(q_right, dtype=float)
    if q_right.shape != (len(RIGHT_ARM_JOINTS),):
        raise ValueError(f"q_right must have shape ({len(RIGHT_ARM_JOINTS)},), got {q_right.shape}")
    model = _yumi_model()
    data = mujoco.MjData(model)
    for name, value in zip(RIGHT_ARM_JOINTS, q_right, strict=True):
        data.qpos[model.joint(name).qposadr[0]] = value
    mujoco.mj_kinematics(model, data)
    site_id = model.site(RIGHT_FLANGE_SITE).id
    pose = np.eye(4)
    pose[:3, :3] = data.site_xmat[site_id].reshape(3, 3)
    pose[:3, 3] = data.site_xpos[site_id]
    return pose
