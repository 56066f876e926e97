"""Image grasp policies: the shared point-cloud geometry, the four heuristics on rendered scenes of one
object per set, the GQ-CNN cross-entropy policy with stub scorers, determinism and the registry."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from suctionbench.config import CUP_DEFAULT, to_dict
from suctionbench.dataset.render import TableScene
from suctionbench.errors import InputError
from suctionbench.objects.registry import load_object
from suctionbench.policies import gqcnn
from suctionbench.policies.base import (
    POLICIES,
    GraspAction,
    NoGraspError,
    Observation,
    Policy,
    SamplerConfig,
    disc_errors,
    make_policy,
    scene_cloud,
    surface_normals,
)
from suctionbench.policies.gqcnn import CEMConfig, GQCNNPolicy, fit_gmm
from suctionbench.sensing.camera import PRIMESENSE
from suctionbench.sensing.camera_pose import sample_camera_pose
from suctionbench.sensing.noise import apply_axial_noise
from suctionbench.sensing.thumbnails import (
    ThumbnailConfig,
    extract_context_thumbnails,
    extract_thumbnails,
    project_grasps,
    sample_thumbnails,
)

HEURISTICS = ["random", "centroid", "planarity", "planarity-centroid"]
OBJECTS = ["basic/box_tea", "typical/mug_classic", "adversarial/narrow_gear"]
CAMERA_SEED = 2  # a 15 deg tilted view (polar angle), r = 0.55 m: side faces are visible too


class Scene:
    """A rendered object in its most probable stable pose, with the ground-truth object mask from a
    second render without the object."""

    def __init__(self, key: str):
        self.record = load_object(key)
        self.pose = self.record.most_probable_pose()
        self.camera_pose = sample_camera_pose(np.random.default_rng(CAMERA_SEED), np.zeros(3))
        with TableScene(self.record, PRIMESENSE) as scene:
            self.depth = scene.render(self.pose, self.camera_pose)
            hidden = self.pose.copy()
            hidden[2, 3] -= 10.0  # under the table
            table = scene.render(hidden, self.camera_pose)
        self.mask = np.abs(self.depth - table) > 1e-3

    def observation(self, *, mask: np.ndarray | None = None) -> Observation:
        return Observation(self.depth, PRIMESENSE, self.camera_pose, mask=mask)

    def pixel_of(self, point_world: np.ndarray) -> np.ndarray:
        rotation, origin = self.camera_pose[:3, :3], self.camera_pose[:3, 3]
        return PRIMESENSE.project((np.asarray(point_world) - origin) @ rotation)


@pytest.fixture(scope="module")
def scenes() -> dict[str, Scene]:
    return {key: Scene(key) for key in OBJECTS}


class CentreDepthStub:
    """Scores a grasp by the depth at its thumbnail's centre: nearer the camera is better
    (q = exp(-(z - z_best) / scale)); checks the inputs' layout on every call."""

    def __init__(self, z_best: float, scale: float):
        self.z_best, self.scale, self.calls = z_best, scale, []

    def predict(self, images: np.ndarray, poses: np.ndarray) -> np.ndarray:
        assert images.dtype == np.float32 and images.ndim == 3 and images.shape[1:] == (32, 32)
        assert poses.dtype == np.float32 and poses.shape == (len(images), 2)
        self.calls.append((images, poses))
        centre = images[:, 15:17, 15:17].mean(axis=(1, 2)).astype(float)
        return np.exp(-np.maximum(centre - self.z_best, 0.0) / self.scale)


class ContextStub:
    """A two-channel scorer (grasp, context thumbnails): q falls with the context thumbnail's centre
    depth; records its inputs."""

    image_channels = 2

    def __init__(self):
        self.calls = []

    def predict(self, images: np.ndarray, poses: np.ndarray) -> np.ndarray:
        assert images.dtype == np.float32 and images.shape[1:] == (2, 32, 32)
        assert poses.dtype == np.float32 and poses.shape == (len(images), 2)
        self.calls.append((images, poses))
        return np.exp(-10.0 * images[:, 1, 15:17, 15:17].mean(axis=(1, 2)).astype(float))


