"""GQ-CNN suction inputs: grasp projection, visibility, depth thumbnails and the pose vector.

A suction grasp (target point p, approach v pointing from the gripper into the object) seen by a
depth camera becomes GQ-CNN's input (Dex-Net 3.0; gqcnn's GQCNN-3.0 config): a 32 x 32 depth
thumbnail, cut 96 x 96 around the grasp pixel, rotated so that the approach axis's image runs
along the middle column, and scaled by 1/3, plus a pose vector [gripper depth, approach angle].

Conventions
-----------
- Pixels (u, v) = (column, row) with integer values at pixel centres, as in
  `suctionbench.sensing.camera` (OpenCV optical frame: x right, y down, z forward).
- The approach's image angle theta is atan2(dv, du) of the approach axis's image direction, in
  radians: 0 points right (+u), pi/2 points down the image (+v), i.e. positive angles turn
  clockwise on screen.
- Thumbnail geometry: the grasp pixel maps to the thumbnail's exact centre ((n - 1) / 2,
  (n - 1) / 2) = (15.5, 15.5), the point shared by the four central pixels, so that the 180 deg
  rotation and the flips of training-time symmetrisation keep the grasp at the centre. The
  approach's image direction points DOWN the middle column (towards increasing row index); the
  thumbnail's +column direction is that direction turned 90 deg anticlockwise on screen (a proper
  rotation, never a mirror image). Thumbnail pixel (row, col) samples image point
  p_pix + s ((col - c) e + (row - c) d) with d = (cos theta, sin theta), e = (sin theta,
  -cos theta), c = (n - 1) / 2 and s = crop / n = 3 image pixels per thumbnail pixel: the centre
  of its 3 x 3 block of the 96 x 96 crop. An approach already pointing down the image
  (theta = pi/2) gives an unrotated crop.
- Pose vector: [depth of p along the optical axis (m), angle between the approach and the
  downward table normal, arccos(-v . n) in [0, pi] (0 = straight down)]. With the thumbnail
  convention above this angle is never signed in a dataset; training augmentation that turns a
  thumbnail upside down (180 deg rotation or up-down flip) should negate it per sample.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np
from scipy import ndimage

from suctionbench.errors import InputError
from suctionbench.sensing.camera import CameraIntrinsics


@dataclass(frozen=True)
class ThumbnailConfig:
    """Geometry of a grasp thumbnail (defaults: gqcnn's Dex-Net 3.0 suction input)."""

    crop_size: int = 96
    """Side (image pixels) of the square crop around the grasp pixel. gqcnn: 96."""

    out_size: int = 32
    """Side (pixels) of the thumbnail the crop is scaled to. gqcnn: 32, a scale of 1/3."""

    sampling: str = "point"
    """What a thumbnail pixel holds (`SAMPLINGS`): "point", the depth at the centre of its block of
    crop pixels (gqcnn: the other 8 of a 3 x 3 block are not read), or "mean", the block's mean depth
    (`sampled_image`), which averages independent per-pixel sensor noise down by the block's side
    (1.3 mm -> 0.43 mm for 3 x 3 at 0.6 m), below the cup's ~0.3 mm seal gap scale."""

    def __post_init__(self) -> None:
        for key in ("crop_size", "out_size"):
            value = getattr(self, key)
            if not (isinstance(value, int) and not isinstance(value, bool) and value > 0):
                raise InputError(f"thumbnail config: {key} = {value!r} must be a positive integer")
        if self.sampling not in SAMPLINGS:
            raise InputError(f"thumbnail config: sampling = {self.sampling!r} must be one of {', '.join(SAMPLINGS)}")
        step = self.crop_size / self.out_size
        if self.sampling == "mean" and (self.crop_size % self.out_size or int(step) % 2 == 0):
            # an even block's mean centres half a pixel off the sample point, and the grasp off the
            # thumbnail's centre, which the training flips and rotations assume
            raise InputError(f"thumbnail config: sampling 'mean' needs an odd whole number of image pixels a "
                             f"thumbnail pixel (crop {self.crop_size} / {self.out_size} = {step:g}; "
                             "e.g. crop 96 or 32)")

    @classmethod
    def from_dict(cls, data: Any, source: str) -> ThumbnailConfig:
        """The config a dataset or model card records (`dataclasses.asdict` form); InputError naming
        `source` if it is not one."""
        names = {f.name for f in fields(cls)}
        if not isinstance(data, dict) or not set(data) <= names:
            raise InputError(f"{source}: thumbnail {data!r} is not a thumbnail config "
                             f"(fields: {', '.join(sorted(names))})")
        try:
            return cls(**data)
        except InputError as exc:
            raise InputError(f"{source}: {exc}") from None

    @classmethod
    def recorded(cls, data: Any, source: str) -> ThumbnailConfig:
        """The config a card records (`from_dict`), or gqcnn's where it records none (cards from
        before the choice existed)."""
        return THUMBNAIL_GQCNN if data is None else cls.from_dict(data, source)

    @property
    def block(self) -> int:
        """Side (image pixels) of the block a thumbnail pixel stands for (3 for gqcnn, 9 for context)."""
        return max(1, int(round(self.crop_size / self.out_size)))

    @property
    def scale(self) -> float:
        """Thumbnail pixels per image pixel (1/3 for gqcnn)."""
        return self.out_size / self.crop_size

    @property
    def centre(self) -> float:
        """Row and column of the thumbnail's centre, where the grasp point lands ((n - 1) / 2)."""
        return (self.out_size - 1) / 2.0

    @property
    def crop_radius(self) -> float:
        """Half-diagonal of the crop (image pixels): the rotated crop stays inside a circle of this
        radius about the grasp pixel, whatever the approach angle."""
        return self.crop_size / 2.0 * math.sqrt(2.0)


def describe_thumbnail(config: ThumbnailConfig) -> str:
    """A thumbnail config in words, for messages: e.g. "96 px crops at 32 x 32, point samples"."""
    return f"{config.crop_size} px crops at {config.out_size} x {config.out_size}, {config.sampling} samples"


SAMPLINGS = ("point", "mean")
"""What `ThumbnailConfig.sampling` accepts."""

THUMBNAIL_GQCNN = ThumbnailConfig()
"""gqcnn's suction thumbnail: 96 x 96 crop scaled to 32 x 32, point samples."""

THUMBNAIL_CONTEXT = ThumbnailConfig(crop_size=288, out_size=32, sampling="mean")
"""The context view around a grasp: 3x the grasp thumbnail's field of view (288 x 288 pixels, ~33 cm
at 0.6 m with the PrimeSense's 525 px focal length) at the same 32 x 32 and rotation, so that the
object's extent and the grasp's place on it, which set the gravity torque the label depends on,
are in view. Each pixel is its 9 x 9 block's mean (point samples 9 pixels apart would alias sensor
noise and thin edges)."""


def _rows3(name: str, value) -> np.ndarray:
    array = np.asarray(value, dtype=float)
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3), got {array.shape}")
    return array


