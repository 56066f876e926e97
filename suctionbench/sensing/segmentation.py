"""Object regions of a cluttered depth image, from depth alone: what a bin-picking policy that
plans per object needs (each heuristic and the GQ-CNN's object context read one object).

Method (the classic range-image segmentation by depth and normal discontinuities):
1. Workspace pixels: those whose point (the camera pose known) lies inside a box in the world,
   the bin's inner volume above its floor (Dex-Net's "3D bounds on the workspace").
2. Boundaries: a pixel is a boundary when the depth jumps to one of its 4-neighbours by more than
   `jump` (an occluding edge between stacked objects) or the surface normals `crease_span` pixels
   either side of it (along a row or a column) differ by more than `crease` and the surface there
   bends into a valley (`convex`: concave; two objects touching side by side). A convex crease, where
   the surface bends away from the camera, is an object's own edge (a box's top meeting its side)
   and does not cut: objects are convex where they are seen, the valleys lie between them (the
   local-convexity reading of Stein et al., CVPR 2014). Normals are read from the workspace pixels
   alone (the floor would blur every edge), and a pixel without one (at the workspace's rim) is a
   boundary too.
3. Regions: the connected components (scipy.ndimage.label, 4-connectivity) of workspace pixels
   that are not boundaries, largest first; components smaller than `min_pixels` are dropped
   (specks, the walls' inner faces seen edge-on).

Why convex creases join: the policies read a region as one object (its centroid, its extent, the
GQ-CNN's object context). Cutting at every crease split 132 of the 176 regions of the first views of
ten typical bins into less than 60 % of their object (a mug's side apart from its top), so each
policy planned on a part whose centroid and size were not the object's. Two touching objects whose
tops meet flush at the same height and angle, or lean together into a ridge, merge into one region:
the oracle (instance masks from the renderer, `--masks oracle`) is there to measure what that costs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from suctionbench.sensing.camera import CameraIntrinsics


@dataclass(frozen=True)
class SegmentationConfig:
    """Thresholds of the depth segmentation (metres, radians, pixels)."""

    floor_clearance: float = 0.005
    """Pixels less than this above the bin floor are floor (the single-object policies' 5 mm)."""

    wall_margin: float = 0.005
    """Points within this of the bin's inner walls are wall (depth noise smears the wall's inner face)."""

    jump: float = 0.008
    """Depth step (m) between neighbours that separates two surfaces: above the simulated sensor's
    noise (about 1.2 mm at 0.6 m) and its smoothing, below any object's thickness in the sets."""

    crease: float = math.radians(45.0)
    """Angle between neighbouring normals that separates two surfaces."""

    normal_sigma: float = 1.5
    """Gaussian smoothing (pixels) of the depth before normals are compared (noise would otherwise
    make every pixel a crease)."""

    crease_span: int = 3
    """Normals are compared `crease_span` pixels either side of a pixel: twice the smoothing's sigma,
    so a sharp edge, which the smoothing spreads over a few pixels, still shows its full angle."""

    min_pixels: int = 60
    """Smallest region kept: about 1.7 x 1.7 cm at 0.65 m with a PrimeSense, the cup's footprint."""

    cut_convex_creases: bool = False
    """Whether a convex crease (an object's own edge, where its top meets a side) also separates
    regions. False: only concave ones do (the valley where two objects meet), so an object seen on
    two faces is one region (module docstring, step 2). True: the segmentation of the bin
    benchmark before 2026-11-28, which left 132 of the 176 regions of ten typical bins holding
    under 60 % of their object (eval/bin/segmentation.py)."""


def convex(n1: np.ndarray, n2: np.ndarray, p1: np.ndarray, p2: np.ndarray) -> np.ndarray:
    """Whether the surface between points p1 and p2 (..., 3) with normals n1, n2 facing the
    camera bends away from it, like a box's edge, rather than into a valley: (n1 - n2) . (p1 - p2)
    > 0, the local convexity criterion of Stein et al., "Object partitioning using local convexity",
    CVPR 2014. (A box's top, n1 = z, at p1 = (0, 0, 1) and its side, n2 = x, at p2 = (1, 0, 0.5):
    (-1, 0, 1) . (-1, 0, 0.5) = 1.5 > 0; two faces meeting in a V, n = (+-1, 0, 1) / sqrt 2 at
    p = (-+1, 0, 1): (sqrt 2, 0, 0) . (-2, 0, 0) < 0.)"""
    return np.einsum("...k,...k->...", n1 - n2, p1 - p2) > 0.0


def workspace_mask(depth: np.ndarray, intrinsics: CameraIntrinsics, camera_pose: np.ndarray,
                   lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Pixels (H, W) bool with depth whose world point lies inside the box [lower, upper] (3,)."""
    points = intrinsics.deproject(np.asarray(depth, dtype=float))
    world = points @ camera_pose[:3, :3].T + camera_pose[:3, 3]
    inside = np.all((world >= lower) & (world <= upper), axis=-1)
    return inside & (depth > 0)


def segment_regions(depth: np.ndarray, intrinsics: CameraIntrinsics, workspace: np.ndarray,
                    config: SegmentationConfig | None = None) -> list[np.ndarray]:
    """Object regions (each (H, W) bool) of the workspace pixels, largest first (see the module
    docstring)."""
    from suctionbench.policies.base import smooth_depth, surface_normals

    config = config or SegmentationConfig()
    depth = np.asarray(depth, dtype=float)
    valid = depth > 0
    boundary = np.zeros_like(valid)
    for axis in (0, 1):
        step = np.abs(np.diff(depth, axis=axis)) > config.jump
        lo = [slice(None)] * 2
        hi = [slice(None)] * 2
        lo[axis], hi[axis] = slice(None, -1), slice(1, None)
        boundary[tuple(lo)] |= step
        boundary[tuple(hi)] |= step
    inside = workspace & valid  # normals from the workspace alone: the floor would blur the objects' edges
    smooth = smooth_depth(np.where(inside, depth, 0.0), config.normal_sigma)
    points = intrinsics.deproject(smooth)
    normals, has_normal = surface_normals(points, inside)
    boundary |= inside & ~has_normal  # the rim of each region, where a neighbour is outside it
    cos_crease = math.cos(config.crease)
    k = config.crease_span
    for axis in (0, 1):  # normals k pixels either side of each pixel: the smoothing spreads a crease
        before = [slice(None)] * 2
        after = [slice(None)] * 2
        centre = [slice(None)] * 2
        before[axis], after[axis], centre[axis] = slice(None, -2 * k), slice(2 * k, None), slice(k, -k)
        b, a = tuple(before), tuple(after)
        crease = has_normal[b] & has_normal[a] & (np.einsum("...k,...k->...", normals[b], normals[a]) < cos_crease)
        if not config.cut_convex_creases:  # of the creases (a few % of the pixels), the concave ones
            at = np.nonzero(crease)
            crease[at] = ~convex(normals[b][at], normals[a][at], points[b][at], points[a][at])
        boundary[tuple(centre)] |= crease
    labels, count = ndimage.label(inside & ~boundary)
    if count == 0:
        return []
    sizes = np.bincount(labels.ravel(), minlength=count + 1)[1:]
    order = np.argsort(-sizes, kind="stable")
    return [labels == (i + 1) for i in order if sizes[i] >= config.min_pixels]
