"""A suction grasp on the user's own depth image: `suctionbench plan` as a Python function.

    >>> from suctionbench.planning import plan_grasp, read_depth
    >>> result = plan_grasp(read_depth("scene.png"), "realsense-d435", policy="planarity-centroid", seed=0)
    >>> result.action.point, result.action.approach, result.action.pixel, result.action.q

Inputs
------
- Depth (`read_depth`): z-depth along the optical axis. ``.npy`` float arrays are metres; ``.npy``
  integer arrays and 16-bit PNGs are millimetres (the RealSense / Kinect / OpenNI convention); a
  float TIFF is metres. ``depth_scale`` (metres per stored unit) overrides the convention. NaN, inf
  and 0 mean "no return". A float image whose depths look like millimetres (median above 20) is
  refused with a hint rather than planned on at a 1000x wrong scale.
- Camera: a preset name (`suctionbench cameras`), an intrinsics TOML file, or `CameraIntrinsics`.
  An image at an exact scale of the camera's resolution (e.g. a D415 streamed at 640 x 360) is
  planned with the scaled intrinsics (`CameraIntrinsics.scaled`).
- Mask (optional): the object's pixels (``.npy`` of bools or numbers, or a PNG; non-zero = object).
- Camera pose (optional): the world-from-camera transform (4 x 4, OpenCV optical frame) in a world
  whose z axis is up and whose support surface is the plane z = `table_height` (``.npy``, a text
  file of 16 numbers, or JSON).

The support plane (no camera pose given)
----------------------------------------
The policies need the support's "up" direction (approach limits) and, without a mask, the object's
pixels. Without a camera pose the plane is fitted to the image: scikit-learn's `RANSACRegressor`
fits depth as a linear function of the camera-frame (x, y) of up to `PlanConfig.plane_samples`
valid pixels (drawn with the seed), inliers within `plane_threshold` of the plane; the largest
plane wins, which is the table or bin floor in a pick scene (an object that fills more of the view
than its support is not a pick scene). The plane defines a world frame (z along the plane normal,
towards the camera; origin below the camera) and so a camera pose. Object pixels are those more
than `table_clearance` above the plane, grouped into 8-connected regions; regions smaller than
`min_object_pixels` are noise, and the object is the largest remaining region that the image shows
whole (not cut by its border, as a bin wall or the robot is), else the largest (all regions with
``keep="all"``).

Output
------
`PlanResult`: the policy's `GraspAction` (point and approach in the camera frame, pixel, q), the
observation it planned from, the plane, and the time of each step. `draw_grasp` renders the depth
image with the object outlined and the grasp (the cup's footprint and its approach) as a PNG.
"""

from __future__ import annotations

import json
import math
import time
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.errors import InputError
from suctionbench.policies.base import MODEL_POLICIES, GraspAction, NoGraspError, Observation
from suctionbench.sensing.camera import CameraIntrinsics, resolve_camera

MILLIMETRE_HINT_DEPTH = 20.0
"""A float depth image whose median valid depth exceeds this many "metres" is taken to be in
millimetres and refused (no pick camera sees a table 20 m away)."""


# --------------------------------------------------------------------------------------------------
# Files
# --------------------------------------------------------------------------------------------------


