"""What every image-based grasp policy shares: the observation it plans from, the grasp it returns,
the `Policy` protocol and registry, and the point-cloud geometry read from the depth image.

Frames
------
Everything a policy computes lives in the camera's OpenCV optical frame (x right, y down, z along
the optical axis; see `suctionbench.sensing.camera`): grasp points are deprojected depth pixels
and approach axes are unit vectors in that frame. `GraspAction.point_world` and `approach_world`
map them to the world with the observation's camera pose. A suction grasp is a target point p and
an approach v pointing from the gripper into the object (DESIGN.md).

Geometry read from the image (`SceneCloud`)
-------------------------------------------
- Object pixels: the observation's mask where one is given (and the depth is valid). Otherwise the
  paper's "3D bounds on the workspace": a pixel is an object pixel when its deprojected point lies
  more than `SamplerConfig.table_clearance` (5 mm) above the table plane z = `table_height` of the
  world frame, found with the camera pose. The table is the world plane z = 0 in every scene of
  the benchmark, so no plane is fitted to the image: a fit is what a real system without a
  calibrated camera pose would need, and it would only add a failure mode here.
- Surface normals: the depth image is smoothed by a Gaussian as a normalised convolution
  (no-return pixels, depth 0, neither contribute nor are filled), the smoothed image is
  deprojected, and the normal at a pixel is the cross product of the 3D tangents along the image
  columns and rows (central differences, as gqcnn's `normal_cloud_im`), oriented towards the
  camera. Pixels whose 4-neighbourhood has a no-return pixel have no normal. The Gaussian's width
  is gqcnn's 1 px (`depth_sigma`), or `normal_sigma` on the surface where that is set (e.g. half
  the cup's lip radius, 3.75 mm: the normal the lip seals along, averaged over the footprint it
  covers, in pixels at the object's median depth). On a flat face at 0.6 m the PrimeSense's
  1.3 mm per-pixel noise leaves 1 px normals 12 deg off in the median, 3.75 mm normals 1.4 deg.
- Planarity (`disc_errors`) reads the smoothed points too, so that per-pixel sensor noise does not
  make every face look rough.
- Grasp at a pixel: the point is the *raw* depth pixel deprojected (the measured surface, so that
  the grasp lies on what the sensor saw; smoothing would pull pixels at a silhouette towards the
  table behind it), and the approach is minus the smoothed normal.
- Valid grasp pixels (the seed sampler of gqcnn's Dex-Net 3.0 suction policy, shared by every policy so that all of
  them choose from the same candidate distribution): object pixels with a normal whose approach
  is within `max_optical_axis_angle` (60 deg; gqcnn: 30) of the optical axis and within `max_approach_angle`
  (80 deg) of straight down (the table's downward normal). If no object pixel passes, both angle
  limits are dropped (the object is still graspable somewhere, e.g. a thin rod seen edge-on) and
  `SceneCloud.relaxed` says so; an observation without any object pixel raises `NoGraspError`.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np
from scipy import ndimage

from suctionbench.config import CUP_DEFAULT
from suctionbench.errors import InputError
from suctionbench.sensing.camera import CameraIntrinsics

# --------------------------------------------------------------------------------------------------
# Observation and action
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Observation:
    """One depth image of the scene and what a policy may know about it."""

    depth: np.ndarray
    """Depth image (H, W) float32: z-depth in metres along the optical axis, 0 = no return."""

    intrinsics: CameraIntrinsics
    """The camera that took the image (its width and height must match the image)."""

    camera_pose: np.ndarray
    """World-from-camera transform (4, 4) in the OpenCV optical frame; gives the table normal in
    the camera frame and segments the object from the table when there is no mask."""

    mask: np.ndarray | None = None
    """Object pixels (H, W) bool, e.g. from a segmentation; None: segment by height above the table."""

    state: dict[str, Any] | None = None
    """Known state for oracle policies (e.g. the object's mesh and pose); image policies ignore it."""

    def __post_init__(self) -> None:
        depth = np.asarray(self.depth, dtype=np.float32)
        expected = (self.intrinsics.height, self.intrinsics.width)
        if depth.shape != expected:
            raise InputError(
                f"observation: depth image has shape {depth.shape}, camera '{self.intrinsics.name}' gives {expected}"
            )
        if not np.isfinite(depth).all() or (depth < 0).any():
            raise InputError("observation: depth image must be finite and non-negative (0 = no return)")
        pose = np.asarray(self.camera_pose, dtype=float)
        if pose.shape != (4, 4) or not np.isfinite(pose).all():
            raise InputError(f"observation: camera_pose must be a finite 4x4 transform, got shape {pose.shape}")
        rotation = pose[:3, :3]
        if not np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-6) or np.linalg.det(rotation) < 0:
            raise InputError("observation: camera_pose rotation is not a proper rotation matrix")
        object.__setattr__(self, "depth", depth)
        object.__setattr__(self, "camera_pose", pose)
        if self.mask is not None:
            mask = np.asarray(self.mask)
            if mask.shape != expected:
                raise InputError(f"observation: mask has shape {mask.shape}, the depth image {expected}")
            object.__setattr__(self, "mask", mask.astype(bool))


