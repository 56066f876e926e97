"""Pinhole depth cameras: intrinsics and named presets, and MuJoCo glue that places a camera with
exact intrinsics in an MjSpec and renders metric depth (where the camera stands: `sensing.camera_pose`).

Frames and pixels
-----------------
Everything here uses the OpenCV optical frame for cameras: x right, y down, z forward along the
optical axis. A camera pose is a 4x4 world-from-camera transform in that frame, so a point p_cam
in the camera frame is ``pose[:3, :3] @ p_cam + pose[:3, 3]`` in the world. Pixel coordinates
(u, v) are (column, row) with integer values at pixel *centres* (OpenCV), so the pixel that holds
the continuous point (u, v) is ``depth[round(v), round(u)]``, and the image spans
[-0.5, width - 0.5] x [-0.5, height - 0.5].

MuJoCo cameras look along their -z axis with y up. The two frames differ by a rotation of pi about
the x axis, `MUJOCO_FROM_OPENCV` (its own inverse); `add_camera` and `camera_pose_from_data`
convert so that callers only ever see OpenCV poses.

Depth is z-depth (distance along the optical axis, not along the ray), in metres, float32, with 0
meaning "no return" (nothing hit), the convention of Dex-Net / GQ-CNN depth images.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from suctionbench.errors import InputError

if TYPE_CHECKING:
    import mujoco


# --------------------------------------------------------------------------------------------------
# Intrinsics
# --------------------------------------------------------------------------------------------------


IMAGE_PIXELS = (32, 4096)
"""Valid image width and height (px): at least one 32 px grasp thumbnail, at most an offscreen buffer."""

FOV_DEG = (1.0, 170.0)
"""Valid field of view (deg) of a pinhole depth camera, from its focal length and image size."""

MAX_DEPTH_M = 10.0
"""Largest working range (m) the scene renders (MuJoCo's far clip plane is ~10.6 m)."""


@dataclass(frozen=True)
class CameraIntrinsics:
    """A distortion-free pinhole depth camera (rendered images have no lens distortion, so none is
    modelled) plus the depth range over which the real sensor returns valid measurements."""

    name: str
    """Preset or user-given name, recorded in datasets and model cards so that a model can be
    matched to the camera it was trained for."""

    width: int
    """Image width in pixels (number of columns)."""

    height: int
    """Image height in pixels (number of rows)."""

    fx: float
    """Focal length along x (columns) in pixels."""

    fy: float
    """Focal length along y (rows) in pixels."""

    cx: float
    """Principal point column in pixels, pixel-centre convention (the exact centre of a 640-wide
    image is 319.5)."""

    cy: float
    """Principal point row in pixels, pixel-centre convention."""

    min_depth: float
    """Near end of the sensor's working range in metres: closer surfaces give no valid return on
    the real device. Used to fit the camera-pose distribution to the sensor, and by noise models."""

    max_depth: float
    """Far end of the sensor's working range in metres."""

    def __post_init__(self) -> None:
        label = f"camera intrinsics '{self.name}'"
        if not isinstance(self.name, str) or not self.name:
            raise InputError(f"camera intrinsics: name = {self.name!r} must be a non-empty string")
        for key in ("width", "height"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
                raise InputError(f"{label}: {key} = {value!r} must be a positive integer")
        for key in ("fx", "fy", "cx", "cy", "min_depth", "max_depth"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int | float | np.number):
                raise InputError(f"{label}: {key} = {value!r} must be a number")
            if not math.isfinite(value):
                raise InputError(f"{label}: {key} = {value!r} must be finite")
        if self.fx <= 0 or self.fy <= 0:
            raise InputError(f"{label}: focal lengths must be positive (fx = {self.fx}, fy = {self.fy})")
        if not -0.5 <= self.cx <= self.width - 0.5:
            raise InputError(
                f"{label}: principal point cx = {self.cx} lies outside the image [-0.5, {self.width - 0.5}]"
            )
        if not -0.5 <= self.cy <= self.height - 0.5:
            raise InputError(
                f"{label}: principal point cy = {self.cy} lies outside the image [-0.5, {self.height - 0.5}]"
            )
        if self.min_depth <= 0:
            raise InputError(f"{label}: min_depth = {self.min_depth} must be positive")
        if self.min_depth >= self.max_depth:
            raise InputError(f"{label}: min_depth = {self.min_depth} must be below max_depth = {self.max_depth}")
        for key in ("width", "height"):  # what the renderer and a 32 x 32 px grasp thumbnail can use
            if not IMAGE_PIXELS[0] <= getattr(self, key) <= IMAGE_PIXELS[1]:
                raise InputError(f"{label}: {key} = {getattr(self, key)} px outside {list(IMAGE_PIXELS)}")
        for key, size, focal in (("horizontal", self.width, self.fx), ("vertical", self.height, self.fy)):
            fov = math.degrees(2 * math.atan(size / (2 * focal)))
            if not FOV_DEG[0] <= fov <= FOV_DEG[1]:
                raise InputError(f"{label}: {key} field of view {fov:.3g} deg (from the focal length) outside "
                                 f"{list(FOV_DEG)} deg")
        if self.max_depth > MAX_DEPTH_M:
            raise InputError(f"{label}: max_depth = {self.max_depth} m beyond {MAX_DEPTH_M} m (the scene's far "
                             "clip plane; depth cameras for picking see a few metres)")

    @property
    def matrix(self) -> np.ndarray:
        """The 3x3 calibration matrix K (maps camera-frame rays to homogeneous pixels)."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def fov(self) -> tuple[float, float]:
        """Horizontal and vertical field of view in radians, measured edge to edge of the image."""
        left, right = self.cx + 0.5, self.width - 0.5 - self.cx
        top, bottom = self.cy + 0.5, self.height - 0.5 - self.cy
        return (
            math.atan(left / self.fx) + math.atan(right / self.fx),
            math.atan(top / self.fy) + math.atan(bottom / self.fy),
        )

    def project(self, points_cam: np.ndarray) -> np.ndarray:
        """Pixel coordinates (..., 2) = (u, v) of camera-frame points (..., 3).

        Points on or behind the image plane (z <= 0) have no image and give NaN.
        """
        p = np.asarray(points_cam, dtype=float)
        if p.shape[-1] != 3:
            raise ValueError(f"points must have shape (..., 3), got {p.shape}")
        z = p[..., 2]
        safe = np.where(z > 0, z, np.nan)
        u = self.fx * p[..., 0] / safe + self.cx
        v = self.fy * p[..., 1] / safe + self.cy
        return np.stack([u, v], axis=-1)

    def deproject(self, depth: np.ndarray, corner: tuple[int, int] | None = None) -> np.ndarray:
        """Camera-frame points (H, W, 3) of a z-depth image (H, W); zero depth gives the origin.

        Pixel (row v, column u) is back-projected through its centre, matching `project`. With
        `corner` = (row, column), `depth` is the window of the image whose top-left pixel that is
        (any size; the same values as deprojecting the whole image and cutting the window).
        """
        depth = np.asarray(depth)
        if corner is None and depth.shape != (self.height, self.width):
            raise ValueError(f"depth image has shape {depth.shape}, camera '{self.name}' expects "
                             f"{(self.height, self.width)}")
        top, left = corner or (0, 0)
        z = depth.astype(float)
        points = np.empty((*z.shape, 3))  # filled in place: ~3x faster than stacking three images
        u = np.arange(left, left + z.shape[1], dtype=float)[None, :]
        v = np.arange(top, top + z.shape[0], dtype=float)[:, None]
        np.multiply(u - self.cx, z, out=points[..., 0])
        np.multiply(v - self.cy, z, out=points[..., 1])
        points[..., 0] /= self.fx  # (u - cx) z / fx, rounded as written
        points[..., 1] /= self.fy
        points[..., 2] = z
        return points

    def scaled(self, factor: float, *, name: str | None = None) -> CameraIntrinsics:
        """The same camera at `factor` times the resolution (e.g. 0.5 for 2x2 binning).

        The image must scale to whole pixels. Focal lengths scale by the factor and the principal
        point scales about the image corner (-0.5, -0.5), which keeps every ray on the same
        (fractional) image position.
        """
        width, height = self.width * factor, self.height * factor
        if not (factor > 0 and float(width).is_integer() and float(height).is_integer()):
            raise InputError(f"camera '{self.name}': scale {factor} does not give a whole-pixel image "
                             f"({self.width} x {self.height} -> {width} x {height})")
        return replace(
            self, name=name or f"{self.name}@{factor:g}", width=int(width), height=int(height),
            fx=self.fx * factor, fy=self.fy * factor,
            cx=(self.cx + 0.5) * factor - 0.5, cy=(self.cy + 0.5) * factor - 0.5,
        )


# Presets. Rendered images have no distortion and the presets use a centred principal point with
# square pixels: a real unit's calibration differs by a few pixels and a few percent in focal
# length, so for a specific device load its calibrated intrinsics with `load_intrinsics_toml`.

PRIMESENSE = CameraIntrinsics(
    # The Primesense Carmine 1.08/1.09 parameters of Dex-Net's depth images (gqcnn's primesense
    # intrinsics: fx = fy = 525, centred principal point) and the Carmine 1.09 short-range working
    # range of ~0.35-1.4 m.
    name="primesense", width=640, height=480, fx=525.0, fy=525.0, cx=319.5, cy=239.5,
    min_depth=0.35, max_depth=1.4,
)
"""Primesense Carmine as used by Dex-Net 3.0: the default, matching the paper's training data."""

REALSENSE_D415 = CameraIntrinsics(
    # Intel RealSense D400 datasheet: D415 depth FOV (HD, 16:9) H 65 +- 2 deg x V 40 +- 1 deg,
    # 1280 x 720 being its best depth resolution. fx = fy = 640 / tan(32.5 deg) = 1004.6 px
    # (implied V FOV 39.4 deg, within the datasheet's tolerance). min_depth is Intel's Min-Z rule,
    # focal length (px) x baseline / 126 px of disparity search = 1004.6 x 0.055 m / 126 = 0.44 m;
    # max_depth is the 3 m end of Intel's stated ideal range.
    name="realsense-d415", width=1280, height=720, fx=1004.6, fy=1004.6, cx=639.5, cy=359.5,
    min_depth=0.44, max_depth=3.0,
)
"""Intel RealSense D415 depth stream at 1280 x 720 (nominal, from the datasheet field of view)."""

REALSENSE_D435 = CameraIntrinsics(
    # Intel RealSense D400 datasheet: D435 depth FOV (HD) H 87 +- 3 deg x V 58 +- 1 deg; 848 x 480 is
    # Intel's recommended depth resolution for the D435. fx = fy = 424 / tan(43.5 deg) = 446.8 px
    # (implied V FOV 56.5 deg). A unit's rs-enumerate-devices output (realsense-ros issue #2788)
    # shows fx = 424.2 px at 848 wide, i.e. 90 deg, inside the datasheet tolerance.
    # min_depth by the Min-Z rule: 446.8 x 0.050 m baseline / 126 = 0.18 m; max_depth 3 m as above.
    name="realsense-d435", width=848, height=480, fx=446.8, fy=446.8, cx=423.5, cy=239.5,
    min_depth=0.18, max_depth=3.0,
)
"""Intel RealSense D435 depth stream at 848 x 480 (nominal, from the datasheet field of view)."""

ZIVID_2 = CameraIntrinsics(
    # Zivid 2 (M70) full-resolution 3D capture: 1944 x 1200 (Zivid docs, "Sampling (3D)" page).
    # No official intrinsics table was found; fx = fy = 1800 px gives a 56.7 deg x 36.9 deg field
    # of view, matching the ~57 deg horizontal field of view quoted for the M70 (about 0.77 m wide
    # at its 0.7 m optimal distance). Working range 0.35-1.1 m is the M70's nominal one.
    # Treat all of this as nominal: use `zivid.experimental.calibration.intrinsics(camera)` and a
    # TOML file for a real unit.
    name="zivid-2", width=1944, height=1200, fx=1800.0, fy=1800.0, cx=971.5, cy=599.5,
    min_depth=0.35, max_depth=1.1,
)
"""Zivid 2 M70 structured-light camera at full resolution (nominal values)."""

CAMERA_PRESETS: dict[str, CameraIntrinsics] = {
    c.name: c for c in (PRIMESENSE, REALSENSE_D415, REALSENSE_D435, ZIVID_2)
}
"""Named camera presets; `primesense` is the default (the camera of the paper's dataset)."""

DEFAULT_CAMERA = "primesense"
"""Name of the default preset."""


def camera_preset(name: str) -> CameraIntrinsics:
    """Return a named camera preset (case-insensitive), or raise InputError naming the known ones."""
    try:
        return CAMERA_PRESETS[name.strip().lower()]
    except (KeyError, AttributeError):
        known = ", ".join(sorted(CAMERA_PRESETS))
        raise InputError(f"camera preset '{name}' is unknown (known: {known})") from None


def intrinsics_from_dict(
    data: dict[str, Any], *, source: str = "camera intrinsics", default_name: str = "custom"
) -> CameraIntrinsics:
    """Build intrinsics from a dict whose keys are the dataclass fields; a missing `name` becomes
    `default_name`. Errors name `source` (e.g. the file) and the offending key."""
    names = [f.name for f in fields(CameraIntrinsics)]
    unknown = sorted(set(data) - set(names))
    if unknown:
        raise InputError(f"{source}: unknown key(s) {', '.join(unknown)} (expected {', '.join(names)})")
    missing = [key for key in names if key not in data and key != "name"]
    if missing:
        raise InputError(f"{source}: missing key(s) {', '.join(missing)}")
    kwargs = dict(data)
    kwargs.setdefault("name", default_name)
    for key in ("width", "height"):
        value = kwargs[key]
        if isinstance(value, float) and value.is_integer():
            kwargs[key] = int(value)
    try:
        return CameraIntrinsics(**kwargs)
    except InputError as exc:
        raise InputError(f"{source}: {exc}") from None


def load_intrinsics_toml(path: str | Path) -> CameraIntrinsics:
    """Load user intrinsics from a TOML file with one key per `CameraIntrinsics` field, e.g.::

        name = "my-d435"
        width = 848
        height = 480
        fx = 425.19
        fy = 425.19
        cx = 422.97
        cy = 238.47
        min_depth = 0.18
        max_depth = 3.0

    `name` defaults to the file name without its suffix. Raises InputError naming the file.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise InputError(f"camera intrinsics '{path}': file not found") from None
    except (IsADirectoryError, PermissionError, UnicodeDecodeError) as exc:
        raise InputError(f"camera intrinsics '{path}': cannot be read ({exc})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"camera intrinsics '{path}': not valid TOML ({exc})") from None
    return intrinsics_from_dict(data, source=str(path), default_name=path.stem or "custom")


def intrinsics_to_toml(intrinsics: CameraIntrinsics) -> str:
    """The TOML text `load_intrinsics_toml` reads back to `intrinsics` (a template for one's own
    camera: `suctionbench cameras --toml NAME`)."""
    lines = [f"# {intrinsics.name}: pinhole depth camera, OpenCV pixel-centre convention, metres"]
    for f in fields(CameraIntrinsics):
        value = getattr(intrinsics, f.name)
        lines.append(f'{f.name} = "{value}"' if isinstance(value, str) else f"{f.name} = {value!r}")
    return "\n".join(lines) + "\n"


def camera_summary(intrinsics: CameraIntrinsics) -> dict[str, Any]:
    """One row of `suctionbench cameras`: resolution, focal lengths, principal point, field of
    view (deg) and working range (m)."""
    hfov, vfov = intrinsics.fov
    return {
        "name": intrinsics.name, "width": intrinsics.width, "height": intrinsics.height,
        "fx": intrinsics.fx, "fy": intrinsics.fy, "cx": intrinsics.cx, "cy": intrinsics.cy,
        "hfov_deg": round(math.degrees(hfov), 1), "vfov_deg": round(math.degrees(vfov), 1),
        "min_depth": intrinsics.min_depth, "max_depth": intrinsics.max_depth,
        "default": intrinsics.name == DEFAULT_CAMERA,
    }


def resolve_camera(spec: str | Path) -> CameraIntrinsics:
    """A preset name or the path of an intrinsics TOML file (what `--camera` accepts)."""
    text = str(spec)
    if text.lower().endswith(".toml") or Path(text).is_file():
        return load_intrinsics_toml(text)
    return camera_preset(text)


# --------------------------------------------------------------------------------------------------
# MuJoCo glue
# --------------------------------------------------------------------------------------------------

MUJOCO_FROM_OPENCV = np.diag([1.0, -1.0, -1.0])
"""Rotation from OpenCV optical-frame coordinates to MuJoCo camera-frame coordinates (and back:
it is its own inverse). R_world_mujoco = R_world_opencv @ MUJOCO_FROM_OPENCV."""

_PIXEL_PITCH = 3e-6
"""Nominal sensor pixel pitch (m) used to express pixel intrinsics in MuJoCo's length units. Only
ratios matter for rendering; a realistic value keeps MuJoCo's frustum visualisation sensible."""


def mujoco_principal_pixel(intrinsics: CameraIntrinsics) -> tuple[float, float]:
    """MuJoCo `principalpixel` offsets that put the rendered principal point at (cx, cy).

    MuJoCo 3.17 offsets the principal point from the image centre ((W - 1) / 2, (H - 1) / 2) by
    *minus* the attribute in both image directions: found by rendering off-axis markers (the x
    sign is opposite to MuJoCo's x-right camera axis), and guarded by tests/test_camera.py, which
    renders with a deliberately off-centre principal point.
    """
    return ((intrinsics.width - 1) / 2 - intrinsics.cx, (intrinsics.height - 1) / 2 - intrinsics.cy)


def add_camera(
    spec: mujoco.MjSpec, name: str, pose_world: np.ndarray, intrinsics: CameraIntrinsics
) -> mujoco.MjsCamera:
    """Add a fixed camera named `name` to the world body of `spec` with exact pinhole intrinsics.

    `pose_world` is the world-from-camera transform in the OpenCV frame. The camera gets MuJoCo's
    physical intrinsics (resolution, sensor size, focal length and principal point in pixels),
    which take precedence over fovy, so fx != fy and off-centre principal points are rendered
    exactly; fovy is still set to the vertical field of view for tools that read it. The
    offscreen buffer is enlarged when needed so a `DepthRenderer` of this size can be created.
    """
    import mujoco

    pose = np.asarray(pose_world, dtype=float)
    if pose.shape != (4, 4):
        raise ValueError(f"pose_world must be a 4x4 transform, got shape {pose.shape}")
    rotation = pose[:3, :3] @ MUJOCO_FROM_OPENCV
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(rotation).ravel())
    camera = spec.worldbody.add_camera(name=name, pos=pose[:3, 3].tolist(), quat=quat.tolist())
    w, h = intrinsics.width, intrinsics.height
    camera.resolution = [w, h]
    camera.sensor_size = [w * _PIXEL_PITCH, h * _PIXEL_PITCH]
    camera.focal_pixel = [intrinsics.fx, intrinsics.fy]
    camera.principal_pixel = list(mujoco_principal_pixel(intrinsics))
    camera.fovy = math.degrees(2.0 * math.atan(h / (2.0 * intrinsics.fy)))
    visual = spec.visual.global_
    visual.offwidth = max(visual.offwidth, w)
    visual.offheight = max(visual.offheight, h)
    return camera


def camera_pose_from_data(model: mujoco.MjModel, data: mujoco.MjData, camera_name: str) -> np.ndarray:
    """Current world-from-camera pose (4x4, OpenCV frame) of a model camera (after mj_forward or
    mj_kinematics), e.g. for cameras attached to moving bodies."""
    import mujoco

    cam_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera_name)
    if cam_id < 0:
        raise ValueError(f"model has no camera named '{camera_name}'")
    pose = np.eye(4)
    pose[:3, :3] = data.cam_xmat[cam_id].reshape(3, 3) @ MUJOCO_FROM_OPENCV
    pose[:3, 3] = data.cam_xpos[cam_id]
    return pose