def dome_observation(apex=(350, 220), radius_px=100, height=0.6, dome=0.05, curvature=1e-6) -> Observation:
    """Synthetic view straight down at a table (depth `height`) with a dome-shaped object whose
    nearest point is at pixel `apex`: depth = height - dome + curvature x (pixels from apex)^2."""
    pose = np.eye(4)
    pose[:3, :3] = np.diag([1.0, -1.0, -1.0])  # optical axis straight down
    pose[2, 3] = height
    v, u = np.mgrid[: PRIMESENSE.height, : PRIMESENSE.width]
    rho2 = (u - apex[0]) ** 2 + (v - apex[1]) ** 2
    depth = np.where(rho2 <= radius_px**2, height - dome + curvature * rho2, height).astype(np.float32)
    return Observation(depth, PRIMESENSE, pose)


# --------------------------------------------------------------------------------------------------
# Observation and geometry
# --------------------------------------------------------------------------------------------------


def test_observation_validation():
    pose = np.eye(4)
    with pytest.raises(InputError, match="shape"):
        Observation(np.zeros((10, 10), np.float32), PRIMESENSE, pose)
    with pytest.raises(InputError, match="camera_pose"):
        Observation(np.zeros((480, 640), np.float32), PRIMESENSE, np.eye(3))
    with pytest.raises(InputError, match="mask"):
        Observation(np.zeros((480, 640), np.float32), PRIMESENSE, pose, mask=np.ones((4, 4), bool))
    with pytest.raises(InputError, match="non-negative"):
        Observation(np.full((480, 640), -1.0, np.float32), PRIMESENSE, pose)


def test_normals_of_a_tilted_plane_face_the_camera():
    """Plane z = 0.6 + 0.3 x in the camera frame: normal (-0.3, 0, 1) up to sign, turned to the camera."""
    v, u = np.mgrid[:48, :64].astype(float)
    x_over_z = (u - 31.5) / 525.0
    depth = 0.6 / (1.0 - 0.3 * x_over_z)  # z = 0.6 + 0.3 x with x = z (u - cx) / fx
    points = np.stack([x_over_z * depth, (v - 23.5) / 525.0 * depth, depth], axis=-1)
    normals, ok = surface_normals(points, depth > 0)
    expected = np.array([0.3, 0.0, -1.0]) / math.hypot(0.3, 1.0)
    assert ok.all()
    np.testing.assert_allclose(normals.reshape(-1, 3), np.broadcast_to(expected, (48 * 64, 3)), atol=1e-9)


def test_segmentation_without_mask_matches_the_object(scenes):
    for scene in scenes.values():
        cloud = scene_cloud(scene.observation(), SamplerConfig())
        height = cloud.points @ scene.camera_pose[2, :3] + scene.camera_pose[2, 3]
        assert not (cloud.object_mask & ~scene.mask).any()
        assert not (scene.mask & ~cloud.object_mask & (height > 0.005 + 1e-6)).any()  # only the 5 mm near the table
        assert (cloud.object_mask != scene.mask).sum() < 0.02 * scene.mask.sum()
        assert cloud.valid.any() and not cloud.relaxed
        assert not (cloud.valid & ~cloud.object_mask).any()


def test_cloud_in_the_object_box_is_the_whole_images_cloud(scenes):
    # The cloud is computed in the object's box; the whole-image arrays built from it on first use
    # must be what deprojecting and reading normals on the whole image gives: raw points everywhere,
    # the box's smoothed points and normals inside it, and every grasp pixel (and object pixel) in it.
    scene = scenes["basic/box_tea"]
    cloud = scene_cloud(scene.observation(), SamplerConfig())
    whole = PRIMESENSE.deproject(scene.depth)
    np.testing.assert_array_equal(cloud.points, whole)
    np.testing.assert_array_equal(cloud.points[cloud.box], cloud.box_points)
    np.testing.assert_array_equal(cloud.object_points, whole[cloud.object_mask])
    outside = np.ones(scene.depth.shape, bool)
    outside[cloud.box] = False
    assert not (outside & (cloud.valid | cloud.object_mask)).any()
    assert not cloud.approaches[outside].any() and np.array_equal(cloud.smooth_points[outside], whole[outside])
    rows, cols = np.nonzero(cloud.valid)
    rows, cols = np.append(rows[:50], 0), np.append(cols[:50], 0)  # and a table pixel outside the box
    pixels, points, approaches = cloud.grasps_at(rows, cols)
    np.testing.assert_array_equal(points, whole[rows, cols])
    np.testing.assert_array_equal(approaches, cloud.approaches[rows, cols])
    assert np.allclose(np.linalg.norm(approaches[:-1], axis=1), 1.0) and not approaches[-1].any()