@dataclass
class GraspAction:
    """A planned suction grasp, in the camera frame of the observation it was planned from."""

    point: np.ndarray
    """Target point p (3,) in the camera frame (metres): the deprojected depth pixel."""

    approach: np.ndarray
    """Unit approach axis v (3,) in the camera frame, from the gripper into the surface."""

    pixel: np.ndarray
    """Image position (2,) = (u, v) = (column, row) of the grasp pixel."""

    q: float
    """Policy quality in [0, 1] (higher is better; a predicted success probability for GQ-CNN
    policies, a monotone map of the heuristic's metric otherwise); NaN for the random policy."""

    camera_pose: np.ndarray
    """World-from-camera pose (4, 4) of the observation, for the world-frame helpers."""

    policy: str = ""
    """Registry name of the policy that planned the grasp."""

    candidates: dict[str, np.ndarray] = field(default_factory=dict)
    """Every candidate the policy scored, for logging: `pixels` (N, 2) (u, v), `points` (N, 3) and
    `approaches` (N, 3) in the camera frame, `q` (N,), plus policy-specific arrays (documented by
    each policy)."""

    info: dict[str, Any] = field(default_factory=dict)
    """Diagnostics: `plan_time` (s), `relaxed` (angle limits dropped), policy-specific entries."""

    @property
    def depth(self) -> float:
        """Gripper depth: z of the target point along the optical axis (metres)."""
        return float(self.point[2])

    @property
    def point_world(self) -> np.ndarray:
        """Target point (3,) in the world frame."""
        return self.camera_pose[:3, :3] @ self.point + self.camera_pose[:3, 3]

    @property
    def approach_world(self) -> np.ndarray:
        """Unit approach axis (3,) in the world frame."""
        return self.camera_pose[:3, :3] @ self.approach


class NoGraspError(RuntimeError):
    """The observation holds no object pixel with a usable surface, so no grasp can be planned."""


@runtime_checkable
class Policy(Protocol):
    """A grasp policy: plans one suction grasp from a depth observation.

    `plan` draws every random number from `rng`, so the same observation and generator state give
    the same grasp, bit for bit.
    """

    name: str

    def plan(self, observation: Observation, rng: np.random.Generator) -> GraspAction: ...


# --------------------------------------------------------------------------------------------------
# Registry (lazy "module:attribute" entry points, as in Gymnasium)
# --------------------------------------------------------------------------------------------------

POLICIES: dict[str, str] = {
    "random": "suctionbench.policies.heuristics:RandomPolicy",
    "centroid": "suctionbench.policies.heuristics:CentroidPolicy",
    "planarity": "suctionbench.policies.heuristics:PlanarityPolicy",
    "planarity-centroid": "suctionbench.policies.heuristics:PlanarityCentroidPolicy",
    "gqcnn": "suctionbench.policies.gqcnn:make_gqcnn_policy",
    "gqcnn-adv": "suctionbench.policies.gqcnn:make_gqcnn_adv_policy",
    "fc-gqcnn": "suctionbench.policies.fc_gqcnn:make_fc_gqcnn_policy",
    "fc-gqcnn-adv": "suctionbench.policies.fc_gqcnn:make_fc_gqcnn_adv_policy",
}
"""Registered image policies: name -> "module:attribute" of a factory taking keyword arguments.
Modules are imported on first use (the GQ-CNN policy's model loading pulls in torch)."""

