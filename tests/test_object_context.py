"""The pose stream's object context (suctionbench.sensing.object_context) on point sets whose
answers follow from their geometry."""

from __future__ import annotations

import math

import numpy as np
import pytest

from suctionbench.sensing.object_context import OBJECT_CONTEXT_COLUMNS, object_context


def plank_top(length: float = 0.3, width: float = 0.05, height: float = 0.02, yaw: float = 0.0) -> np.ndarray:
    """The top face of a plank lying on the table (a dense grid of points), turned by `yaw`."""
    u, v = np.meshgrid(np.linspace(-length / 2, length / 2, 301), np.linspace(-width / 2, width / 2, 51))
    c, s = math.cos(yaw), math.sin(yaw)
    return np.column_stack([c * u.ravel() - s * v.ravel(), s * u.ravel() + c * v.ravel(), np.full(u.size, height)])


@pytest.mark.parametrize("yaw", [0.0, 0.7])
def test_a_plank_gripped_off_centre(yaw):
    # A 30 x 5 cm plank's top at 2 cm, gripped 10 cm from its centre along its length, straight
    # down: offset 0.1 m, nothing along a vertical approach, the grasp at the centroid's height;
    # extents 30 and 5 cm less the 1-99 % percentiles' trim: 1 % of the length at each end of the
    # 301 columns' uniform spread (0.98 x 30 = 29.4 cm); none across, where each of the 51 edge
    # rows holds 2 % of the points, so the percentiles land on the edges (5 cm); top 2 cm.
    points = plank_top(yaw=yaw)
    grasp = np.array([[0.1 * math.cos(yaw), 0.1 * math.sin(yaw), 0.02]])
    ctx = object_context(points, grasp, np.array([[0.0, 0.0, -1.0]]))[0]
    expected = dict(zip(OBJECT_CONTEXT_COLUMNS, [0.1, 0.0, 0.0, 0.294, 0.05, 0.02], strict=True))
    for name, value in zip(OBJECT_CONTEXT_COLUMNS, ctx, strict=True):
        assert value == pytest.approx(expected[name], abs=1e-3), name


def test_offset_along_the_approachs_lean():
    # The same grasp approached leaning 30 deg towards the plank's centre (-x): the centroid lies
    # 0.1 m ahead of the lean, weighted by sin 30 = 0.5: 0.05 m; leaning away, -0.05 m; leaning
    # across, beside (0).
    points, grasp = plank_top(), np.array([[0.1, 0.0, 0.02]])
    s, c = math.sin(math.radians(30)), math.cos(math.radians(30))
    leans = np.array([[-s, 0.0, -c], [s, 0.0, -c], [0.0, s, -c]])
    along = object_context(points, np.repeat(grasp, 3, axis=0), leans)[:, 1]
    np.testing.assert_allclose(along, [0.05, -0.05, 0.0], atol=1e-9)


def test_offset_along_is_continuous_through_a_vertical_approach():
    # A mesh normal on a flat top is exactly vertical; a normal estimated from a noisy depth image
    # is a fraction of a degree off, in any direction. The feature must not tell them apart: at
    # 0.5 deg off vertical towards or away from the centroid it is 0.1 m x sin(0.5 deg) = 0.87 mm.
    points, grasp = plank_top(), np.array([[0.1, 0.0, 0.02]])
    t = math.radians(0.5)
    approaches = np.array([[0.0, 0.0, -1.0], [-math.sin(t), 0.0, -math.cos(t)], [math.sin(t), 0.0, -math.cos(t)]])
    along = object_context(points, np.repeat(grasp, 3, axis=0), approaches)[:, 1]
    np.testing.assert_allclose(along, [0.0, 0.1 * math.sin(t), -0.1 * math.sin(t)], atol=1e-9)


def test_no_object_seen_gives_zeros():
    assert not object_context(np.zeros((0, 3)), np.zeros((2, 3)), np.tile([0.0, 0.0, -1.0], (2, 1))).any()


def test_the_generator_computes_what_the_policy_sees():
    # A 12 x 8 cm box, 3 cm tall, seen straight down from 0.6 m, in an image whose depth scale is
    # 3 % off (the noise model's Gamma factor: one such error per image). The dataset generator
    # (dataset.generate.image_object_context) and the GQ-CNN policies (policies.gqcnn.network_poses)
    # must give the network the same numbers for the same grasps on that image: a grasp point taken
    # from the mesh while the object's points come from the noisy image would be 3 % x 0.57 m =
    # 1.7 cm off in its rise.
    from types import SimpleNamespace

    from suctionbench.dataset.generate import image_object_context
    from suctionbench.policies.base import Observation, SamplerConfig, scene_cloud
    from suctionbench.policies.gqcnn import network_poses
    from suctionbench.sensing.camera import resolve_camera

    camera = resolve_camera("primesense")
    pose = np.eye(4)
    pose[:3, :3] = np.diag([1.0, -1.0, -1.0])  # optical axis straight down
    pose[2, 3] = 0.6
    rows, cols = np.mgrid[0:camera.height, 0:camera.width]
    x = (cols - camera.cx) * 0.6 / camera.fx
    y = -(rows - camera.cy) * 0.6 / camera.fy
    box = (np.abs(x - 0.02) < 0.06) & (np.abs(y + 0.01) < 0.04)
    depth = np.where(box, 0.57, 0.6).astype(np.float32)
    noisy = (depth * 1.03).astype(np.float32)
    pixels = np.array([[300.0, 240.0], [340.0, 250.0], [370.0, 220.0]])  # (u, v) on the box top
    assert box[pixels[:, 1].astype(int), pixels[:, 0].astype(int)].all()
    tilt = math.radians(3.0)
    approaches = np.array([[0.0, 0.0, -1.0], [math.sin(tilt), 0.0, -math.cos(tilt)], [0.0, -math.sin(tilt),
                                                                                       -math.cos(tilt)]])
    exact = (camera.deproject(depth) @ pose[:3, :3].T + pose[:3, 3])[pixels[:, 1].astype(int), pixels[:, 0].astype(int)]
    generated = image_object_context(camera, depth, noisy, pose, pixels, exact, approaches)

    observation = Observation(noisy, camera, pose, mask=box)
    cloud = scene_cloud(observation, SamplerConfig())
    _, points, _ = cloud.grasps_at(pixels[:, 1], pixels[:, 0])
    model = SimpleNamespace(pose_dim=8)
    planned = network_poses(model, observation, cloud, points[:, 2], points, approaches @ pose[:3, :3], 0.0)[:, 2:]
    np.testing.assert_allclose(generated, planned, atol=1e-6)
    assert np.all(np.abs(generated[:, 2]) < 1e-6)  # the box top's grasps at the visible centroid's height