def test_object_cut_by_the_image_border(scenes):
    # An object running off the bottom-right of the image (cropping there keeps cx, cy): the
    # normals' window around the object must stay inside the image (regression: a window past the
    # border crashed planning on typical objects near the frame's edge).
    scene = scenes["basic/box_tea"]
    rows, cols = np.nonzero(scene.mask)
    height, width = int(rows.max()) - 5, int(cols.max()) - 5
    intrinsics = dataclasses.replace(PRIMESENSE, width=width, height=height)
    mask = scene.mask[:height, :width]
    observation = Observation(scene.depth[:height, :width], intrinsics, scene.camera_pose, mask=mask)
    cloud = scene_cloud(observation, SamplerConfig())
    assert (cloud.object_mask == mask).all() and cloud.valid.any()
    action = make_policy("planarity-centroid").plan(observation, np.random.default_rng(0))
    assert mask[int(round(action.pixel[1])), int(round(action.pixel[0]))]


def test_empty_scene_raises_no_grasp():
    depth = np.full((480, 640), 0.6, np.float32)
    pose = np.eye(4)
    pose[:3, :3] = np.diag([1.0, -1.0, -1.0])
    pose[2, 3] = 0.6
    with pytest.raises(NoGraspError):
        make_policy("centroid").plan(Observation(depth, PRIMESENSE, pose), np.random.default_rng(0))


# --------------------------------------------------------------------------------------------------
# Heuristics on rendered scenes
# --------------------------------------------------------------------------------------------------


def check_grasp_on_object(action: GraspAction, scene: Scene, cloud_valid: np.ndarray | None = None) -> None:
    u, v = action.pixel.astype(int)
    assert np.array_equal(action.pixel, np.rint(action.pixel))
    assert scene.mask[v, u], "grasp pixel off the object"
    assert action.depth == pytest.approx(float(scene.depth[v, u]), abs=1e-6), "grasp point is not the surface"
    np.testing.assert_allclose(PRIMESENSE.project(action.point), action.pixel, atol=1e-6)
    assert action.point_world[2] > 0.005, "grasp point not above the table"
    assert np.linalg.norm(action.approach) == pytest.approx(1.0, abs=1e-9)
    cone = SamplerConfig().max_optical_axis_angle
    assert action.approach[2] >= math.cos(cone) - 1e-9, "approach not within the seed cone of the optical axis"
    assert action.approach_world[2] < 0.0, "approach must point down into the object"
    if cloud_valid is not None:
        assert cloud_valid[v, u]


@pytest.mark.parametrize("name", HEURISTICS)
def test_heuristics_grasp_the_object(scenes, name):
    policy = make_policy(name)
    assert isinstance(policy, Policy) and policy.name == name
    for scene in scenes.values():
        action = policy.plan(scene.observation(), np.random.default_rng(11))
        check_grasp_on_object(action, scene)
        count = 1 if name == "random" else 250
        assert action.candidates["pixels"].shape == (count, 2) and action.candidates["q"].shape == (count,)
        if name == "random":
            assert math.isnan(action.q)
        else:
            q = action.candidates["q"]
            assert ((q >= 0) & (q <= 1)).all() and action.q == q.max()