def body_image(model: Any, segmentation: np.ndarray) -> np.ndarray:
    """The body id (H, W) int of every pixel of a segmentation image (`DepthRenderer.segment`) that
    shows a geom, -1 elsewhere."""
    import mujoco

    is_geom = segmentation[..., 1] == mujoco.mjtObj.mjOBJ_GEOM
    return np.where(is_geom, model.geom_bodyid[np.clip(segmentation[..., 0], 0, None)], -1)


def render_colour(model: Any, data: Any, camera: str, intrinsics: CameraIntrinsics) -> np.ndarray:
    """A model camera's colour view of a state, (H, W, 3) uint8. The OpenGL context is made and freed
    per call (about 0.2 s): one left for the garbage collector at interpreter exit fails noisily."""
    import mujoco

    renderer = mujoco.Renderer(model, intrinsics.height, intrinsics.width)
    try:
        renderer.update_scene(data, camera)
        return renderer.render().copy()
    finally:
        renderer.close()


class DepthRenderer:
    """Metric z-depth images of model cameras through MuJoCo's offscreen OpenGL renderer.

    One renderer serves every camera of the model that has the intrinsics' resolution. Only the
    geom groups in `geom_groups` are drawn (MuJoCo's default 0-2, where suctionbench puts visual
    geoms; collision-only parts sit in group 3), and sites and tendons are hidden because a real
    depth sensor does not see them. Headless machines need MUJOCO_GL=egl (or osmesa) in the
    environment before mujoco is first imported. Release the OpenGL context with `close()` or a
    `with` block: contexts left to the garbage collector fail noisily at interpreter exit.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        intrinsics: CameraIntrinsics,
        *,
        geom_groups: tuple[int, ...] = (0, 1, 2),
    ) -> None:
        import mujoco

        self._model = model
        self.intrinsics = intrinsics
        extent = float(model.stat.extent)
        near, far = model.vis.map.znear * extent, model.vis.map.zfar * extent
        if near >= intrinsics.min_depth or far <= intrinsics.max_depth:
            raise ValueError(
                f"clip planes [{near:.3f}, {far:.3f}] m (visual.map.znear/zfar x stat.extent = {extent:.3f}) "
                f"do not contain camera '{intrinsics.name}''s working range "
                f"[{intrinsics.min_depth}, {intrinsics.max_depth}] m; lower spec.visual.map.znear or raise zfar"
            )
        # The renderer maps the cleared depth buffer (nothing drawn) to exactly the far plane,
        # computed in float32; anything at or beyond (1 - 1e-6) far is background.
        self._background = np.float32(far) * np.float32(1.0 - 1e-6)
        try:
            self._renderer = mujoco.Renderer(model, height=intrinsics.height, width=intrinsics.width)
        except ValueError:
            raise
        except Exception as exc:  # no OpenGL context: the usual cause is a missing MUJOCO_GL
            raise RuntimeError(
                f"cannot create an OpenGL context for depth rendering ({exc}); on a headless machine set "
                "MUJOCO_GL=egl (or osmesa) before mujoco is imported"
            ) from exc
        self._renderer.enable_depth_rendering()
        self._option = mujoco.MjvOption()
        self._option.geomgroup[:] = [1 if g in geom_groups else 0 for g in range(len(self._option.geomgroup))]
        self._option.sitegroup[:] = 0
        self._option.flags[mujoco.mjtVisFlag.mjVIS_TENDON] = 0

    def render(self, data: mujoco.MjData, camera_name: str) -> np.ndarray:
        """Depth image (H, W) float32 in metres along the optical axis; 0 where nothing is hit
        (including beyond the far clip plane)."""
        cam_id = self._camera_id(camera_name)
        self._renderer.update_scene(data, camera=cam_id, scene_option=self._option)
        depth = self._renderer.render()
        depth[depth >= self._background] = 0.0
        return depth

    def segment(self, data: mujoco.MjData, camera_name: str) -> np.ndarray:
        """MuJoCo's segmentation of the same view, (H, W, 2) int32: object id and object type per
        pixel (-1 for background), drawn with the same visible groups as the depth image. Shares
        this renderer's OpenGL context, which costs far less than creating a second one."""
        cam_id = self._camera_id(camera_name)
        self._renderer.disable_depth_rendering()
        self._renderer.enable_segmentation_rendering()
        try:
            self._renderer.update_scene(data, camera=cam_id, scene_option=self._option)
            return self._renderer.render()
        finally:
            self._renderer.disable_segmentation_rendering()
            self._renderer.enable_depth_rendering()

    def _camera_id(self, camera_name: str) -> int:
        """The camera's id, checked to exist and to have this renderer's resolution."""
        import mujoco

        if self._renderer is None:
            raise RuntimeError("DepthRenderer used after close()")
        cam_id = mujoco.mj_name2id(self._model, mujoco.mjtObj.mjOBJ_CAMERA, camera_name)
        if cam_id < 0:
            raise ValueError(f"model has no camera named '{camera_name}'")
        resolution = tuple(int(x) for x in self._model.cam_resolution[cam_id])
        expected = (self.intrinsics.width, self.intrinsics.height)
        if resolution != expected:
            raise ValueError(
                f"camera '{camera_name}' has resolution {resolution}, this renderer renders {expected} "
                f"(camera '{self.intrinsics.name}'); add the camera with add_camera and these intrinsics"
            )
        return cam_id

    def close(self) -> None:
        """Free the OpenGL context (idempotent)."""
        renderer, self._renderer = getattr(self, "_renderer", None), None
        if renderer is not None:
            renderer.close()

    def __enter__(self) -> DepthRenderer:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()