KNOWN_STATE_POLICIES = ("analytic", "analytic-image", "analytic-image-uniform", "random-surface")
"""Policies that see the true object state, planned in the simulation rather than built from this
registry: rank surface grasps by a 3D metric (the known-state upper bound), rank the grasps the
depth image offers the image policies by it (that bound over what the camera sees:
`policies.analytic`), do so believing the object of uniform density (the true shape, pose and mass,
the centre of mass at the shape's: what no depth image shows taken away), or draw one surface grasp
uniformly."""

RANKING_POLICIES = ("analytic", "analytic-image", "analytic-image-uniform")
"""The known-state policies that rank by a 3D metric (`--metric`; their runs are named by it)."""

IMAGE_KNOWN_STATE_POLICIES = ("analytic-image", "analytic-image-uniform")
"""The known-state policies that draw their grasps from the depth image: they take a camera frame,
and the one object whose state they know must be the one in view (no bins)."""

UNIFORM_DENSITY_POLICIES = ("analytic-image-uniform",)
"""The known-state policies that rank believing the object of uniform density: the centre of mass
at the shape's (`policies.analytic.uniform_density_com`), not the true one."""

MODEL_POLICIES = ("gqcnn", "fc-gqcnn")
"""Built-in policies that read a GQ-CNN model (the `model` option, `--model` on the command line)."""

ADV_VARIANTS: dict[str, str] = {"gqcnn-adv": "gqcnn", "fc-gqcnn-adv": "fc-gqcnn"}
"""Built-in policies that are another built-in's search with the shipped GQ-CNN (ADV) model instead of
the default: name -> that policy. Only the weights differ, so they share its planning time."""

ALIASES: dict[str, str] = {"gqcnn-cem": "gqcnn"}
"""Other accepted names (DESIGN.md calls the GQ-CNN policy gqcnn-cem)."""


def register_policy(name: str, entry_point: str | Callable[..., Policy]) -> None:
    """Add a policy factory under `name` (a callable or a lazy "module:attribute" string)."""
    POLICIES[name] = entry_point  # type: ignore[assignment]


def policy_factory(name: str) -> Callable[..., Policy]:
    """The factory a policy spec names: a registered name (or alias), an installed plug-in, or a
    user's PATH.py:FACTORY / package.module:FACTORY (`suctionbench.policies.plugins`); InputError
    when there is none."""
    from suctionbench.policies.plugins import resolve_factory

    return resolve_factory(name)


TABLE_OPTIONS = ("sampler",)
"""Nested configs a policy option may set as a table (`configured`). Not the thumbnails: a trained
model reads its grasps the way its dataset was cut, whatever the policy's config says."""


def configured(config: Any, overrides: dict[str, Any]) -> Any:
    """`config` (a policy's config dataclass) with `overrides` (its keyword options, e.g. from
    ``--policy-arg``) replaced. An option in `TABLE_OPTIONS` given as a table replaces that nested
    config's own fields: ``--policy-arg 'sampler={max_optical_axis_angle=1.0472}'`` widens the seed
    cone and keeps the sampler's other defaults. Unknown names raise TypeError, as
    `dataclasses.replace` does (`load_policy` reports it as bad options)."""
    changes = dict(overrides)
    for key, value in overrides.items():
        if not isinstance(value, dict):
            continue
        current = getattr(config, key, None)
        if key not in TABLE_OPTIONS or not dataclasses.is_dataclass(current):
            raise TypeError(f"{key}: takes no table (tables: {', '.join(TABLE_OPTIONS)})")
        try:
            changes[key] = dataclasses.replace(current, **value)
        except TypeError as exc:
            raise TypeError(f"{key}: {exc}") from None
    return dataclasses.replace(config, **changes)


def make_policy(name: str, **kwargs: Any) -> Policy:
    """Build the policy a spec names, e.g. make_policy("centroid", num_candidates=500),
    make_policy("gqcnn", model="path/to/model") or make_policy("my_policy.py:make_policy", k=1).
    Unknown names and options raise InputError (`suctionbench.policies.plugins.load_policy`)."""
    from suctionbench.policies.plugins import load_policy

    return load_policy(name, kwargs)