def box_top(scene: Scene):
    """Top-face centre (world) of the box in its stable pose, and its short horizontal half-axis."""
    rotation = scene.pose[:3, :3]
    extents = np.asarray(scene.record.extents)
    horizontal = [i for i in range(3) if abs(rotation[2, i]) < 1e-6]
    vertical = next(i for i in range(3) if i not in horizontal)
    short = min(horizontal, key=lambda i: extents[i])
    centre = scene.pose[:3, :3] @ np.asarray(scene.record.com) + scene.pose[:3, 3]
    top = np.array([centre[0], centre[1], extents[vertical]])
    return top, rotation[:, short] * extents[short] / 2


def test_centroid_picks_the_box_top_above_the_centroid(scenes):
    scene = scenes["basic/box_tea"]
    top, _ = box_top(scene)
    action = make_policy("centroid").plan(scene.observation(), np.random.default_rng(3))
    assert action.point_world[2] == pytest.approx(top[2], abs=1e-3)
    assert np.linalg.norm(action.point_world[:2] - top[:2]) < 0.01
    assert action.approach_world[2] < -math.cos(math.radians(2.0))


def test_planarity_prefers_the_flat_top_over_an_edge(scenes):
    scene = scenes["basic/box_tea"]
    cloud = scene_cloud(scene.observation(), SamplerConfig())
    top, half_side = box_top(scene)
    near_edge = top + half_side * (1.0 - 0.002 / np.linalg.norm(half_side))  # 2 mm inside the top's long edge
    pixels = np.rint(np.array([scene.pixel_of(top), scene.pixel_of(near_edge), scene.pixel_of(top - 0.5 * half_side)]))
    rows, cols = pixels[:, 1].astype(int), pixels[:, 0].astype(int)
    assert scene.mask[rows, cols].all()
    sse, count = disc_errors(cloud, rows, cols, cloud.approaches[rows, cols], CUP_DEFAULT.radius)
    assert (count > 50).all()
    assert sse[0] < 1e-9 and sse[2] < 1e-9 and sse[1] > 1e3 * max(sse[0], sse[2])
    # The policy's grasp lies on the top, at least a cup radius (less a pixel) from its long edges.
    for name in ("planarity", "planarity-centroid"):
        action = make_policy(name).plan(scene.observation(), np.random.default_rng(5))
        assert action.point_world[2] == pytest.approx(top[2], abs=1e-3)
        across = abs((action.point_world - top) @ half_side) / np.linalg.norm(half_side)
        assert across <= np.linalg.norm(half_side) - CUP_DEFAULT.radius + 0.0012
    pc = make_policy("planarity-centroid").plan(scene.observation(), np.random.default_rng(5))
    assert pc.candidates["planar"][pc.info["chosen"]] and pc.q > 0.5
    assert np.linalg.norm(pc.point_world[:2] - top[:2]) < 0.015


def test_planarity_centroid_with_sensor_noise(scenes):
    """With the simulated sensor's per-pixel noise a flat box top still counts as planar."""
    scene = scenes["basic/box_tea"]
    noisy = apply_axial_noise(scene.depth, np.random.default_rng(0))
    observation = Observation(noisy, PRIMESENSE, scene.camera_pose, mask=scene.mask)
    action = make_policy("planarity-centroid").plan(observation, np.random.default_rng(1))
    top, _ = box_top(scene)
    assert action.candidates["planar"].mean() > 0.6 and action.q > 0.5
    assert np.linalg.norm(action.point_world[:2] - top[:2]) < 0.015
    assert action.point_world[2] == pytest.approx(top[2], abs=0.005)


def test_planarity_centroid_falls_back_to_planarity(scenes):
    scene = scenes["adversarial/narrow_gear"]
    strict = make_policy("planarity-centroid", max_planar_rms=1e-9)
    action = strict.plan(scene.observation(), np.random.default_rng(4))
    planarity = make_policy("planarity").plan(scene.observation(), np.random.default_rng(4))
    assert not action.candidates["planar"].any() and action.q < 0.5
    np.testing.assert_array_equal(action.pixel, planarity.pixel)