def read_depth(path: str | Path, depth_scale: float | None = None) -> np.ndarray:
    """Depth image (H, W) float32 in metres, 0 = no return, from ``.npy``, a 16-bit PNG or a float
    TIFF (see the module docstring); `depth_scale` is metres per stored unit."""
    path = Path(path)
    if depth_scale is not None and not (math.isfinite(depth_scale) and depth_scale > 0):
        raise InputError(f"--depth-scale {depth_scale}: must be a positive number (metres per stored unit)")
    if not path.is_file():
        raise InputError(f"depth '{path}': file not found")
    suffix = path.suffix.lower()
    if suffix == ".npy":
        try:
            raw = np.load(path, allow_pickle=False)
        except (ValueError, OSError) as exc:
            raise InputError(f"depth '{path}': not a readable .npy array ({exc})") from None
        if raw.dtype.kind == "f":
            default = 1.0
        elif raw.dtype.kind in "ui":
            default = 0.001
        else:
            raise InputError(f"depth '{path}': dtype {raw.dtype} is not a depth image (float metres or integer mm)")
    elif suffix in (".png", ".tif", ".tiff"):
        from PIL import Image, UnidentifiedImageError

        try:
            with Image.open(path) as image:
                mode = image.mode
                raw = np.array(image)
        except (UnidentifiedImageError, OSError) as exc:
            raise InputError(f"depth '{path}': not a readable image ({exc})") from None
        if mode.startswith("I;16") or mode == "I":
            default = 0.001
        elif mode == "F":
            default = 1.0
        else:
            raise InputError(f"depth '{path}': a {mode} image holds no depth; expected a 16-bit PNG in "
                             "millimetres (or --depth-scale for other units) or a float TIFF in metres")
    else:
        raise InputError(f"depth '{path}': unknown format '{suffix}' (expected .npy, .png, .tif)")
    if raw.ndim == 3 and raw.shape[-1] == 1:
        raw = raw[..., 0]
    if raw.ndim != 2:
        raise InputError(f"depth '{path}': expected one channel (H, W), got shape {raw.shape}")
    depth = raw.astype(np.float64) * (default if depth_scale is None else depth_scale)
    depth[~np.isfinite(depth)] = 0.0
    if (depth < 0).any():
        raise InputError(f"depth '{path}': negative depths ({int((depth < 0).sum())} pixels)")
    valid = depth > 0
    if not valid.any():
        raise InputError(f"depth '{path}': no pixel has a depth")
    median = float(np.median(depth[valid]))
    if median > MILLIMETRE_HINT_DEPTH:
        raise InputError(f"depth '{path}': median depth {median:g} m looks like millimetres; "
                         "pass --depth-scale 0.001")
    return depth.astype(np.float32)


def read_mask(path: str | Path, shape: tuple[int, int]) -> np.ndarray:
    """Object pixels (H, W) bool from ``.npy`` or an image (non-zero = object)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"mask '{path}': file not found")
    try:
        if path.suffix.lower() == ".npy":
            mask = np.load(path, allow_pickle=False)
        else:
            from PIL import Image

            with Image.open(path) as image:
                mask = np.array(image.convert("L"))
    except Exception as exc:
        raise InputError(f"mask '{path}': cannot be read ({type(exc).__name__}: {exc})") from None
    if mask.shape != tuple(shape):
        raise InputError(f"mask '{path}': shape {mask.shape}, the depth image is {tuple(shape)}")
    if not mask.any():
        raise InputError(f"mask '{path}': no object pixel")
    return mask.astype(bool)


def read_camera_pose(path: str | Path) -> np.ndarray:
    """World-from-camera transform (4, 4) from ``.npy``, JSON (a 4 x 4 list, or {"camera_pose": ...})
    or a text file of 16 numbers (row-major)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"camera pose '{path}': file not found")
    try:
        if path.suffix.lower() == ".npy":
            pose = np.load(path, allow_pickle=False)
        elif path.suffix.lower() == ".json":
            data = json.loads(path.read_text())
            pose = data.get("camera_pose", data.get("pose")) if isinstance(data, dict) else data
        else:
            pose = np.loadtxt(path, delimiter=None if "," not in path.read_text() else ",")
        pose = np.asarray(pose, dtype=float).reshape(4, 4)
    except Exception as exc:
        raise InputError(f"camera pose '{path}': expected a 4x4 transform ({type(exc).__name__}: {exc})") from None
    if not np.isfinite(pose).all() or not np.allclose(pose[3], [0, 0, 0, 1]):
        raise InputError(f"camera pose '{path}': the last row must be 0 0 0 1 and every entry finite")
    rotation = pose[:3, :3]
    if not np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-4) or np.linalg.det(rotation) < 0:
        raise InputError(f"camera pose '{path}': the rotation part is not a proper rotation matrix")
    return pose