# --------------------------------------------------------------------------------------------------
# Candidate sampler configuration and the image's point cloud
# --------------------------------------------------------------------------------------------------


FOOTPRINT_NORMAL_SIGMA = CUP_DEFAULT.radius / 2.0
"""`SamplerConfig.normal_sigma` that averages the normal over the default cup's footprint (m)."""


@dataclass(frozen=True)
class SamplerConfig:
    """Which pixels a policy may grasp, and how normals are read (gqcnn's Dex-Net 3.0 seed sampler)."""

    max_optical_axis_angle: float = math.radians(60.0)
    """Largest angle (rad) between the approach and the optical axis: 60 deg. Grazing surfaces have
    unreliable depth; by the structured-light noise model of Nguyen et al. (2012), sigma_z(z, t) =
    1.2 mm + 1.9 mm (z - 0.4)^2 + 0.1 mm / sqrt(z) t^2 / (pi/2 - t)^2, a surface at t = 60 deg from
    the ray reads with 0.5 mm more noise than face-on at 0.6 m (1.3 mm), at 70 deg with 1.6 mm more.
    gqcnn's `max_suction_dir_optical_axis_angle` is 30 deg, which leaves a lying triangular prism's
    60 deg faces (and so the whole prism) out of every image policy's reach; the GQ-CNN's training
    grasps approach up to 80 deg from vertical (`max_approach_angle`)."""

    max_approach_angle: float = math.radians(80.0)
    """Largest angle (rad) between the approach and straight down (the table's downward normal);
    gqcnn's Dex-Net 3.0 policy: 80 deg. The arm never approaches from below."""

    depth_sigma: float = 1.0
    """Standard deviation (pixels) of the Gaussian that smooths the depth image for the point cloud
    that planarity reads (`disc_errors`), and for the normals when `normal_sigma` is 0; gqcnn: 1 px.
    0 disables smoothing."""

    normal_sigma: float = 0.0
    """Standard deviation (m, on the surface) of the Gaussian that smooths the depth image before
    normals are estimated, turned into pixels at the object's median depth; 0 (default) reads the
    normals from the `depth_sigma` image, as gqcnn does. A compliant lip seals along the mean plane
    of the footprint it covers, not along the surface's normal at one pixel: a Gaussian of half the
    lip radius (FOOTPRINT_NORMAL_SIGMA) puts 86 % of its weight (1 - e^-2) inside the lip's disc.
    At 0.6 m with the PrimeSense (f = 525 px) 3.75 mm is 3.3 px, which cuts the per-pixel noise in
    a normal about 10 times against gqcnn's 1 px (the noise of a Gaussian-derivative estimate falls
    as 1/sigma^2)."""

    table_clearance: float = 0.005
    """Object segmentation without a mask: pixels whose point lies more than this (m) above the
    table plane are object pixels."""

    table_height: float = 0.0
    """Height (m) of the table plane in the world frame (z = 0 in suctionbench scenes)."""

    def __post_init__(self) -> None:
        for key, high in (("max_optical_axis_angle", math.pi / 2), ("max_approach_angle", math.pi)):
            value = getattr(self, key)
            if not (isinstance(value, int | float) and 0.0 < value <= high):
                raise InputError(f"sampler config: {key} = {value!r} must be an angle in (0, {high:.4f}] rad")
        if not (isinstance(self.depth_sigma, int | float) and 0.0 <= self.depth_sigma <= 10.0):
            raise InputError(f"sampler config: depth_sigma = {self.depth_sigma!r} must be in [0, 10] pixels")
        if not (isinstance(self.normal_sigma, int | float) and 0.0 <= self.normal_sigma <= 0.05):
            raise InputError(f"sampler config: normal_sigma = {self.normal_sigma!r} must be in [0, 0.05] m")
        if not (isinstance(self.table_clearance, int | float) and self.table_clearance >= 0.0):
            raise InputError(f"sampler config: table_clearance = {self.table_clearance!r} must be >= 0 m")
        if not (isinstance(self.table_height, int | float) and math.isfinite(self.table_height)):
            raise InputError(f"sampler config: table_height = {self.table_height!r} must be finite")