def test_mask_restricts_the_grasps(scenes):
    scene = scenes["typical/mug_classic"]
    columns = np.flatnonzero(scene.mask.any(axis=0))
    left = scene.mask.copy()
    left[:, (columns[0] + columns[-1]) // 2:] = False
    for name in HEURISTICS:
        action = make_policy(name).plan(scene.observation(mask=left), np.random.default_rng(2))
        assert left[int(action.pixel[1]), int(action.pixel[0])]


# --------------------------------------------------------------------------------------------------
# GQ-CNN cross-entropy policy
# --------------------------------------------------------------------------------------------------


def test_fit_gmm_recovers_two_clusters():
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.normal([-3.0, 0.0], 0.3, (200, 2)), rng.normal([3.0, 1.0], 0.3, (100, 2))])
    gmm = fit_gmm(x, 2, np.random.default_rng(1), reg_covar=1e-3)
    order = np.argsort(gmm.means[:, 0])
    np.testing.assert_allclose(gmm.means[order], [[-3.0, 0.0], [3.0, 1.0]], atol=0.1)
    np.testing.assert_allclose(gmm.weights[order], [2 / 3, 1 / 3], atol=0.02)
    samples = gmm.sample(3000, np.random.default_rng(2))
    assert abs((samples[:, 0] < 0).mean() - 2 / 3) < 0.03
    again = fit_gmm(x, 2, np.random.default_rng(1), reg_covar=1e-3)
    np.testing.assert_array_equal(gmm.means, again.means)


def test_cem_config_counts():
    cfg = CEMConfig()
    assert (cfg.num_seed_samples, cfg.num_iters, cfg.num_gmm_samples) == (250, 3, 50)
    assert cfg.elite_count(250) == 63 and cfg.component_count(63) == 26
    assert cfg.elite_count(50) == 13 and cfg.component_count(13) == 6
    with pytest.raises(InputError):
        CEMConfig(elite_fraction=0.0)


def test_cem_climbs_to_the_stub_optimum():
    """On a dome whose nearest point the stub likes best, CEM ends nearer the optimum than its seeds.
    Over 10 plans the best of the 250 uniform seeds lies a median 3.2 px from the apex and the
    plan's grasp 2.1 px (8 of 10 plans improve; the mixture resamples around the elites, so the
    paper's 3 rounds of 50 refine locally rather than jump to the optimum)."""
    apex = np.array([350.0, 220.0])
    observation = dome_observation(apex=tuple(apex))
    seed_best, final_best, distance = [], [], []
    for seed in range(10):
        stub = CentreDepthStub(z_best=0.55, scale=2e-5)
        action = GQCNNPolicy(stub).plan(observation, np.random.default_rng(seed))
        iteration, q = action.candidates["iteration"], action.candidates["q"]
        assert len(action.info["round_best_q"]) == 4 and action.info["evaluations"] == 250 + 3 * 50
        assert [len(images) for images, _ in stub.calls] == [250, 50, 50, 50]
        assert action.q == q.max() >= q[iteration == 0].max()
        seed_best.append(q[iteration == 0].max())
        final_best.append(action.q)
        distance.append(np.linalg.norm(action.pixel - apex))
        # Later rounds concentrate around the optimum.
        pixels = action.candidates["pixels"]
        spread_seeds = np.median(np.linalg.norm(pixels[iteration == 0] - apex, axis=1))
        spread_last = np.median(np.linalg.norm(pixels[iteration == 3] - apex, axis=1))
        assert spread_last < 0.3 * spread_seeds
    assert np.median(distance) <= 3.0, distance
    assert np.mean(final_best) > np.mean(seed_best) + 0.1, (seed_best, final_best)
    assert sum(f > s for f, s in zip(final_best, seed_best, strict=True)) >= 7
    # Pose vectors: depth of the grasp, approach angle ~0 at the apex seen straight down.
    poses = action.candidates["poses"]
    np.testing.assert_allclose(poses[:, 0], action.candidates["points"][:, 2], atol=1e-6)
    assert poses[action.info["chosen"], 1] < math.radians(2.0)
    assert np.all(poses[:, 1] <= SamplerConfig().max_optical_axis_angle + 1e-6)


