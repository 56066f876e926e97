"""Where a grasp lies on the visible object, in metres: the pose stream's object context.

With a physical cup the robust label depends on the gravity torque about the grasp, i.e. on how
far the grasp lies from the object's centre of mass and how large the object is. The context
thumbnail shows the object around the grasp, but in pixels whose size changes with depth and with
a long object's centre often outside it. These numbers give the same facts in metres, from the
depth image any policy sees (the visible object: its pixels' points, segmented by a mask or by
height above the table), so the dataset generator and the policies compute them alike:

    0 offset        horizontal distance (m) from the grasp point to the visible object's centroid
    1 offset_along  the offset dotted with the approach's horizontal part (m x sin of the tilt):
                    where the centroid lies relative to the way the cup tilts, weighted by how
                    far it tilts; 0 for a vertical approach and continuous through it (an
                    approach estimated from a noisy depth image is never exactly vertical, a
                    mesh normal on a flat top is: a feature that jumped from 0 to the full
                    projection at vertical would differ between training and planning)
    2 rise          height (m) of the grasp point above the visible centroid
    3 length        extent (m) of the visible object along its main horizontal axis
    4 width         extent (m) across it
    5 height        the visible object's top above the table (m)

All are unchanged by the thumbnails' flips (training-time symmetrisation mirrors the image and
the approach's lean together). Extents and the top are taken between the 1st and 99th percentiles
of the points, so a few stray edge pixels (depth noise at the silhouette) do not set them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

OBJECT_CONTEXT_COLUMNS = ("offset", "offset_along", "rise", "length", "width", "height")
"""The features, in order (module docstring)."""

SPREAD_PERCENTILES = (1.0, 99.0)
"""Percentiles of the points' projections that bound the extents and the top."""


@dataclass(frozen=True)
class ObjectShape:
    """What the object context reads of the visible object, once per image: its points' centroid
    (3,) and horizontal extents and top above the table (module docstring, columns 3-5); None for
    an object with no point seen."""

    centroid: np.ndarray
    length: float
    width: float
    height: float

    @classmethod
    def of(cls, object_points: np.ndarray, table_height: float = 0.0) -> ObjectShape | None:
        """The shape of the object seen as `object_points` (M, 3), world frame (z up, the table
        at `table_height`); None when M = 0."""
        points = np.asarray(object_points, dtype=float).reshape(-1, 3)
        if len(points) == 0:
            return None
        centroid = points.mean(axis=0)
        flat = points[:, :2] - centroid[:2]
        _, vectors = np.linalg.eigh(flat.T @ flat)  # ascending: the main axis last
        lo, hi = SPREAD_PERCENTILES
        length, width = (float(np.subtract(*np.percentile(flat @ vectors[:, k], [hi, lo]))) for k in (1, 0))
        return cls(centroid, length, width, float(np.percentile(points[:, 2], hi) - table_height))


def object_context(object_points: np.ndarray | ObjectShape | None, grasp_points: np.ndarray,
                   approaches: np.ndarray, table_height: float = 0.0) -> np.ndarray:
    """(N, 6) float32 object context (module docstring) of grasps at `grasp_points` (N, 3) along
    `approaches` (N, 3, into the object) on the object seen as `object_points` (M, 3), or its
    `ObjectShape` when several calls share one image; all in the world frame (z up, the table at
    `table_height`). A grasp with no object point seen gets zeros."""
    grasp_points = np.asarray(grasp_points, dtype=float).reshape(-1, 3)
    approaches = np.asarray(approaches, dtype=float).reshape(-1, 3)
    shape = object_points if object_points is None or isinstance(object_points, ObjectShape) else \
        ObjectShape.of(object_points, table_height)
    out = np.zeros((len(grasp_points), len(OBJECT_CONTEXT_COLUMNS)), dtype=np.float32)
    if shape is None or len(grasp_points) == 0:
        return out
    offset = shape.centroid[:2] - grasp_points[:, :2]
    out[:, 0] = np.linalg.norm(offset, axis=1)
    out[:, 1] = np.einsum("ni,ni->n", offset, approaches[:, :2])
    out[:, 2] = grasp_points[:, 2] - shape.centroid[2]
    out[:, 3], out[:, 4], out[:, 5] = shape.length, shape.width, shape.height
    return out
