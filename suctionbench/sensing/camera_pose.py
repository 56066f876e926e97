"""Where the camera looks from: the paper's camera-pose distribution (`CameraPoseConfig`, a
spherical shell around the target) and the pose it gives (`sample_camera_pose`), in the OpenCV
optical frame of `suctionbench.sensing.camera` (x right, y down, z along the optical axis)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from suctionbench.errors import InputError
from suctionbench.sensing.camera import CameraIntrinsics


@dataclass(frozen=True)
class CameraPoseConfig:
    """The paper's camera-pose distribution p(T_c) ("Details of Distributions"): spherical
    coordinates about a target point, uniform in each coordinate, with the optical axis through
    the target (the paper's table centre)."""

    radius_range: tuple[float, float] = (0.5, 0.7)
    """Range of the distance r in metres from the camera centre to the target, which is also the
    target's depth since it lies on the optical axis. Paper: [0.5, 0.7]."""

    azimuth_range: tuple[float, float] = (0.0, 2.0 * math.pi)
    """Range of the azimuth theta in radians, measured in the world xy plane from +x towards +y.
    Paper: [0, 2 pi)."""

    polar_range: tuple[float, float] = (0.01 * math.pi, 0.1 * math.pi)
    """Range of the polar angle phi in radians between the world +z axis and the direction from
    the target to the camera (0 = straight overhead). Paper: [0.01 pi, 0.1 pi], i.e. 1.8-18 deg."""

    def __post_init__(self) -> None:
        bounds = {  # key -> (smallest allowed low, exclusive ceiling of high)
            "radius_range": (0.0, math.inf),
            "azimuth_range": (-math.inf, math.inf),
            "polar_range": (0.0, math.pi / 2),
        }
        for key, (floor, ceiling) in bounds.items():
            value = getattr(self, key)
            ok = (
                len(value) == 2
                and all(isinstance(x, int | float) and math.isfinite(x) for x in value)
                and floor <= value[0] <= value[1] < ceiling
                and (key != "radius_range" or value[0] > 0.0)
            )
            if not ok:
                raise InputError(f"camera pose config: {key} = {value!r} is not a valid (low, high) range")

    def for_camera(self, intrinsics: CameraIntrinsics) -> CameraPoseConfig:
        """This distribution with its radius range fitted into the camera's working range.

        The radius range is clipped to [min_depth, max_depth]; where it lies wholly outside, it
        keeps its width and slides to the nearest end of the working range (shrinking only if the
        working range is narrower). Clipping rather than scaling by focal length: the paper's
        range was tuned on a real robot (by average precision of the labels), so a camera that can
        see the scene from there should reproduce it unchanged, and every preset's working range
        contains [0.5, 0.7] m; scaling to keep object sizes in pixels would instead move, e.g., the
        Zivid preset (fx = 1800 px) to 1.7-2.4 m, beyond its range. Only the target depth is
        fitted; object tops are closer than the radius by up to their height.
        """
        lo, hi = self.radius_range
        near, far = intrinsics.min_depth, intrinsics.max_depth
        new_lo, new_hi = max(lo, near), min(hi, far)
        if new_lo > new_hi:  # wholly outside: keep the width, slide inside
            width = min(hi - lo, far - near)
            new_lo, new_hi = (near, near + width) if hi < near else (far - width, far)
        return replace(self, radius_range=(new_lo, new_hi))


CAMERA_POSE_PAPER = CameraPoseConfig()
"""The paper's distribution: r in [0.5, 0.7] m, azimuth in [0, 2 pi), polar in [0.01 pi, 0.1 pi]."""


def camera_pose_from_spherical(target, radius: float, azimuth: float, polar: float) -> np.ndarray:
    """World-from-camera pose (4x4, OpenCV frame) at spherical coordinates about `target`.

    The camera sits at target + r (sin phi cos theta, sin phi sin theta, cos phi) with its z axis
    pointing at the target. Roll about the optical axis is fixed so that the camera x axis is
    horizontal and the image's down direction (+y) points, seen from above, towards the camera's
    own side of the target, as for a person looking down at a table: the near side of the table is
    at the bottom of the image. The roll follows the azimuth (the image turns with the camera
    around the table), and it stays defined at phi = 0 because it is built from theta, not from
    the (then vertical) viewing direction.
    """
    target = np.asarray(target, dtype=float).reshape(3)
    st, ct, sp, cp = math.sin(azimuth), math.cos(azimuth), math.sin(polar), math.cos(polar)
    outward = np.array([sp * ct, sp * st, cp])  # target -> camera
    z = -outward
    horizontal = np.array([ct, st, 0.0])
    y = horizontal - (horizontal @ z) * z  # in the vertical plane through the axis, leaning outwards
    y /= np.linalg.norm(y)
    x = np.cross(y, z)  # horizontal, completes a right-handed frame (x = y cross z)
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([x, y, z])
    pose[:3, 3] = target + radius * outward
    return pose


def sample_camera_pose(
    rng: np.random.Generator, target, config: CameraPoseConfig = CAMERA_POSE_PAPER
) -> np.ndarray:
    """Draw one world-from-camera pose (4x4, OpenCV frame) from `config` about `target`.

    Draws r, theta, phi (in that order, one call) uniformly from their ranges, so the pose is a
    deterministic function of the generator state.
    """
    (r0, r1), (a0, a1), (p0, p1) = config.radius_range, config.azimuth_range, config.polar_range
    radius, azimuth, polar = rng.uniform([r0, a0, p0], [r1, a1, p1])
    return camera_pose_from_spherical(target, radius, azimuth, polar)