def test_cem_on_rendered_scenes(scenes):
    for key, scene in scenes.items():
        stub = CentreDepthStub(z_best=0.3, scale=0.01)
        policy = make_policy("gqcnn", model=stub)
        action = policy.plan(scene.observation(), np.random.default_rng(9))
        check_grasp_on_object(action, scene)
        assert action.q == pytest.approx(action.candidates["q"].max()) and action.policy == "gqcnn", key
        images, poses = stub.calls[0]
        assert len(images) == 250
        # the thumbnail centre is the grasp pixel's depth (a flat 3 px neighbourhood on most grasps)
        centre = images[:, 15:17, 15:17].mean(axis=(1, 2))
        assert np.median(np.abs(centre - poses[:, 0])) < 1e-3


def test_cem_feeds_a_two_channel_model_the_grasp_and_context_thumbnails():
    observation = dome_observation()
    stub = ContextStub()
    action = GQCNNPolicy(stub, num_seed_samples=40, num_gmm_samples=10, num_iters=1).plan(
        observation, np.random.default_rng(0))
    assert [len(images) for images, _ in stub.calls] == [40, 10]
    images = np.concatenate([images for images, _ in stub.calls])
    c = action.candidates
    _, _, angles = project_grasps(c["points"], c["approaches"], PRIMESENSE)
    np.testing.assert_array_equal(images[:, 0], extract_thumbnails(observation.depth, c["pixels"], angles))
    np.testing.assert_array_equal(images[:, 1], extract_context_thumbnails(observation.depth, c["pixels"], angles))
    assert not np.allclose(images[:, 0], images[:, 1], atol=1e-3)


@pytest.mark.parametrize("thumbnail", [ThumbnailConfig(sampling="mean"), ThumbnailConfig(crop_size=64)],
                         ids=["block-means", "crop-64"])
def test_cem_plans_with_a_trained_format_context_model(tmp_path, thumbnail):
    """A `context` network saved and loaded as a model directory (lazily, as `make_policy` does) plans
    a grasp on the object; its q is the network's for the two thumbnails of that grasp, the grasp
    thumbnail cut as its card says its dataset was (block means or a 64 px crop, not gqcnn's 96 px
    of point samples)."""
    import torch

    from suctionbench.learning.checkpoint import GQCNNModel, load_model, save_model
    from suctionbench.learning.data import NormStats
    from suctionbench.learning.models import build_model

    stats = NormStats((0.57, 0.59), (0.02, 0.01), (0.57, 0.2), (0.02, 0.1), count=1)
    save_model(tmp_path, GQCNNModel(build_model("context", torch.Generator().manual_seed(0)), stats,
                                    {"arch": "context", "dataset": {"thumbnail": to_dict(thumbnail)}}))
    assert load_model(tmp_path).thumbnail == thumbnail
    policy = make_policy("gqcnn", model=tmp_path, num_seed_samples=30, num_gmm_samples=10, num_iters=1)
    observation = dome_observation()
    action = policy.plan(observation, np.random.default_rng(1))
    assert action.info["evaluations"] == 40 and 0.0 <= action.q <= 1.0
    assert action.q == action.candidates["q"].max()
    u, v = np.round(action.pixel).astype(int)
    assert observation.depth[v, u] < 0.6 - 0.01  # on the dome, not the table
    best = action.info["chosen"]
    pixels, points, approaches = (action.candidates[k][best:best + 1] for k in ("pixels", "points", "approaches"))
    _, _, angles = project_grasps(points, approaches, PRIMESENSE)
    both = np.stack([sample_thumbnails(observation.depth, pixels, angles, thumbnail),
                     extract_context_thumbnails(observation.depth, pixels, angles)], axis=1)
    q = load_model(tmp_path).predict(both, action.candidates["poses"][best:best + 1])
    assert float(q[0]) == pytest.approx(action.q, rel=1e-6)
    points = np.stack([extract_thumbnails(observation.depth, pixels, angles), both[:, 1]], axis=1)
    assert float(load_model(tmp_path).predict(points, action.candidates["poses"][best:best + 1])[0]) != action.q


