"""Camera models: presets and TOML intrinsics, the paper's camera-pose distribution, and the
agreement of MuJoCo depth renders with the pinhole model (intrinsics + pose) that the rest of the
pipeline uses to project grasps into images."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import math  # noqa: E402

import mujoco  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from scipy import ndimage, stats  # noqa: E402

from suctionbench.errors import InputError  # noqa: E402
from suctionbench.sensing.camera import (  # noqa: E402
    CAMERA_PRESETS,
    MUJOCO_FROM_OPENCV,
    PRIMESENSE,
    CameraIntrinsics,
    DepthRenderer,
    add_camera,
    camera_pose_from_data,
    camera_preset,
    load_intrinsics_toml,
    resolve_camera,
)
from suctionbench.sensing.camera_pose import (  # noqa: E402
    CAMERA_POSE_PAPER,
    CameraPoseConfig,
    camera_pose_from_spherical,
    sample_camera_pose,
)

# ------------------------------------------------------------------------------------------------
# (a) intrinsics, presets, TOML
# ------------------------------------------------------------------------------------------------


def test_primesense_is_the_paper_camera():
    cam = camera_preset("primesense")
    assert cam is PRIMESENSE
    assert (cam.width, cam.height) == (640, 480)
    assert (cam.fx, cam.fy, cam.cx, cam.cy) == (525.0, 525.0, 319.5, 239.5)
    assert (cam.min_depth, cam.max_depth) == (0.35, 1.4)
    np.testing.assert_array_equal(cam.matrix, [[525.0, 0, 319.5], [0, 525.0, 239.5], [0, 0, 1]])


@pytest.mark.parametrize("name", sorted(CAMERA_PRESETS))
def test_every_preset_is_a_valid_pinhole_camera(name):
    cam = camera_preset(name.upper())  # names are case-insensitive
    assert cam.name == name
    k = cam.matrix
    assert k.shape == (3, 3) and k[2, 2] == 1.0 and k[0, 1] == k[1, 0] == k[2, 0] == k[2, 1] == 0.0
    assert k[0, 0] > 0 and k[1, 1] > 0
    assert 0 <= k[0, 2] <= cam.width - 1 and 0 <= k[1, 2] <= cam.height - 1
    assert 0 < cam.min_depth < cam.max_depth
    fov_x, fov_y = cam.fov
    assert math.radians(30) < fov_x < math.radians(100) and math.radians(20) < fov_y < math.radians(80)
    # Every preset can see the paper's camera distances.
    assert CAMERA_POSE_PAPER.for_camera(cam).radius_range == CAMERA_POSE_PAPER.radius_range


def test_preset_fields_of_view_match_their_sources():
    assert math.degrees(camera_preset("realsense-d415").fov[0]) == pytest.approx(65.0, abs=0.1)
    assert math.degrees(camera_preset("realsense-d435").fov[0]) == pytest.approx(87.0, abs=0.1)
    assert (camera_preset("zivid-2").width, camera_preset("zivid-2").height) == (1944, 1200)


def test_unknown_preset_names_the_known_ones():
    with pytest.raises(InputError, match="unknown.*primesense.*realsense-d415"):
        camera_preset("kinect")


def test_project_and_deproject_are_inverse():
    cam = CameraIntrinsics("t", 64, 48, 50.0, 45.0, 30.0, 20.0, 0.1, 2.0)
    depth = np.random.default_rng(0).uniform(0.2, 1.0, size=(48, 64))
    points = cam.deproject(depth)
    assert points.shape == (48, 64, 3)
    np.testing.assert_allclose(points[..., 2], depth)
    uv = cam.project(points.reshape(-1, 3))
    v, u = np.mgrid[0:48, 0:64]
    np.testing.assert_allclose(uv, np.stack([u.ravel(), v.ravel()], axis=1), atol=1e-9)
    assert np.all(np.isnan(cam.project(np.array([[0.1, 0.2, 0.0], [0.1, 0.2, -1.0]]))))
    np.testing.assert_array_equal(cam.deproject(np.zeros((48, 64))), 0.0)
    # a window of the image, given its corner, deprojects to the same points
    np.testing.assert_array_equal(cam.deproject(depth[7:20, 30:61], corner=(7, 30)), points[7:20, 30:61])


def test_scaled_keeps_rays_on_the_same_image_position():
    half = camera_preset("zivid-2").scaled(0.5)
    assert (half.width, half.height, half.cx, half.cy, half.fx) == (972, 600, 485.5, 299.5, 900.0)
    p = np.array([[0.1, -0.05, 0.7]])
    full_uv = camera_preset("zivid-2").project(p)
    np.testing.assert_allclose(half.project(p), (full_uv + 0.5) * 0.5 - 0.5)
    with pytest.raises(InputError, match="whole-pixel"):
        PRIMESENSE.scaled(0.33)


GOOD_TOML = """
name = "my-d435"
width = 848
height = 480
fx = 425.19
fy = 425.5
cx = 422.97
cy = 238.47
min_depth = 0.18
max_depth = 3.0
"""


def test_load_intrinsics_toml(tmp_path):
    path = tmp_path / "cam.toml"
    path.write_text(GOOD_TOML)
    cam = load_intrinsics_toml(path)
    assert cam == CameraIntrinsics("my-d435", 848, 480, 425.19, 425.5, 422.97, 238.47, 0.18, 3.0)
    assert resolve_camera(path) == cam
    assert resolve_camera("Primesense") is PRIMESENSE
    # The name defaults to the file's stem.
    path.write_text(GOOD_TOML.replace('name = "my-d435"', ""))
    assert load_intrinsics_toml(path).name == "cam"


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (("fx = 425.19", ""), "missing key.*fx"),
        (("fx = 425.19", "fx = 425.19\nskew = 0.0"), "unknown key.*skew"),
        (("fx = 425.19", "fx = -1.0"), "focal lengths must be positive"),
        (("fy = 425.5", "fy = 0"), "focal lengths must be positive"),
        (("cx = 422.97", "cx = 900.0"), "cx = 900.0 lies outside the image"),
        (("cy = 238.47", "cy = -3.0"), "cy = -3.0 lies outside the image"),
        (("min_depth = 0.18", "min_depth = 3.0"), "min_depth = 3.0 must be below max_depth"),
        (("min_depth = 0.18", "min_depth = 0.0"), "min_depth = 0.0 must be positive"),
        (("fx = 425.19", "fx = nan"), "fx = nan must be finite"),
        (("width = 848", "width = 848.5"), "width = 848.5 must be a positive integer"),
        (("width = 848", 'width = "848"'), "width = '848' must be a positive integer"),
        (("fy = 425.5", "fy = true"), "fy = True must be a number"),
        (("fx = 425.19", "fx = [1"), "not valid TOML"),
    ],
)
def test_bad_intrinsics_toml_names_file_and_problem(tmp_path, edit, message):
    path = tmp_path / "bad.toml"
    path.write_text(GOOD_TOML.replace(*edit))
    with pytest.raises(InputError, match=message) as info:
        load_intrinsics_toml(path)
    assert "bad.toml" in str(info.value)


def test_missing_intrinsics_file(tmp_path):
    with pytest.raises(InputError, match="file not found"):
        load_intrinsics_toml(tmp_path / "absent.toml")
    with pytest.raises(InputError, match="file not found"):
        resolve_camera(tmp_path / "absent.toml")


# ------------------------------------------------------------------------------------------------
# (b) camera-pose distribution
# ------------------------------------------------------------------------------------------------


def _spherical(poses, target):
    offset = poses[:, :3, 3] - target
    radius = np.linalg.norm(offset, axis=1)
    polar = np.arccos(offset[:, 2] / radius)
    azimuth = np.mod(np.arctan2(offset[:, 1], offset[:, 0]), 2 * np.pi)
    return radius, azimuth, polar


def test_sampled_poses_follow_the_paper_distribution():
    target = np.array([0.45, -0.15, 0.0])
    rng = np.random.default_rng(7)
    poses = np.stack([sample_camera_pose(rng, target) for _ in range(1000)])
    radius, azimuth, polar = _spherical(poses, target)
    assert radius.min() >= 0.5 and radius.max() <= 0.7
    assert polar.min() >= 0.01 * np.pi - 1e-12 and polar.max() <= 0.1 * np.pi + 1e-12
    # Uniform in each spherical coordinate (fixed seed: a deterministic check).
    for values, lo, hi in ((radius, 0.5, 0.7), (azimuth, 0.0, 2 * np.pi), (polar, 0.01 * np.pi, 0.1 * np.pi)):
        assert stats.kstest(values, stats.uniform(lo, hi - lo).cdf).pvalue > 1e-3

    rot = poses[:, :3, :3]
    np.testing.assert_allclose(np.einsum("nji,njk->nik", rot, rot), np.broadcast_to(np.eye(3), rot.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(rot), 1.0, atol=1e-12)
    # The optical axis passes through the target, looking towards it, at depth = radius.
    z = rot[:, :, 2]
    to_target = target - poses[:, :3, 3]
    along = np.einsum("ni,ni->n", to_target, z)
    off_axis = np.linalg.norm(to_target - along[:, None] * z, axis=1)
    assert off_axis.max() < 1e-9
    np.testing.assert_allclose(along, radius, atol=1e-12)
    # Roll convention: camera x horizontal, image down leaning towards the camera's side.
    assert np.abs(rot[:, 2, 0]).max() < 1e-12
    assert np.all(np.einsum("ni,ni->n", rot[:, :2, 1], -to_target[:, :2]) > 0)


def test_pose_sampling_is_deterministic_given_the_seed():
    target = np.zeros(3)
    a = [sample_camera_pose(np.random.default_rng(3), target) for _ in range(2)]
    b = sample_camera_pose(np.random.default_rng(4), target)
    np.testing.assert_array_equal(a[0], a[1])
    assert not np.allclose(a[0], b)


def test_spherical_pose_overhead_is_defined():
    pose = camera_pose_from_spherical([0.1, 0.2, 0.0], 0.6, 0.3, 0.0)
    np.testing.assert_allclose(pose[:3, 3], [0.1, 0.2, 0.6])
    np.testing.assert_allclose(pose[:3, 2], [0.0, 0.0, -1.0], atol=1e-15)
    np.testing.assert_allclose(pose[:3, 1], [math.cos(0.3), math.sin(0.3), 0.0], atol=1e-15)


def test_radius_range_is_fitted_into_the_working_range():
    def cam(near, far):
        return CameraIntrinsics("c", 64, 48, 50.0, 50.0, 31.5, 23.5, near, far)

    assert CAMERA_POSE_PAPER.for_camera(cam(0.6, 2.0)).radius_range == (0.6, 0.7)
    assert CAMERA_POSE_PAPER.for_camera(cam(0.2, 0.65)).radius_range == (0.5, 0.65)
    assert CAMERA_POSE_PAPER.for_camera(cam(0.8, 2.0)).radius_range == pytest.approx((0.8, 1.0))
    assert CAMERA_POSE_PAPER.for_camera(cam(0.1, 0.3)).radius_range == pytest.approx((0.1, 0.3))
    assert CAMERA_POSE_PAPER.for_camera(cam(0.1, 0.4)).radius_range == pytest.approx((0.2, 0.4))
    for bad in ({"radius_range": (0.7, 0.5)}, {"radius_range": (0.0, 0.5)}, {"radius_range": (0.5,)},
                {"polar_range": (0.1, math.pi / 2)}, {"azimuth_range": (0.0, math.nan)}):
        with pytest.raises(InputError, match=next(iter(bad))):
            CameraPoseConfig(**bad)


# ------------------------------------------------------------------------------------------------
# (c) rendered depth agrees with the pinhole model
# ------------------------------------------------------------------------------------------------

BOX_CENTRE, BOX_HALF = np.array([0.06, -0.03, 0.04]), np.array([0.04, 0.03, 0.04])
SPHERE_CENTRE, SPHERE_RADIUS = np.array([-0.07, 0.05, 0.03]), 0.03
PLANE, BOX, SPHERE, NOTHING = 0, 1, 2, -1


@pytest.fixture(scope="module")
def gl_available():
    """Skip (rather than fail) the rendering tests on machines without any OpenGL backend."""
    spec = mujoco.MjSpec()
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.1, 0, 0])
    model = spec.compile()
    try:
        mujoco.Renderer(model, 8, 8).close()
    except Exception as exc:  # pragma: no cover - depends on the machine
        pytest.skip(f"no OpenGL context for MuJoCo rendering ({exc})")


def _scene(intrinsics, pose):
    spec = mujoco.MjSpec()
    world = spec.worldbody
    world.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[1.0, 1.0, 0.05])
    world.add_geom(name="box", type=mujoco.mjtGeom.mjGEOM_BOX, size=BOX_HALF.tolist(), pos=BOX_CENTRE.tolist())
    world.add_geom(name="ball", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[SPHERE_RADIUS, 0, 0],
                   pos=SPHERE_CENTRE.tolist())
    world.add_site(name="marker", pos=[0.0, 0.0, 0.2], size=[0.05, 0, 0])  # must not show in depth
    add_camera(spec, "cam", pose, intrinsics)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def _render(intrinsics, pose):
    model, data = _scene(intrinsics, pose)
    # MuJoCo's camera frame (looking along -z, y up) is the OpenCV frame turned by pi about x.
    mj_rotation = data.cam_xmat[model.camera("cam").id].reshape(3, 3)
    np.testing.assert_allclose(mj_rotation @ MUJOCO_FROM_OPENCV, pose[:3, :3], atol=1e-12)
    np.testing.assert_allclose(camera_pose_from_data(model, data, "cam"), pose, atol=1e-12)
    with DepthRenderer(model, intrinsics) as renderer:
        depth = renderer.render(data, "cam")
    return depth


def _raycast(intrinsics, pose):
    """Analytic z-depth and surface label per pixel centre, from the intrinsics and pose alone."""
    v, u = np.mgrid[0 : intrinsics.height, 0 : intrinsics.width].astype(float)
    d_cam = np.stack([(u - intrinsics.cx) / intrinsics.fx, (v - intrinsics.cy) / intrinsics.fy, np.ones_like(u)], -1)
    d = d_cam @ pose[:3, :3].T  # world direction per unit of z-depth
    o = pose[:3, 3]
    hits = np.full(u.shape + (3,), np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -o[2] / d[..., 2]
        hits[..., PLANE] = np.where(t > 0, t, np.inf)
        t0, t1 = (BOX_CENTRE - BOX_HALF - o) / d, (BOX_CENTRE + BOX_HALF - o) / d
        t_near = np.minimum(t0, t1).max(-1)
        t_far = np.maximum(t0, t1).min(-1)
        hits[..., BOX] = np.where((t_near <= t_far) & (t_near > 0), t_near, np.inf)
        oc = o - SPHERE_CENTRE
        a, b, c = (d * d).sum(-1), 2 * (d @ oc), oc @ oc - SPHERE_RADIUS**2
        disc = b * b - 4 * a * c
        t = (-b - np.sqrt(disc)) / (2 * a)
        hits[..., SPHERE] = np.where((disc >= 0) & (t > 0), t, np.inf)
    label = np.argmin(hits, axis=-1)
    depth = np.min(hits, axis=-1)
    label[~np.isfinite(depth)] = NOTHING
    return np.where(np.isfinite(depth), depth, 0.0), label


def _interior(label):
    """Pixels whose 5x5 neighbourhood has one label: away from silhouettes, where a pixel's
    centre ray and the rasteriser may legitimately disagree."""
    lo = ndimage.minimum_filter(label, size=5, mode="nearest")
    hi = ndimage.maximum_filter(label, size=5, mode="nearest")
    return lo == hi


def test_segmentation_shares_the_depth_renderer_and_matches_the_ray_cast(gl_available):
    # The segmentation drawn by the depth renderer's own context labels every interior pixel with
    # the geom the analytic ray cast hits (the marker site is hidden, as in depth), and switching
    # to it and back leaves the depth image bit-identical.
    pose = sample_camera_pose(np.random.default_rng(4), np.array([0.02, 0.0, 0.0]), CameraPoseConfig())
    model, data = _scene(PRIMESENSE, pose)
    with DepthRenderer(model, PRIMESENSE) as renderer:
        before = renderer.render(data, "cam")
        segmentation = renderer.segment(data, "cam")
        after = renderer.render(data, "cam")
    np.testing.assert_array_equal(before, after)
    _, label = _raycast(PRIMESENSE, pose)
    inside = _interior(label) & (label != NOTHING)
    geom_of = {PLANE: model.geom("floor").id, BOX: model.geom("box").id, SPHERE: model.geom("ball").id}
    expected = np.vectorize(geom_of.get)(label)
    is_geom = segmentation[..., 1] == mujoco.mjtObj.mjOBJ_GEOM
    assert is_geom[inside].all()
    assert (segmentation[..., 0][inside] == expected[inside]).mean() > 0.999


OFF_CENTRE = CameraIntrinsics("off-centre", 640, 480, 540.0, 505.0, 290.0, 262.0, 0.3, 1.5)
"""fx != fy and a principal point 29.5 px left of and 22.5 px below the image centre."""


@pytest.mark.parametrize(
    ("intrinsics", "seed"),
    [(PRIMESENSE, 0), (PRIMESENSE, 1), (camera_preset("realsense-d435"), 2), (OFF_CENTRE, 3)],
    ids=["primesense-0", "primesense-1", "realsense-d435", "off-centre"],
)
def test_rendered_depth_matches_the_pinhole_model(gl_available, intrinsics, seed):
    target = np.array([0.02, 0.0, 0.0])
    config = CameraPoseConfig(polar_range=(0.08 * np.pi, 0.1 * np.pi))  # tilted: depth varies over the image
    pose = sample_camera_pose(np.random.default_rng(seed), target, config.for_camera(intrinsics))
    depth = _render(intrinsics, pose)
    assert depth.shape == (intrinsics.height, intrinsics.width) and depth.dtype == np.float32

    # (i) Known points on the box's top face: depth at the projected pixel = camera-frame z.
    rng = np.random.default_rng(seed)
    top = BOX_CENTRE + np.column_stack([rng.uniform(-0.8, 0.8, (8, 2)) * BOX_HALF[:2], np.full(8, BOX_HALF[2])])
    cam_points = (top - pose[:3, 3]) @ pose[:3, :3]
    uv = intrinsics.project(cam_points)
    cols, rows = np.rint(uv).astype(int).T
    assert np.all((cols >= 0) & (cols < intrinsics.width) & (rows >= 0) & (rows < intrinsics.height))
    np.testing.assert_allclose(depth[rows, cols], cam_points[:, 2], atol=1.5e-3)

    # (ii) Every pixel against an analytic ray cast, and the deprojected cloud in the world frame.
    expected, label = _raycast(intrinsics, pose)
    inside = _interior(label) & (label != NOTHING)
    assert inside.mean() > 0.9 and (label == BOX).sum() > 500 and (label == SPHERE).sum() > 300
    error = np.abs(depth - expected)[inside]
    assert np.median(error) < 5e-4 and np.percentile(error, 99) < 2e-3
    world = intrinsics.deproject(depth) @ pose[:3, :3].T + pose[:3, 3]
    plane_z = world[..., 2][inside & (label == PLANE)]
    assert np.median(np.abs(plane_z)) < 1e-3
    box_points = world[inside & (label == BOX)]
    top_z = box_points[box_points[:, 2] > BOX_CENTRE[2] + BOX_HALF[2] - 5e-3, 2]
    assert top_z.size > 300 and np.median(np.abs(top_z - 2 * BOX_HALF[2])) < 1e-3
    # A wrong principal point or focal length would shift the box's silhouette by pixels.
    rendered_box = np.abs(depth - expected) < 2e-3
    assert rendered_box[inside & (label == BOX)].mean() > 0.99


def test_background_renders_as_zero(gl_available):
    looking_up = np.eye(4)  # OpenCV axes = world axes: the optical axis points at the sky
    looking_up[:3, 3] = [0.0, 0.0, 0.5]
    np.testing.assert_array_equal(looking_up[:3, 2], [0.0, 0.0, 1.0])
    depth = _render(PRIMESENSE, looking_up)
    np.testing.assert_array_equal(depth, 0.0)

    # Looking at the horizon: the finite floor ends and the sky above it reads 0, not far.
    sideways = camera_pose_from_spherical([0.0, 0.0, 0.2], 0.5, 0.0, 0.45 * np.pi)
    depth = _render(PRIMESENSE, sideways)
    assert (depth == 0).mean() > 0.1 and (depth > 0).mean() > 0.1
    assert depth.max() < 5.0


def test_renderer_rejects_unknown_camera_and_wrong_resolution(gl_available):
    model, data = _scene(PRIMESENSE, camera_pose_from_spherical(np.zeros(3), 0.6, 0.0, 0.1))
    with DepthRenderer(model, PRIMESENSE) as renderer, pytest.raises(ValueError, match="no camera named 'nope'"):
        renderer.render(data, "nope")
    other = CameraIntrinsics("small", 320, 240, 262.5, 262.5, 159.5, 119.5, 0.35, 1.4)
    with DepthRenderer(model, other) as renderer, pytest.raises(ValueError, match="resolution"):
        renderer.render(data, "cam")
    renderer.close()  # idempotent
    with pytest.raises(RuntimeError, match="after close"):
        renderer.render(data, "cam")
