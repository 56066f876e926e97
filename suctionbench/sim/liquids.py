"""Levelling the liquids of simulated objects: MuJoCo bodies have fixed mass properties, so a
part-filled bottle's liquid is moved by hand, quasi-statically (`objects.liquid`): each time the
object comes to rest, its body's centre of mass and inertia are set to those of the object with
the liquid level in its current pose. `PickEpisode.settle` calls `level` and keeps settling while
the centre of mass moves (a bottle on a slope may roll on once its liquid has run down).

A reset puts back the bodies' mass properties as built (liquid filled upright), so every episode
starts from the same model."""

from __future__ import annotations

import copy
from collections.abc import Iterable

import mujoco
import numpy as np

from suctionbench.objects.liquid import Liquid
from suctionbench.objects.mass import MassProperties

LEVEL_SHIFT = 5e-4
"""A levelling that moves an object's centre of mass by more than this (m) may change how it rests:
`PickEpisode.settle` waits for it to come to rest again."""


DERIVED = ("body_subtreemass", "body_invweight0", "dof_invweight0", "dof_M0")
"""mjModel fields mj_setConst derives from bodies' mass properties at qpos0."""


CORNERS = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])
"""The corners of a box of half-sizes 1, (8, 3)."""


def rotation_matrix(quat: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) of a unit quaternion (w, x, y, z)."""
    out = np.zeros(9)
    mujoco.mju_quat2Mat(out, np.asarray(quat, dtype=float))
    return out.reshape(3, 3)


def principal_axes(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo's form of an inertia tensor: principal moments (3,) and the unit quaternion (w, x, y,
    z) of the frame of principal axes in the body frame."""
    moments, axes = np.linalg.eigh(0.5 * (inertia + inertia.T))
    if np.linalg.det(axes) < 0.0:  # a right-handed frame
        axes[:, 2] = -axes[:, 2]
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(axes).ravel())
    return moments, quat


class LiquidBodies:
    """The object bodies of a compiled model that hold a liquid (body id -> `Liquid`)."""

    def __init__(self, model: mujoco.MjModel, liquids: dict[int, Liquid]):
        self.model = model
        self.liquids = liquids
        self._built = {b: (model.body_ipos[b].copy(), model.body_iquat[b].copy(), model.body_inertia[b].copy())
                       for b in liquids}
        self._built_sameframe = {b: int(model.body_sameframe[b]) for b in liquids}
        self._bvh = {b: slice(int(model.body_bvhadr[b]), int(model.body_bvhadr[b] + model.body_bvhnum[b]))
                     for b in liquids}
        self._built_bvh = {b: model.bvh_aabb[nodes].copy() for b, nodes in self._bvh.items()}
        self._changed = False

    def level(self, data: mujoco.MjData, bodies: Iterable[int]) -> float:
        """Level the liquid of each of `bodies` that holds one for its current orientation in
        `data` (gravity along world -z); returns the largest move (m) of a centre of mass."""
        m = self.model
        moved, levelled = 0.0, False
        for b in bodies:
            liquid = self.liquids.get(b)
            if liquid is None:
                continue
            down = data.xmat[b].reshape(3, 3).T @ np.array([0.0, 0.0, -1.0])  # world down in the body frame
            props: MassProperties = liquid.properties(down)
            moved = max(moved, float(np.linalg.norm(props.com - m.body_ipos[b])))
            m.body_ipos[b] = props.com
            m.body_inertia[b], m.body_iquat[b] = principal_axes(props.inertia)
            # The compiler marks a body whose inertial frame is its own frame, or has its
            # orientation (an upright can), and kinematics then skips the inertial frame's
            # rotation: left so, the levelled inertia acts about the wrong axes and the bounding
            # boxes below are placed by the wrong frame (a lying can's parts 17 mm outside them).
            m.body_sameframe[b] = mujoco.mjtSameFrame.mjSAMEFRAME_NONE
            self._move_bounding_boxes(b)
            levelled = self._changed = True
        if levelled:
            self._set_constants()
        return moved

    def restore(self) -> None:
        """The bodies' mass properties as built (contents filled upright)."""
        if not self._changed:
            return
        for b, (ipos, iquat, inertia) in self._built.items():
            self.model.body_ipos[b], self.model.body_iquat[b], self.model.body_inertia[b] = ipos, iquat, inertia
            self.model.bvh_aabb[self._bvh[b]] = self._built_bvh[b]
            self.model.body_sameframe[b] = self._built_sameframe[b]
        self._set_constants()
        self._changed = False

    def _move_bounding_boxes(self, body: int) -> None:
        """Re-express the body's collision bounding boxes in its new inertial frame. MuJoCo's
        mid-phase keeps each body's tree of geom bounding boxes in the body's inertial frame (centre
        of mass, principal axes): left in the built frame, they miss the geoms by the frame's move,
        and a part of the object passes through the table uncollided. Each built box's corners are
        taken to the new frame and bounded again (a box that turned grows: still conservative)."""
        m = self.model
        ipos0, iquat0, _ = self._built[body]
        built = self._built_bvh[body]
        turn0, turn = rotation_matrix(iquat0), rotation_matrix(m.body_iquat[body])
        corners = built[:, None, :3] + built[:, None, 3:] * CORNERS[None]  # (K, 8, 3), built frame
        moved = (ipos0 + corners @ turn0.T - m.body_ipos[body]) @ turn  # body frame, then the new frame
        lo, hi = moved.min(axis=1), moved.max(axis=1)
        m.bvh_aabb[self._bvh[body]] = np.hstack([(lo + hi) / 2.0, (hi - lo) / 2.0])

    def _set_constants(self) -> None:
        """Recompute the model's quantities that derive from mass properties (DERIVED: the inverse
        weights at qpos0 that scale constraint softness, ...). mj_setConst runs on a copy of the
        model: it also recomputes fields an episode changes at run time (a parked object's body
        collision bits, from its geoms' cleared ones), which must stay as the episode set them."""
        scratch = copy.copy(self.model)
        mujoco.mj_setConst(scratch, mujoco.MjData(scratch))
        for name in DERIVED:
            getattr(self.model, name)[:] = getattr(scratch, name)