def slope_observation(slope_deg: float, height: float = 0.6) -> Observation:
    """Straight-down view of a table (depth `height`) with an 80 x 80 px patch of plane whose normal
    is `slope_deg` from the optical axis, turned about the camera's y axis: z = z0 + tan(s) x, i.e.
    at pixel u the depth z0 / (1 - tan(s) (u - cx) / fx)."""
    pose = np.eye(4)
    pose[:3, :3] = np.diag([1.0, -1.0, -1.0])
    pose[2, 3] = height
    v, u = np.mgrid[: PRIMESENSE.height, : PRIMESENSE.width]
    patch = (abs(u - PRIMESENSE.cx) < 40) & (abs(v - PRIMESENSE.cy) < 40)
    plane = 0.5 / (1.0 - math.tan(math.radians(slope_deg)) * (u - PRIMESENSE.cx) / PRIMESENSE.fx)
    return Observation(np.where(patch, plane, height).astype(np.float32), PRIMESENSE, pose)


@pytest.mark.parametrize("name", ["planarity-centroid", "gqcnn"])
def test_a_table_option_sets_the_seed_cone(name):
    # A face 45 deg from the optical axis lies inside the default 60 deg seed cone: its pixels are
    # valid and the candidates approach ~45 deg from the optical axis (the normal of a plane, but
    # for the smoothing at the patch's rim). `sampler={...}` (a --policy-arg table) sets gqcnn's
    # sampler, a 30 deg cone and 1 px normals, and keeps the sampler's other defaults: no pixel is
    # valid and the sampler drops its angle limits (relaxed). (With the default normals, smoothed
    # over the cup's footprint, the pixels within ~10 px of the patch's 10 cm step blend the step
    # into their normals and a few of them fall inside 30 deg.)
    kwargs = {"model": CentreDepthStub(z_best=0.5, scale=0.01)} if name == "gqcnn" else {}
    observation = slope_observation(45.0)
    assert SamplerConfig().max_optical_axis_angle == pytest.approx(math.radians(60))
    gqcnn_sampler = {"max_optical_axis_angle": math.radians(30), "normal_sigma": 0.0}
    narrow_policy = make_policy(name, sampler=gqcnn_sampler, **kwargs)
    assert narrow_policy.config.sampler == SamplerConfig(**gqcnn_sampler)
    narrow = narrow_policy.plan(observation, np.random.default_rng(0))
    wide = make_policy(name, **kwargs).plan(observation, np.random.default_rng(0))
    assert narrow.info["relaxed"] and not wide.info["relaxed"]
    tilt = np.degrees(np.arccos(np.abs(wide.candidates["approaches"][:, 2])))
    assert np.median(np.abs(tilt - 45.0)) < 1.0
    with pytest.raises(InputError, match="cone"):
        make_policy(name, sampler={"cone": 1.0}, **kwargs)
    with pytest.raises(InputError, match="thumbnail: takes no table"):  # a trained model reads its own cut
        make_policy(name, thumbnail={"crop_size": 64}, **kwargs)


# --------------------------------------------------------------------------------------------------
# Determinism and registry
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", [*HEURISTICS, "gqcnn"])
def test_policies_are_deterministic(scenes, name):
    scene = scenes["typical/mug_classic"]
    kwargs = {"model": CentreDepthStub(z_best=0.3, scale=0.01)} if name == "gqcnn" else {}
    policy = make_policy(name, **kwargs)
    first = policy.plan(scene.observation(), np.random.default_rng(21))
    second = policy.plan(scene.observation(), np.random.default_rng(21))
    other = policy.plan(scene.observation(), np.random.default_rng(22))
    np.testing.assert_array_equal(first.point, second.point)
    np.testing.assert_array_equal(first.approach, second.approach)
    assert first.q == second.q or (math.isnan(first.q) and math.isnan(second.q))
    assert first.candidates.keys() == second.candidates.keys()
    for key in first.candidates:
        np.testing.assert_array_equal(first.candidates[key], second.candidates[key])
    assert not np.array_equal(first.candidates["pixels"], other.candidates["pixels"])