def camera_for_image(camera: str | Path | CameraIntrinsics, shape: tuple[int, int]) -> CameraIntrinsics:
    """The camera's intrinsics for an image of `shape` (H, W): as given, or scaled when the image is
    an exact scale of the camera's resolution; InputError otherwise."""
    intrinsics = camera if isinstance(camera, CameraIntrinsics) else resolve_camera(camera)
    height, width = shape
    if (height, width) == (intrinsics.height, intrinsics.width):
        return intrinsics
    factor = width / intrinsics.width
    if math.isclose(height / intrinsics.height, factor, rel_tol=1e-9):
        try:
            return intrinsics.scaled(factor)
        except InputError:
            pass
    raise InputError(f"depth image is {width} x {height}, camera '{intrinsics.name}' is {intrinsics.width} x "
                     f"{intrinsics.height}; give the camera's intrinsics at this resolution as a TOML file")


# --------------------------------------------------------------------------------------------------
# Support plane and object segmentation
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class PlanConfig:
    """How `plan_grasp` finds the support plane and the object."""

    plane_threshold: float = 0.005
    """RANSAC inlier distance (m) from the plane, along the optical axis: a few times a depth
    sensor's noise at 0.5-1 m (PrimeSense ~1.5 mm, D435 ~2-5 mm)."""

    plane_samples: int = 20_000
    """Valid pixels the plane is fitted to (drawn with the seed; all when there are fewer)."""

    plane_trials: int = 200
    """Most RANSAC hypotheses (sampling stops earlier once a plane with 99 % confidence is found)."""

    min_inlier_fraction: float = 0.2
    """The plane must hold at least this share of the sampled pixels, else no support was seen."""

    table_clearance: float = 0.005
    """Object pixels lie more than this (m) above the support plane (the policies' own 5 mm)."""

    min_object_pixels: int = 50
    """Connected regions above the plane smaller than this are noise, not objects."""

    keep: str = "largest"
    """'largest': the object is the largest region above the plane not cut by the image border
    (else the largest); 'all': every region."""

    def __post_init__(self) -> None:
        for key in ("plane_threshold", "table_clearance"):
            value = getattr(self, key)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise InputError(f"plan config: {key} = {value!r} must be a positive number of metres")
        for key in ("plane_samples", "plane_trials", "min_object_pixels"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise InputError(f"plan config: {key} = {value!r} must be a positive integer")
        if not 0.0 < self.min_inlier_fraction <= 1.0:
            raise InputError(f"plan config: min_inlier_fraction = {self.min_inlier_fraction!r} must be in (0, 1]")
        if self.keep not in ("largest", "all"):
            raise InputError(f"plan config: keep = {self.keep!r} must be 'largest' or 'all'")


@dataclass(frozen=True)
class SupportPlane:
    """A plane in the camera frame: points p with normal . p = offset; the normal faces the camera."""

    normal: np.ndarray
    """Unit normal (3,), camera frame, pointing from the plane towards the camera ("up")."""

    offset: float
    """normal . p of the plane's points (negative: the camera is on the normal's side)."""

    inlier_fraction: float
    """Share of the fitted pixels within the threshold of the plane."""

    rms: float
    """Root-mean-square distance (m) of the inliers from the plane."""

    def height(self, points: np.ndarray) -> np.ndarray:
        """Signed distance (m) above the plane of camera-frame points (..., 3)."""
        return np.asarray(points) @ self.normal - self.offset

    def camera_pose(self) -> np.ndarray:
        """World-from-camera transform (4, 4) of a world frame whose z axis is the plane normal and
        whose origin is the plane point below the camera, so that the plane is z = 0."""
        z = self.normal
        x = np.array([1.0, 0.0, 0.0]) - z[0] * z  # the camera's x axis, laid into the plane
        if np.linalg.norm(x) < 1e-6:
            x = np.array([0.0, 1.0, 0.0]) - z[1] * z
        x /= np.linalg.norm(x)
        y = np.cross(z, x)
        world_in_camera = np.column_stack([x, y, z])  # world axes expressed in the camera frame
        origin = self.offset * z  # the plane point nearest the camera centre
        pose = np.eye(4)
        pose[:3, :3] = world_in_camera.T
        pose[:3, 3] = -world_in_camera.T @ origin
        return pose

    def to_dict(self) -> dict[str, Any]:
        return {"normal": [round(float(v), 6) for v in self.normal], "offset": round(float(self.offset), 6),
                "inlier_fraction": round(self.inlier_fraction, 4), "rms": round(self.rms, 6)}


def fit_support_plane(points: np.ndarray, valid: np.ndarray, config: PlanConfig, seed: int) -> SupportPlane:
    """The dominant plane of an organised point cloud (H, W, 3) over `valid` pixels, by
    scikit-learn's RANSACRegressor on z = a x + b y + c (see the module docstring)."""
    from sklearn.linear_model import LinearRegression, RANSACRegressor

    rng = np.random.default_rng(seed)
    cloud = points[valid]
    if len(cloud) < 3:
        raise InputError("depth image: fewer than 3 valid pixels, no support plane can be fitted")
    if len(cloud) > config.plane_samples:
        cloud = cloud[np.sort(rng.choice(len(cloud), size=config.plane_samples, replace=False))]
    ransac = RANSACRegressor(
        LinearRegression(), min_samples=3, residual_threshold=config.plane_threshold,
        max_trials=config.plane_trials, stop_probability=0.99, random_state=int(rng.integers(2**31)),
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "max_trials reached" warnings: the fraction check below decides
        try:
            ransac.fit(cloud[:, :2], cloud[:, 2])
        except ValueError as exc:  # scikit-learn: no consensus set found
            raise InputError(f"depth image: no support plane found ({exc})") from None
    a, b = ransac.estimator_.coef_
    c = float(ransac.estimator_.intercept_)
    inliers = ransac.inlier_mask_
    fraction = float(inliers.mean())
    if fraction < config.min_inlier_fraction:
        raise InputError(f"depth image: the largest plane holds only {100 * fraction:.0f} % of the pixels "
                         f"(< {100 * config.min_inlier_fraction:.0f} %); no support surface in view? "
                         "Give --camera-pose or --mask")
    normal = np.array([a, b, -1.0]) / math.sqrt(a * a + b * b + 1.0)  # a x + b y - z + c = 0
    offset = -c / math.sqrt(a * a + b * b + 1.0)
    if offset > 0:  # make the normal face the camera (the origin): normal . 0 - offset > 0
        normal, offset = -normal, -offset
    distance = np.abs(cloud[inliers] @ normal - offset)
    return SupportPlane(normal, float(offset), fraction, float(np.sqrt(np.mean(distance**2))))


def segment_objects(points: np.ndarray, valid: np.ndarray, plane: SupportPlane, config: PlanConfig) -> np.ndarray:
    """Object pixels (H, W) bool: above the plane by more than the clearance, in 8-connected
    regions of at least `min_object_pixels`; with keep='largest' the largest region that does not
    touch the image border (what is cut by the border - a bin wall, the robot, the edge of the
    workspace - is not the object to pick) or, if every region does, the largest; all of them with
    keep='all'."""
    from scipy import ndimage

    above = valid & (plane.height(points) > config.table_clearance)
    labels, count = ndimage.label(above, structure=np.ones((3, 3), dtype=bool))
    if count == 0:
        return np.zeros_like(above)
    sizes = np.bincount(labels.ravel(), minlength=count + 1)
    sizes[0] = 0
    big = np.flatnonzero(sizes >= config.min_object_pixels)
    if len(big) == 0:
        return np.zeros_like(above)
    if config.keep == "all":
        return np.isin(labels, big)
    border = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    inside = np.setdiff1d(big, border)  # regions the image shows whole: in the workspace, not its edge
    pool = inside if len(inside) else big
    return labels == int(pool[np.argmax(sizes[pool])])


# --------------------------------------------------------------------------------------------------
# Planning
# --------------------------------------------------------------------------------------------------


@dataclass
class PlanResult:
    """A grasp planned on a depth image, with what it was planned from."""

    action: GraspAction
    """The grasp: point and approach in the camera frame, pixel (u, v), q, candidates."""

    observation: Observation
    """Depth, intrinsics, camera pose (given or from the plane) and the object mask used."""

    plane: SupportPlane | None
    """The fitted support plane; None when a camera pose was given."""

    policy: str
    """The policy's label (spec and options)."""

    timings: dict[str, float] = field(default_factory=dict)
    """Seconds per step: plane, segment, plan, total."""

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (what `suctionbench plan --json` prints)."""
        a = self.action
        return {
            "policy": self.policy, "camera": self.observation.intrinsics.name,
            "point": [round(float(v), 6) for v in a.point],
            "approach": [round(float(v), 6) for v in a.approach],
            "pixel": [round(float(v), 2) for v in a.pixel], "q": None if math.isnan(a.q) else round(float(a.q), 6),
            "depth": round(a.depth, 6),
            "point_world": [round(float(v), 6) for v in a.point_world],
            "approach_world": [round(float(v), 6) for v in a.approach_world],
            "camera_pose": "fitted" if self.plane is not None else "given",
            "plane": None if self.plane is None else self.plane.to_dict(),
            "object_pixels": int(self.observation.mask.sum()) if self.observation.mask is not None else None,
            "candidates": len(a.candidates.get("q", ())) or 1,
            "timings": {k: round(v, 4) for k, v in self.timings.items()},
        }


def plan_grasp(
    depth: np.ndarray,
    camera: str | Path | CameraIntrinsics,
    *,
    mask: np.ndarray | None = None,
    camera_pose: np.ndarray | None = None,
    policy: str = "gqcnn",
    policy_args: dict[str, Any] | None = None,
    model: str | Path | None = None,
    seed: int = 0,
    table_height: float = 0.0,
    config: PlanConfig | None = None,
) -> PlanResult:
    """Plan one suction grasp on a depth image (H, W) in metres (see the module docstring).

    `policy` is any `--policy` spec (built-in, plug-in, PATH.py:FACTORY) with `policy_args`;
    `model` is the GQ-CNN model directory for policy 'gqcnn' (default: the shipped one). Every
    random draw (plane sampling, the policy) comes from `seed`. Bad input, an image without a
    support plane or an object, and an object with no graspable surface raise InputError.
    """
    from suctionbench.policies.plugins import builtin_name, load_policy, policy_label

    config = config or PlanConfig()
    start = time.perf_counter()
    depth = np.asarray(depth, dtype=np.float32)
    if depth.ndim != 2:
        raise InputError(f"depth image: expected (H, W), got shape {depth.shape}")
    depth = np.where(np.isfinite(depth), depth, 0.0).astype(np.float32)
    intrinsics = camera_for_image(camera, depth.shape)
    options = dict(policy_args or {})
    if model is not None and builtin_name(policy) in MODEL_POLICIES:
        options.setdefault("model", str(model))
    planner = load_policy(policy, options)
    timings: dict[str, float] = {}
    plane = given_pose = None
    valid = depth > 0
    points = intrinsics.deproject(depth)
    if camera_pose is None:
        t = time.perf_counter()
        support = valid if mask is None else valid & ~np.asarray(mask, dtype=bool)
        plane = fit_support_plane(points, support, config, seed)
        camera_pose = plane.camera_pose()
        timings["plane"] = time.perf_counter() - t
    else:
        # The policies take the table at z = 0 of the pose's world (their samplers' table_height,
        # and the object context's heights above it): move that world down by the table height.
        given_pose = np.asarray(camera_pose, dtype=float)
        camera_pose = given_pose.copy()
        camera_pose[2, 3] -= table_height
    t = time.perf_counter()
    if mask is None:
        if plane is None:  # a given pose: the table is the plane z = 0 of its (shifted) world
            up = camera_pose[2, :3]  # world z in the camera frame
            plane_of_pose = SupportPlane(up.copy(), float(-camera_pose[2, 3]), 1.0, 0.0)
            mask = segment_objects(points, valid, plane_of_pose, config)
        else:
            mask = segment_objects(points, valid, plane, config)
        if not mask.any():
            raise InputError(f"depth image: nothing stands more than {1000 * config.table_clearance:g} mm above "
                             f"the support plane in a region of at least {config.min_object_pixels} pixels")
    timings["segment"] = time.perf_counter() - t
    observation = Observation(depth=depth, intrinsics=intrinsics, camera_pose=camera_pose, mask=mask)
    t = time.perf_counter()
    try:
        action = planner.plan(observation, np.random.default_rng(seed))
    except NoGraspError as exc:
        raise InputError(f"depth image: no grasp ({exc})") from None
    timings["plan"] = time.perf_counter() - t
    if given_pose is not None:  # report in the given pose's world
        action.camera_pose = given_pose
        observation = replace(observation, camera_pose=given_pose)
    timings["total"] = time.perf_counter() - start
    return PlanResult(action=action, observation=observation, plane=plane,
                      policy=policy_label(policy, policy_args), timings=timings)


# --------------------------------------------------------------------------------------------------
# Drawing
# --------------------------------------------------------------------------------------------------


def draw_grasp(result: PlanResult, path: str | Path, *, cup_radius: float | None = None) -> None:
    """Write a PNG of the depth image (near = bright), the object's outline (blue), the candidates
    (grey dots), and the grasp: the cup's footprint circle and the approach drawn from where the
    cup comes in (green when q >= 0.5, else orange), with its q."""
    from PIL import Image, ImageDraw
    from scipy import ndimage

    from suctionbench.config import CUP_DEFAULT
    from suctionbench.io import atomic_path

    cup_radius = CUP_DEFAULT.radius if cup_radius is None else cup_radius
    obs, action = result.observation, result.action
    depth = obs.depth
    valid = depth > 0
    lo, hi = (np.percentile(depth[valid], [1, 99]) if valid.any() else (0.0, 1.0))
    grey = np.where(valid, 235 - 190 * np.clip((depth - lo) / max(hi - lo, 1e-6), 0, 1), 0).astype(np.uint8)
    rgb = np.repeat(grey[..., None], 3, axis=2)
    if obs.mask is not None:
        edge = obs.mask & ~ndimage.binary_erosion(obs.mask)
        rgb[edge] = (40, 110, 255)
    image = Image.fromarray(rgb)
    draw = ImageDraw.Draw(image)
    for u, v in np.asarray(action.candidates.get("pixels", np.zeros((0, 2)))):
        draw.point((float(u), float(v)), fill=(150, 150, 150))
    intr = obs.intrinsics
    u, v = (float(x) for x in action.pixel)
    radius = max(cup_radius * intr.fx / max(action.depth, 1e-6), 2.0)
    colour = (40, 200, 60) if not math.isnan(action.q) and action.q >= 0.5 else (255, 150, 30)
    draw.ellipse((u - radius, v - radius, u + radius, v + radius), outline=colour, width=2)
    tail = intr.project(action.point - 0.05 * action.approach)  # 5 cm back along the approach
    if np.isfinite(tail).all():
        draw.line((float(tail[0]), float(tail[1]), u, v), fill=colour, width=2)
    draw.ellipse((u - 2, v - 2, u + 2, v + 2), fill=colour)
    q = "nan" if math.isnan(action.q) else f"{action.q:.2f}"
    draw.text((6, 6), f"{result.policy}  q = {q}  ({u:.0f}, {v:.0f})  depth {action.depth:.3f} m", fill=colour)
    with atomic_path(path) as tmp:
        image.save(tmp, format="PNG")


def plan_files(
    depth: str | Path,
    camera: str | Path,
    *,
    mask: str | Path | None = None,
    camera_pose: str | Path | None = None,
    policy: str = "gqcnn",
    policy_args: dict[str, Any] | None = None,
    model: str | Path | None = None,
    seed: int = 0,
    depth_scale: float | None = None,
    table_height: float = 0.0,
    out: str | Path | None = None,
) -> dict[str, Any]:
    """`suctionbench plan`: read the files, plan (`plan_grasp`), draw the grasp to `out` if given,
    and return the JSON-ready result (`PlanResult.to_dict` plus the input and output paths)."""
    from suctionbench.validate import output_file, require_disk

    if out is not None:  # before any work: a drawing that cannot be written costs no planning
        output_file(out, "--out")
    image = read_depth(depth, depth_scale)
    if out is not None:
        require_disk(out, 3 * image.size + 2**12, f"--out drawing of {image.shape[1]} x {image.shape[0]} px")
    result = plan_grasp(
        image, camera, mask=None if mask is None else read_mask(mask, image.shape),
        camera_pose=None if camera_pose is None else read_camera_pose(camera_pose), policy=policy,
        policy_args=policy_args, model=model, seed=seed, table_height=table_height,
    )
    if out is not None:
        draw_grasp(result, out)
    return {"depth_file": str(depth), **result.to_dict(), "seed": seed, "out": None if out is None else str(out)}
