"""Grasp candidates: points uniform on the surface with inward normals (the paper's p(u | x))."""

from __future__ import annotations

import numpy as np
import trimesh


def sample_surface_grasps(
    mesh: trimesh.Trimesh, count: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """`count` points uniform over the surface area and their inward face normals as approaches.

    Returns (points (N, 3), approaches (N, 3)); the approach points from the gripper into the
    object, i.e. minus the outward surface normal.
    """
    areas = np.asarray(mesh.area_faces, dtype=float)
    faces = rng.choice(len(areas), size=count, p=areas / areas.sum())
    u, w = rng.random(count), rng.random(count)
    flip = u + w > 1.0  # fold the unit square onto the triangle: uniform barycentrics
    u[flip], w[flip] = 1.0 - u[flip], 1.0 - w[flip]
    tri = np.asarray(mesh.triangles)[faces]
    points = tri[:, 0] + u[:, None] * (tri[:, 1] - tri[:, 0]) + w[:, None] * (tri[:, 2] - tri[:, 0])
    approaches = -np.asarray(mesh.face_normals)[faces]
    return points, approaches