def test_registry_and_errors(tmp_path, monkeypatch):
    assert set(POLICIES) >= {*HEURISTICS, "gqcnn"}
    with pytest.raises(InputError, match="unknown"):
        make_policy("grasp-anything")
    with pytest.raises(InputError, match="bad options"):
        make_policy("centroid", nonsense=1)
    assert make_policy(" Planarity-Centroid ").name == "planarity-centroid"
    assert make_policy("centroid", num_candidates=10).config.num_candidates == 10
    monkeypatch.setattr(gqcnn, "default_model_dir", lambda: tmp_path / "no-model")
    with pytest.raises(InputError, match="default model"):
        make_policy("gqcnn")
    with pytest.raises(InputError, match="does not exist"):
        make_policy("gqcnn", model=tmp_path / "missing")
    with pytest.raises(InputError, match="predict"):
        make_policy("gqcnn", model=object())
    model_dir = tmp_path / "model"
    model_dir.mkdir()
    lazy = make_policy("gqcnn-cem", model=model_dir)  # loads nothing until the first plan
    assert isinstance(lazy, GQCNNPolicy) and lazy.model.path == model_dir


def test_normals_average_the_cup_footprint():
    # A flat face 0.6 m in front of the PrimeSense (f = 525 px; a pixel spans p = 0.6 / 525 =
    # 1.143 mm) under its axial noise, sigma_n = 1.2 + 1.9 (0.6 - 0.4)^2 = 1.276 mm per pixel, iid.
    # Gaussian smoothing of width s px then differentiation leaves a slope noise per image axis of
    # sigma_n / (sqrt(8 pi) s^2 p) (the L2 norm of a 2-D Gaussian's derivative is
    # 1 / (sqrt(8 pi) s^2)). The footprint smooths by half the lip radius on the surface, 3.75 mm =
    # 3.28 px: 0.0207 rad per axis, and the angle of an isotropic 2-D Gaussian error has the Rayleigh
    # median sqrt(2 ln 2) x that: 1.40 deg. gqcnn's 1 px smoothing (`normal_sigma = 0`, the default) leaves
    # ~10x more (s^2 = 10.8 times; the continuous formula's 14.8 deg is an upper bound for the
    # discrete 1 px kernel).
    from suctionbench.policies.base import FOOTPRINT_NORMAL_SIGMA, normal_sigma_pixels

    height, width = PRIMESENSE.height, PRIMESENSE.width
    depth = np.full((height, width), 0.6, dtype=np.float32)
    mask = np.zeros((height, width), dtype=bool)
    mask[140:340, 220:420] = True
    pose = np.eye(4)
    pose[:3, :3] = np.diag([1.0, -1.0, -1.0])
    pose[2, 3] = 0.6
    config = SamplerConfig(normal_sigma=FOOTPRINT_NORMAL_SIGMA)
    assert math.isclose(FOOTPRINT_NORMAL_SIGMA, 3.75e-3)
    assert normal_sigma_pixels(config, PRIMESENSE, depth[mask]) == pytest.approx(3.75e-3 * 525 / 0.6, rel=0.02)

    def median_error(cfg: SamplerConfig) -> float:
        errors = []
        for seed in range(3):
            noisy = apply_axial_noise(depth, np.random.default_rng(seed))
            cloud = scene_cloud(Observation(noisy, PRIMESENSE, pose, mask=mask), cfg)
            approach = cloud.approaches[180:300, 260:380].reshape(-1, 3)  # away from the face's rim
            errors.append(np.degrees(np.arccos(np.clip(approach[:, 2], -1.0, 1.0))))
        return float(np.median(np.concatenate(errors)))

    footprint = median_error(config)
    one_pixel = median_error(SamplerConfig())
    assert footprint == pytest.approx(1.40, rel=0.15)
    assert 6.0 * footprint < one_pixel < 14.8