def smooth_depth(depth: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian-smoothed depth (H, W) float64 that ignores no-return pixels (normalised convolution):
    valid pixels average only valid neighbours, no-return pixels stay 0."""
    depth = np.asarray(depth, dtype=float)
    valid = depth > 0
    if sigma <= 0:
        return depth.copy()
    weight = ndimage.gaussian_filter(valid.astype(float), sigma, mode="nearest")
    total = ndimage.gaussian_filter(np.where(valid, depth, 0.0), sigma, mode="nearest")
    return np.where(valid, total / np.maximum(weight, 1e-12), 0.0)


def surface_normals(points: np.ndarray, valid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals (H, W, 3) of an organised point cloud (H, W, 3), oriented towards the camera at
    the origin, and which pixels have one (H, W) bool.

    The normal is t_u x t_v with t_u, t_v the central-difference tangents along image columns and
    rows; it needs valid depth at the pixel and its 4 neighbours (one-sided at the image border).
    """
    # Per coordinate image (planar, contiguous), the same arithmetic as np.gradient, np.cross and
    # np.linalg.norm on the interleaved (H, W, 3) cloud (the same values), ~2x faster.
    planes = [np.ascontiguousarray(points[..., k]) for k in range(3)]
    ux, uy, uz = (np.gradient(p, axis=1) for p in planes)  # t_u
    vx, vy, vz = (np.gradient(p, axis=0) for p in planes)  # t_v
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx  # t_u x t_v
    norm = np.sqrt(nx * nx + ny * ny + nz * nz)
    ok = valid & (norm > 0)
    padded = np.pad(valid, 1, mode="edge")
    ok &= padded[:-2, 1:-1] & padded[2:, 1:-1] & padded[1:-1, :-2] & padded[1:-1, 2:]
    safe = np.where(ok, norm, 1.0)
    sign = np.where(nx * planes[0] + ny * planes[1] + nz * planes[2] > 0, -1.0, 1.0)  # face the camera: n . (0 - p) > 0
    return np.stack([np.where(ok, n / safe * sign, 0.0) for n in (nx, ny, nz)], axis=-1), ok  # unit; 0 without one


@dataclass
class SceneCloud:
    """Geometry of one observation that policies read (see the module docstring).

    Everything that needs a normal lies in `box`, the object's bounding box plus the smoothing
    margin, so the cloud is computed there (`box_*`); the whole-image arrays (`points`,
    `smooth_points`, `approaches`) are built on first use, which the image policies never need
    (they read `grasps_at` and `object_points`): 3 x 7 MB less to write per plan at 640 x 480."""

    depth: np.ndarray
    """Raw depth image (H, W) float64, metres."""

    box: tuple[slice, slice]
    """(rows, columns) of the object's bounding box plus the smoothing margin, inside the image."""

    box_points: np.ndarray
    """Raw depth image deprojected in `box` (h, w, 3), camera frame; the origin where depth is 0."""

    box_smooth_points: np.ndarray
    """Smoothed depth image deprojected in `box` (h, w, 3)."""

    box_approaches: np.ndarray
    """Minus the smoothed-image normals in `box` (h, w, 3), unit (smoothed by `normal_sigma`); zero
    where there is no normal."""

    object_mask: np.ndarray
    """Object pixels (H, W) bool with valid depth."""

    valid: np.ndarray
    """Pixels (H, W) bool a policy may grasp (object pixels passing the sampler's angle limits)."""

    table_normal: np.ndarray
    """World +z (up) in the camera frame (3,)."""

    intrinsics: CameraIntrinsics
    """The observation's camera."""

    relaxed: bool
    """True when no object pixel passed the angle limits and `valid` is every object pixel with a normal."""

    @functools.cached_property
    def points(self) -> np.ndarray:
        """Raw depth image deprojected (H, W, 3), camera frame; the origin where depth is 0."""
        return self.intrinsics.deproject(self.depth)

    @functools.cached_property
    def smooth_points(self) -> np.ndarray:
        """`box_smooth_points` in the box, the raw points elsewhere (table only, far from any
        object pixel), (H, W, 3)."""
        points = self.points.copy()
        points[self.box] = self.box_smooth_points
        return points

    @functools.cached_property
    def approaches(self) -> np.ndarray:
        """`box_approaches` in the box, zero elsewhere (no normal away from the object), (H, W, 3)."""
        approaches = np.zeros((*self.depth.shape, 3))
        approaches[self.box] = self.box_approaches
        return approaches

    @property
    def object_points(self) -> np.ndarray:
        """Points (M, 3) of the object pixels, camera frame, in row-major order."""
        return self.box_points[self.object_mask[self.box]]

    @property
    def valid_pixels(self) -> np.ndarray:
        """(row, col) indices (K, 2) of the valid pixels, in row-major order (all in `box`)."""
        return np.argwhere(self.valid[self.box]) + [self.box[0].start, self.box[1].start]

    def grasps_at(self, rows: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Pixels (N, 2) = (u, v) float, points (N, 3) and approaches (N, 3) of grasps at pixels."""
        rows, cols = np.asarray(rows, dtype=np.intp), np.asarray(cols, dtype=np.intp)
        pixels = np.column_stack([cols, rows]).astype(float)
        r, c = rows - self.box[0].start, cols - self.box[1].start
        height, width = self.box_points.shape[:2]
        if ((r < 0) | (r >= height) | (c < 0) | (c >= width)).any():  # not a grasp pixel: the whole image
            return pixels, self.points[rows, cols], self.approaches[rows, cols]
        return pixels, self.box_points[r, c], self.box_approaches[r, c]

    def sample(self, count: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """(rows, cols) of up to `count` distinct valid pixels drawn uniformly (all of them, in
        random order, if there are fewer)."""
        pixels = self.valid_pixels
        pick = rng.choice(len(pixels), size=min(int(count), len(pixels)), replace=False)
        return pixels[pick, 0], pixels[pick, 1]


def segment_object(observation: Observation, config: SamplerConfig) -> np.ndarray:
    """Object pixels (H, W) bool: the observation's mask, or points above the table plane (world frame)."""
    has_depth = observation.depth > 0
    if observation.mask is not None:
        return observation.mask & has_depth
    pose = observation.camera_pose
    points = observation.intrinsics.deproject(observation.depth)
    height = points @ pose[2, :3] + pose[2, 3]  # world z of every pixel's point
    return has_depth & (height > config.table_height + config.table_clearance)


def normal_sigma_pixels(config: SamplerConfig, intrinsics: CameraIntrinsics, object_depths: np.ndarray) -> float:
    """The normals' smoothing in pixels: `normal_sigma` (m) at the object's median depth, or
    `depth_sigma` when `normal_sigma` is 0."""
    if config.normal_sigma <= 0.0:
        return float(config.depth_sigma)
    focal = 0.5 * (intrinsics.fx + intrinsics.fy)
    return float(config.normal_sigma * focal / np.median(object_depths))


def scene_cloud(observation: Observation, config: SamplerConfig) -> SceneCloud:
    """Read the point cloud, normals, object pixels and valid grasp pixels of an observation."""
    intrinsics = observation.intrinsics
    depth = observation.depth.astype(float)
    has_depth = depth > 0
    object_mask = segment_object(observation, config)
    if not object_mask.any():
        raise NoGraspError("no object pixel in the observation (empty mask or nothing above the table)")
    normal_sigma = normal_sigma_pixels(config, intrinsics, depth[object_mask])
    # Normals only around the object: a margin of the smoothing radius (4 sigma, scipy's truncation)
    # plus the gradient's neighbour leaves every object pixel's normal as on the whole image.
    margin = math.ceil(4.0 * max(config.depth_sigma, normal_sigma)) + 2
    rows, cols = np.nonzero(object_mask.any(axis=1))[0], np.nonzero(object_mask.any(axis=0))[0]
    r0, c0 = max(rows[0] - margin, 0), max(cols[0] - margin, 0)
    r1, c1 = min(rows[-1] + margin, depth.shape[0] - 1), min(cols[-1] + margin, depth.shape[1] - 1)
    box = (slice(r0, r1 + 1), slice(c0, c1 + 1))
    smooth_points = intrinsics.deproject(smooth_depth(depth[box], config.depth_sigma), corner=(r0, c0))
    normal_points = (smooth_points if normal_sigma == config.depth_sigma
                     else intrinsics.deproject(smooth_depth(depth[box], normal_sigma), corner=(r0, c0)))
    normals, has_normal = surface_normals(normal_points, has_depth[box])
    table_normal = observation.camera_pose[:3, :3].T @ np.array([0.0, 0.0, 1.0])
    candidates = object_mask[box] & has_normal
    if not candidates.any():
        raise NoGraspError("no object pixel has a surface normal (object too small or no depth around it)")
    approaches = -normals
    along_axis = approaches[..., 2] >= math.cos(config.max_optical_axis_angle)
    downward = -(approaches @ table_normal) >= math.cos(config.max_approach_angle)
    passing = candidates & along_axis & downward
    relaxed = not passing.any()
    valid = np.zeros_like(has_depth)
    valid[box] = candidates if relaxed else passing
    return SceneCloud(
        depth=depth, box=box, box_points=intrinsics.deproject(depth[box], corner=(r0, c0)),
        box_smooth_points=smooth_points, box_approaches=approaches, object_mask=object_mask, valid=valid,
        table_normal=table_normal, intrinsics=intrinsics, relaxed=relaxed,
    )


def disc_errors(
    cloud: SceneCloud, rows: np.ndarray, cols: np.ndarray, approaches: np.ndarray, radius: float, *, chunk: int = 64
) -> tuple[np.ndarray, np.ndarray]:
    """Planarity of the cup's footprint at grasps on pixels (rows, cols): the sum of squared
    distances (N,) (m^2) from the approach plane (through the grasp pixel's point, normal to
    `approaches`) of the image points that lie within the cup disc, i.e. whose distance from the
    approach axis is at most `radius`, and how many points (N,) that is.

    Points come from the smoothed image (`SceneCloud.smooth_points`), the cloud the normals are
    read from: per-pixel sensor noise (about 1.2 mm for the simulated PrimeSense) would otherwise
    make every real face look rough, the smoothing cuts it about 3.5 times, and a face that is
    flat stays flat.

    Points are gathered from a square window of image pixels around each grasp pixel, wide enough
    for the disc at the grasp's depth (radius x f / z plus 50 %); every valid depth pixel counts,
    object or table, since anything in the footprint breaks the seal. Vectorised over a window per
    grasp, in blocks of `chunk` grasps.
    """
    rows, cols = np.asarray(rows, dtype=np.intp), np.asarray(cols, dtype=np.intp)
    approaches = np.asarray(approaches, dtype=float)
    height, width = cloud.depth.shape
    sse, count = np.zeros(len(rows)), np.zeros(len(rows), dtype=np.intp)
    if len(rows) == 0:
        return sse, count
    focal = max(cloud.intrinsics.fx, cloud.intrinsics.fy)
    z_near = max(float(cloud.depth[rows, cols].min()), 0.5 * cloud.intrinsics.min_depth)
    half = int(math.ceil(1.5 * radius * focal / z_near)) + 1
    offsets = np.arange(-half, half + 1)
    has_depth = cloud.depth > 0
    for start in range(0, len(rows), chunk):
        block = slice(start, start + chunk)
        r = rows[block, None, None] + offsets[None, :, None]
        c = cols[block, None, None] + offsets[None, None, :]
        inside = (r >= 0) & (r < height) & (c >= 0) & (c < width)
        r, c = np.clip(r, 0, height - 1), np.clip(c, 0, width - 1)
        centre = cloud.smooth_points[rows[block], cols[block]]
        d = cloud.smooth_points[r, c] - centre[:, None, None, :]
        axial = np.einsum("nijk,nk->nij", d, approaches[block])
        radial2 = np.einsum("nijk,nijk->nij", d, d) - axial**2
        in_disc = inside & has_depth[r, c] & (radial2 <= radius**2)
        sse[block] = np.where(in_disc, axial**2, 0.0).sum(axis=(1, 2))
        count[block] = in_disc.sum(axis=(1, 2))
    return sse, count