def project_grasps(
    points_cam: np.ndarray, approaches_cam: np.ndarray, intrinsics: CameraIntrinsics
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Image data of grasps given in the camera frame (OpenCV optical frame).

    Returns pixels (N, 2) = (u, v) float from `intrinsics.project`, depths (N,) = z in metres, and
    image angles (N,) in radians of the approach axis: the direction in which the image of
    p + s v moves as s grows from 0, i.e. the limit of projecting p and p + s v and taking the
    angle of the difference, computed exactly from the derivative of the projection,
    d(u, v)/ds = (fx (v_x z - x v_z), fy (v_y z - y v_z)) / z^2 (a 3D line projects to a 2D line,
    so this is also the direction towards the image of any later point on the approach ray).
    An approach along the viewing ray has no image direction and gets angle 0; points with
    z <= 0 get NaN pixels (and should be dropped by `visible_mask`).
    """
    p = _rows3("points_cam", points_cam)
    a = _rows3("approaches_cam", approaches_cam)
    if len(p) != len(a):
        raise ValueError(f"points_cam and approaches_cam differ in length ({len(p)} vs {len(a)})")
    pixels = intrinsics.project(p)
    x, y, z = p.T
    du = intrinsics.fx * (a[:, 0] * z - x * a[:, 2])
    dv = intrinsics.fy * (a[:, 1] * z - y * a[:, 2])
    angles = np.arctan2(dv, du)  # z^2 > 0 does not change the direction
    return pixels, z.copy(), angles


def visible_mask(
    pixels: np.ndarray,
    depths: np.ndarray,
    depth_image: np.ndarray,
    tol: float = 0.003,
    *,
    config: ThumbnailConfig = THUMBNAIL_GQCNN,
    margin: float | None = None,
) -> np.ndarray:
    """Which grasps (N,) bool can be turned into a thumbnail from this depth image.

    A grasp passes if (1) its pixel lies at least `margin` pixels inside the image, by default
    `config.crop_radius` (67.9 px for a 96 crop), so that the rotated crop lies wholly inside the
    image for any approach angle and visibility does not depend on the approach; and (2) the depth
    image at the rounded pixel equals the grasp depth within `tol` metres, i.e. the target point
    is the visible surface at its pixel: a nearer surface (occlusion) or no return (0) fails. The
    default 3 mm covers the depth change across half a pixel on surfaces tilted up to ~70 deg at
    0.6 m with fx = 525 px, plus rendering round-off. Non-finite pixels or depths fail.
    """
    pixels = np.asarray(pixels, dtype=float)
    depths = np.asarray(depths, dtype=float)
    depth_image = np.asarray(depth_image)
    if pixels.ndim != 2 or pixels.shape[1] != 2 or depths.shape != (len(pixels),):
        raise ValueError(f"pixels must be (N, 2) and depths (N,), got {pixels.shape} and {depths.shape}")
    if depth_image.ndim != 2:
        raise ValueError(f"depth image must have shape (H, W), got {depth_image.shape}")
    height, width = depth_image.shape
    margin = config.crop_radius if margin is None else float(margin)
    u, v = pixels[:, 0], pixels[:, 1]
    finite = np.isfinite(u) & np.isfinite(v) & np.isfinite(depths)
    # Margin measured from the image edges at (-0.5, size - 0.5), clamped to keep the rounded index valid.
    inside = (
        finite
        & (u >= margin - 0.5) & (u <= width - 0.5 - margin)
        & (v >= margin - 0.5) & (v <= height - 0.5 - margin)
    )
    cols = np.clip(np.rint(np.where(inside, u, 0.0)), 0, width - 1).astype(np.intp)
    rows = np.clip(np.rint(np.where(inside, v, 0.0)), 0, height - 1).astype(np.intp)
    seen = depth_image[rows, cols].astype(float)
    return inside & (seen > 0) & (np.abs(seen - depths) <= tol)


def thumbnail_axes(angles: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """Image directions (..., 2) = (du, dv) of a thumbnail's +row axis, d = (cos, sin) (the
    approach's image direction), and its +column axis, e = (sin, -cos), for image angles `angles`
    (module doc, "Thumbnail geometry")."""
    cos, sin = np.cos(angles), np.sin(angles)
    return np.stack([cos, sin], axis=-1), np.stack([sin, -cos], axis=-1)


def _sample_coordinates(pixels: np.ndarray, angles: np.ndarray, config: ThumbnailConfig) -> np.ndarray:
    """Image coordinates (2, N, n, n) = (row, column) sampled by each thumbnail pixel (see the
    module docstring for the geometry)."""
    n, step = config.out_size, config.crop_size / config.out_size
    offsets = (np.arange(n) - config.centre) * step  # image pixels from the grasp, per thumbnail index
    d, e = (axis[:, None, None, :] for axis in thumbnail_axes(angles))  # (N, 1, 1, 2) = (du, dv)
    down = offsets[None, :, None]  # along d, by thumbnail row
    right = offsets[None, None, :]  # along e, by thumbnail column
    u = pixels[:, 0, None, None] + right * e[..., 0] + down * d[..., 0]
    v = pixels[:, 1, None, None] + right * e[..., 1] + down * d[..., 1]
    return np.stack([v, u])


def _window(image: np.ndarray, rows: tuple[float, float], cols: tuple[float, float]):
    """The part of `image` that bilinear samples at rows in [rows[0], rows[1]] and columns in
    [cols[0], cols[1]] read, as a float64 tensor (1, 1, h, w), with its top-left pixel (top, left)
    and the grid units per pixel (column, row) that `grid_sample` reads it in. Every point's 2 x 2
    neighbours lie in it, and where a point lies past the image, so does the window's edge (the same
    clamping), so sampling the window is sampling the image."""
    import torch

    (top, bottom), (left, right) = (np.clip([math.floor(lo), math.floor(hi) + 1], 0, n - 1)
                                    for (lo, hi), n in ((rows, image.shape[0]), (cols, image.shape[1])))
    window = np.asarray(image[top:bottom + 1, left:right + 1], dtype=np.float64)
    height, width = window.shape
    scale = np.array([2.0 / max(width - 1, 1), 2.0 / max(height - 1, 1)])  # grid_sample's [-1, 1] per pixel
    return torch.from_numpy(window)[None, None], top, left, scale


def _grid_sample(source, grid) -> np.ndarray:
    """Bilinear samples of `source` (B, 1, h, w) at `grid` (B, H, W, 2) = (x, y) in [-1, 1], edge
    pixels repeated outside (map_coordinates' order 1, mode "nearest"): (B, H, W) float32."""
    import torch.nn.functional as F

    sampled = F.grid_sample(source, grid, mode="bilinear", padding_mode="border", align_corners=True)
    return sampled[:, 0].numpy().astype(np.float32)


def bilinear_sample(image: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Bilinear samples (rows.shape) float32 of `image` (H, W) at image coordinates (rows, cols),
    edge pixels repeated outside: the values of ``scipy.ndimage.map_coordinates(image, [rows, cols],
    order=1, mode="nearest")``, computed in float64 by torch's `grid_sample` over the window the
    points read (`_window`), which runs on the process's torch threads and is about 2x faster than
    scipy's spline machinery at thumbnail work (5.1 against 9.5 ms for 200 thumbnails, 2 threads).
    Coordinates must be finite."""
    import torch

    rows, cols = np.asarray(rows, dtype=float), np.asarray(cols, dtype=float)
    if rows.size == 0:
        return np.zeros(rows.shape, dtype=np.float32)
    source, top, left, scale = _window(np.asarray(image), (rows.min(), rows.max()), (cols.min(), cols.max()))
    grid = np.empty((*rows.shape, 2))
    grid[..., 0] = (cols - left) * scale[0] - 1.0  # grid_sample's x: the column
    grid[..., 1] = (rows - top) * scale[1] - 1.0
    return _grid_sample(source, torch.from_numpy(grid.reshape(1, 1, -1, 2))).reshape(rows.shape)


def affine_sample(image: np.ndarray, origin: np.ndarray, down: np.ndarray, right: np.ndarray,
                  shape: tuple[int, int]) -> np.ndarray:
    """Bilinear samples (B, rows, cols) float32 of `image` (H, W) on B affine lattices: sample
    (a, b) of lattice k at image (u, v) = origin[k] + a down[k] + b right[k] ((B, 2) each), edge
    pixels repeated outside (`bilinear_sample`'s values). torch builds the points (`affine_grid`)
    and samples them in float64, from the window of the image the lattices cover: 2.4x faster than
    building the points in numpy for `bilinear_sample` (1.9 against 4.7 ms for 16 lattices of
    90 x 88)."""
    import torch
    import torch.nn.functional as F

    origin, down, right = (np.asarray(x, dtype=float).reshape(-1, 2) for x in (origin, down, right))
    rows, cols = shape
    count = len(origin)
    corners = (origin[:, None] + np.array([0, rows - 1, 0, rows - 1])[None, :, None] * down[:, None]
               + np.array([0, 0, cols - 1, cols - 1])[None, :, None] * right[:, None])  # (B, 4, 2) = (u, v)
    source, top, left, scale = _window(np.asarray(image), (corners[..., 1].min(), corners[..., 1].max()),
                                       (corners[..., 0].min(), corners[..., 0].max()))
    # affine_grid maps output index (a, b) to (x, y) = (-1 + 2 b / (cols - 1), -1 + 2 a / (rows - 1))
    # and applies theta to [x, y, 1]; grid_sample reads window column (x' + 1) / scale.
    half_rows, half_cols = (rows - 1) / 2, (cols - 1) / 2
    theta = np.empty((count, 2, 3))
    theta[:, :, 0] = scale * right * half_cols
    theta[:, :, 1] = scale * down * half_rows
    theta[:, :, 2] = scale * (origin - [left, top] + down * half_rows + right * half_cols) - 1.0
    grid = F.affine_grid(torch.from_numpy(theta), [count, 1, rows, cols], align_corners=True)
    return _grid_sample(source.expand(count, 1, *source.shape[2:]), grid)


_CHUNK = 4096
"""Grasps per vectorised block in `extract_thumbnails`: bounds the coordinate arrays (2 x 4096 x
32 x 32 doubles = 67 MB) for any number of grasps."""


def extract_thumbnails(
    depth_image: np.ndarray, pixels: np.ndarray, angles: np.ndarray, config: ThumbnailConfig = THUMBNAIL_GQCNN
) -> np.ndarray:
    """Depth thumbnails (N, n, n) float32 in metres, one rotated, scaled crop per grasp.

    One affine warp per grasp (rotation by the approach's image angle, scale 1/3, translation to
    the sub-pixel grasp pixel), all grasps sampled in one `bilinear_sample` call per block of
    grasps (bilinear interpolation, as map_coordinates' order=1) and edge replication outside the image
    (mode='nearest'; `visible_mask`'s default margin keeps crops inside). Each thumbnail pixel is
    a point sample at the centre of its 3 x 3 block of crop pixels, not a block average.
    Bilinear sampling blends a no-return pixel (0) with its valid neighbours, as gqcnn's resize
    did; rendered table scenes have no such holes near grasps. Grasps with non-finite pixels or
    angles give all-zero thumbnails.
    """
    depth_image = np.asarray(depth_image, dtype=np.float32)
    pixels = np.asarray(pixels, dtype=float)
    angles = np.asarray(angles, dtype=float)
    if depth_image.ndim != 2:
        raise ValueError(f"depth image must have shape (H, W), got {depth_image.shape}")
    if pixels.ndim != 2 or pixels.shape[1] != 2 or angles.shape != (len(pixels),):
        raise ValueError(f"pixels must be (N, 2) and angles (N,), got {pixels.shape} and {angles.shape}")
    n = config.out_size
    good = np.isfinite(pixels).all(axis=1) & np.isfinite(angles)
    safe_pixels = np.where(good[:, None], pixels, 0.0)
    safe_angles = np.where(good, angles, 0.0)
    out = np.empty((len(pixels), n, n), dtype=np.float32)
    for start in range(0, len(pixels), _CHUNK):  # blocks of grasps, not one grasp at a time
        block = slice(start, start + _CHUNK)
        coords = _sample_coordinates(safe_pixels[block], safe_angles[block], config)
        out[block] = bilinear_sample(depth_image, coords[0], coords[1])
    out[~good] = 0.0
    return out


def sample_thumbnails(
    depth_image: np.ndarray, pixels: np.ndarray, angles: np.ndarray, config: ThumbnailConfig = THUMBNAIL_GQCNN
) -> np.ndarray:
    """Thumbnails (N, n, n) float32 in metres as `config` samples them: `extract_thumbnails` on
    `sampled_image` (the image itself for point samples, its block means for "mean")."""
    return extract_thumbnails(sampled_image(depth_image, config), pixels, angles, config)


def extract_context_thumbnails(
    depth_image: np.ndarray, pixels: np.ndarray, angles: np.ndarray, config: ThumbnailConfig = THUMBNAIL_CONTEXT
) -> np.ndarray:
    """Context thumbnails (N, n, n) float32 in metres: block means at `config`'s geometry, whatever
    its `sampling` (`sample_thumbnails`)."""
    return sample_thumbnails(depth_image, pixels, angles, replace(config, sampling="mean"))


def sampled_image(depth_image: np.ndarray, config: ThumbnailConfig) -> np.ndarray:
    """The image (H, W) float32 that `extract_thumbnails` samples for `config`: the depth image for
    point samples; for "mean", the depth image box-filtered over a thumbnail pixel's block (crop / n
    image pixels square), so that a sample at a block's centre is the block's mean. Computed once
    per image, it serves any number of grasps and calls."""
    image = np.asarray(depth_image, dtype=np.float32)
    if config.sampling == "point" or config.block == 1:
        return image
    return ndimage.uniform_filter(image, size=config.block, mode="nearest")


def extract_thumbnails_reference(
    depth_image: np.ndarray, pixels: np.ndarray, angles: np.ndarray, config: ThumbnailConfig = THUMBNAIL_GQCNN
) -> np.ndarray:
    """Slow, obviously-correct reference for `extract_thumbnails`: one grasp at a time, written as
    the explicit affine map thumbnail (row, col) -> image (row, col) and applied with
    `scipy.ndimage.affine_transform` (same interpolation). For tests and timing only."""
    depth_image = np.asarray(depth_image, dtype=np.float32)
    n, c, step = config.out_size, config.centre, config.crop_size / config.out_size
    out = np.zeros((len(pixels), n, n), dtype=np.float32)
    for i, ((u, v), theta) in enumerate(zip(np.asarray(pixels, float), np.asarray(angles, float), strict=True)):
        if not (np.isfinite([u, v, theta]).all()):
            continue
        d, e = (axis[::-1] for axis in thumbnail_axes(theta))  # thumbnail +row, +col, as image (row, col)
        matrix = step * np.column_stack([d, e])  # image (row, col) per thumbnail (row, col)
        offset = np.array([v, u]) - matrix @ np.array([c, c])
        out[i] = ndimage.affine_transform(depth_image, matrix, offset, output_shape=(n, n), order=1, mode="nearest")
    return out


def pose_vector(depths: np.ndarray, approaches_world: np.ndarray, table_normal=(0.0, 0.0, 1.0)) -> np.ndarray:
    """GQ-CNN's pose input (N, 2) float32: [gripper depth (m), approach angle (rad)].

    The angle is arccos(-v . n) between the approach v (from the gripper into the object,
    normalised here) and the downward table normal -n: 0 for a grasp straight down, pi/2 for a
    horizontal approach. It does not depend on the camera, unlike the image, so the network
    learns gravity-relative approach quality.
    """
    depths = np.asarray(depths, dtype=float)
    v = _rows3("approaches_world", approaches_world)
    if depths.shape != (len(v),):
        raise ValueError(f"depths must have shape ({len(v)},), got {depths.shape}")
    normal = np.asarray(table_normal, dtype=float).reshape(3)
    normal = normal / np.linalg.norm(normal)
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    angle = np.arccos(np.clip(-(v @ normal), -1.0, 1.0))
    return np.stack([depths, angle], axis=1).astype(np.float32)


_GREEN = np.array([30, 190, 60], dtype=np.uint8)
_RED = np.array([220, 40, 40], dtype=np.uint8)


def to_uint8_grid(
    thumbnails: np.ndarray, labels: np.ndarray, *, columns: int = 4, scale: int = 4, border: int = 3
) -> np.ndarray:
    """A picture (H, W, 3) uint8 of thumbnails in a grid (16 make 4 x 4), each with a green
    (label true) or red (false) frame, for `suctionbench.sensing.image.save_png`.

    Each thumbnail is shaded on its own depth range like `save_png` (near bright, far dark, no
    return black) and enlarged `scale` times by pixel replication, so the pixels the network sees
    stay visible.
    """
    if min(columns, scale) < 1 or border < 0:
        raise ValueError(f"columns = {columns} and scale = {scale} must be >= 1, border = {border} >= 0")
    thumbs = np.asarray(thumbnails, dtype=float)
    labels = np.asarray(labels).astype(bool).reshape(-1)
    if thumbs.ndim != 3 or len(labels) != len(thumbs) or len(thumbs) == 0:
        raise ValueError(f"need thumbnails (N, h, w) and labels (N,), N > 0; got {thumbs.shape} and {labels.shape}")
    count, h, w = thumbs.shape
    valid = thumbs > 0
    lo = np.where(valid, thumbs, np.inf).min(axis=(1, 2), keepdims=True)
    hi = np.where(valid, thumbs, -np.inf).max(axis=(1, 2), keepdims=True)
    lo, hi = np.where(np.isfinite(lo), lo, 0.0), np.where(np.isfinite(hi), hi, 1.0)
    grey = np.where(valid, 255.0 - 200.0 * (thumbs - lo) / np.maximum(hi - lo, 1e-9), 0.0).astype(np.uint8)
    grey = grey.repeat(scale, axis=1).repeat(scale, axis=2)
    tile_h, tile_w, gap = h * scale + 2 * border, w * scale + 2 * border, border
    tiles = np.empty((count, tile_h, tile_w, 3), dtype=np.uint8)
    tiles[:] = np.where(labels[:, None, None, None], _GREEN, _RED)
    tiles[:, border:border + h * scale, border:border + w * scale, :] = grey[..., None]
    rows = math.ceil(count / columns)
    cols = min(columns, count)
    grid = np.full((rows * (tile_h + gap) + gap, cols * (tile_w + gap) + gap, 3), 40, dtype=np.uint8)
    for k in range(count):  # one tile copy each, a handful per picture
        r, c = divmod(k, columns)
        y, x = gap + r * (tile_h + gap), gap + c * (tile_w + gap)
        grid[y:y + tile_h, x:x + tile_w] = tiles[k]
    return grid
