"""The cluttered-bin scene: the pick workspace (`suctionbench.sim.scene`) with a pick bin at the
workspace centre holding several objects, and the receptacle bin at the side as before.

Why a bin and not a heap on the table: the walls keep a pile together, are what a real pick
cell has, and add the failure modes clutter brings (the cup or arm meeting a wall, an object
dragged over the rim).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from suctionbench.config import CupConfig
from suctionbench.objects.build import ObjectRecord
from suctionbench.sensing.camera import CameraIntrinsics
from suctionbench.sensing.camera_pose import CameraPoseConfig
from suctionbench.sim.cup import SimCupConfig
from suctionbench.sim.scene import Scene, SceneConfig, add_open_box, assemble_scene

PICK_BIN = "pick_bin"
"""Name prefix of the pick bin's geoms (PICK_BIN_floor, PICK_BIN_wall_xp, ...)."""


@dataclass(frozen=True)
class PickBinConfig:
    """The bin the objects are picked from (metres, world frame; table top at z = 0)."""

    centre: tuple[float, float] = SceneConfig().workspace_centre
    """Centre of the bin: the workspace centre, where the camera looks and the right arm reaches."""

    inner: tuple[float, float] = (0.34, 0.30)
    """Inner width (x) and depth (y): the largest evaluation object (a 25 x 19 cm cereal box) lies
    flat in it with room to spare, and every point of its floor is within the YuMi's reach with
    the cup pointing down."""

    wall_height: float = 0.08
    """Height of the walls above the table: half the height of the tallest object lying down, so
    a pile stays in the bin while the cup, 2 cm wide, still reaches past the rim at 30 deg."""

    wall: float = 0.01
    """Wall and floor thickness (the inner floor is at z = wall)."""

    def contains(self, xy: np.ndarray, margin: float = 0.0) -> np.ndarray:
        """Whether world points (..., 2+) lie over the bin's inner floor, shrunk by `margin`."""
        xy = np.asarray(xy, dtype=float)
        (cx, cy), (w, d) = self.centre, self.inner
        return (np.abs(xy[..., 0] - cx) <= w / 2 - margin) & (np.abs(xy[..., 1] - cy) <= d / 2 - margin)

    @property
    def floor(self) -> float:
        """Height (m) of the inner floor."""
        return self.wall

    def workspace(self, margin: float = 0.005, clearance: float = 0.005, top: float = 1.0
                  ) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) corners of the bin's inner volume as a world box (Dex-Net's "3D bounds on
        the workspace"): `margin` inside the walls, from `clearance` above the floor up to `top`."""
        (cx, cy), (w, d) = self.centre, self.inner
        lower = np.array([cx - w / 2 + margin, cy - d / 2 + margin, self.floor + clearance])
        upper = np.array([cx + w / 2 - margin, cy + d / 2 - margin, top])
        return lower, upper


FLOOR_DEPTH = 0.75
"""The room's floor, this far (m) below the table top (a table's usual height)."""

BIN_CAMERA = CameraPoseConfig(radius_range=(0.6, 0.7), polar_range=(0.0, 0.05 * math.pi))
"""Camera poses over a bin: nearly overhead (at most 9 deg off vertical, the paper's range goes
to 18 deg), as bin-picking cells mount their cameras, so that the walls hide little of the
floor; 0.6-0.7 m away, the far half of the paper's range, so the whole bin is in view."""


def build_bin_scene(
    records: Sequence[ObjectRecord],
    cup: CupConfig,
    intrinsics: CameraIntrinsics,
    camera_pose: np.ndarray,
    *,
    bin_config: PickBinConfig | None = None,
    sim_cup: SimCupConfig | None = None,
) -> Scene:
    """The workspace with the pick bin and one body per record (object_00, object_01, ...; the
    episode drops them in)."""
    bin_config = bin_config or PickBinConfig()

    def add_bin(world: mujoco.MjsBody, env: dict) -> None:
        world.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[3, 3, 0.1],
                       pos=[0, 0, -FLOOR_DEPTH], **env)  # what falls off the table lands somewhere
        add_open_box(world, PICK_BIN, bin_config.centre, (*bin_config.inner, bin_config.wall_height),
                     bin_config.wall, env, rgba=(0.35, 0.4, 0.55, 1))

    names = [f"object_{i:02d}" for i in range(len(records))]
    return assemble_scene(records, cup, intrinsics, camera_pose, sim_cup=sim_cup, names=names, add_world=add_bin,
                          floating=True)
