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


def smoothed_approaches(
    mesh: trimesh.Trimesh, points: np.ndarray, approaches: np.ndarray, radius: float, rng: np.random.Generator,
    *, per_disc: int = 100, max_samples: int = 200_000,
) -> np.ndarray:
    """Approaches along the surface normal averaged over a ball of `radius` around each point, as a
    depth-image policy estimates them: at an edge or a ridge it sees the blend of the faces, not
    either face's normal. Surface facing more than 120 deg away from the grasp's own face is left
    out, so the far side of a thin part does not cancel it while both faces of a box edge count.

    The average is over points uniform over the surface area (area-weighted), about `per_disc` of
    them per disc of `radius` (at most `max_samples` in all); a point with no neighbour keeps its
    approach.
    """
    from scipy.spatial import cKDTree

    samples = int(np.clip(mesh.area * per_disc / (np.pi * radius**2), 1000, max_samples))
    cloud, cloud_approaches = sample_surface_grasps(mesh, samples, rng)
    tree = cKDTree(cloud)
    smoothed = np.array(approaches, dtype=float, copy=True)
    for i, neighbours in enumerate(tree.query_ball_point(points, radius)):
        near = cloud_approaches[neighbours]
        near = near[near @ approaches[i] > -0.5]
        if len(near):
            mean = near.sum(axis=0)
            smoothed[i] = mean / np.linalg.norm(mean)
    return smoothed
