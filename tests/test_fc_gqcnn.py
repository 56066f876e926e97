"""The dense suction policy (policies/fc_gqcnn.py) with the shipped GQ-CNN."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import torch
from scipy import ndimage
from test_policies import OBJECTS, Scene

from suctionbench.learning.checkpoint import load_model
from suctionbench.policies.base import make_policy, scene_cloud
from suctionbench.policies.fc_gqcnn import lattice_positions
from suctionbench.policies.gqcnn import default_model_dir
from suctionbench.sensing.thumbnails import THUMBNAIL_GQCNN, extract_thumbnails, project_grasps

MODEL_DIR = default_model_dir()


def test_lattice_window_is_the_thumbnail_of_its_centre():
    # A window of the turned lattice is, sample for sample, the thumbnail extract_thumbnails cuts
    # at the window's centre and the lattice's angle, so the dense q there is the network's q.
    rng = np.random.default_rng(0)
    depth = (0.6 + 0.05 * rng.random((120, 140))).astype(np.float32)
    pixels = np.array([[60.0, 50.0], [75.0, 66.0], [52.0, 71.0]])
    angle, config = 2 * math.pi * 5 / 16, THUMBNAIL_GQCNN
    points, windows = lattice_positions(pixels, angle, config)
    lattice = ndimage.map_coordinates(depth, [points[..., 1], points[..., 0]], order=1, mode="nearest")
    for (a0, b0), pixel in zip(windows, pixels, strict=True):
        centre = _window_centre(points, a0, b0, angle)
        # the window nearest the pixel is centred within half the lattice's diagonal of it
        assert np.linalg.norm(centre - pixel) <= 3.0 * math.sqrt(2) / 2 + 1e-9
        want = extract_thumbnails(depth, centre[None], np.array([angle]))[0]
        np.testing.assert_allclose(lattice[a0:a0 + 32, b0:b0 + 32], want, rtol=0, atol=1e-6)


def _window_centre(points: np.ndarray, a0: int, b0: int, angle: float, pitch: float = 3.0) -> np.ndarray:
    """Image (u, v) of the centre of lattice window (a0, b0): its top-left sample plus 15.5 pitches
    along the thumbnail's row and column axes (an independent reading of the geometry)."""
    return points[a0, b0] + pitch * 15.5 * (np.array([math.cos(angle), math.sin(angle)])
                                            + np.array([math.sin(angle), -math.cos(angle)]))


def _dense_windows(model, configs, count: int, seed: int, strides=None):
    """fc-gqcnn's dense map (refine 0) on box_tea; `count` random pixels of it, their bins' angles
    and, per thumbnail config, the image centre of each pixel's lattice window (read independently
    through `_window_centre`; windows `strides` lattice steps apart, 1 each by default)."""
    policy = make_policy("fc-gqcnn", model=model, refine=0)
    scene = Scene("basic/box_tea")
    observation = scene.observation(mask=scene.mask)
    cloud = scene_cloud(observation, policy.config.sampler)
    dense = policy.quality(observation, cloud)
    _, _, angles = project_grasps(dense["points"], dense["approaches"], cloud.intrinsics)
    step = 2 * math.pi / policy.config.rotations
    bins = np.mod(np.rint(angles / step).astype(int), policy.config.rotations)
    pick = np.random.default_rng(seed).choice(len(bins), size=count, replace=False)
    centres = [[] for _ in configs]
    for i in pick:
        mine = np.flatnonzero(bins == bins[i])
        for config, stride, found in zip(configs, strides or [1] * len(configs), centres, strict=True):
            points, windows = lattice_positions(dense["pixels"][mine], bins[i] * step, config, stride)
            assert not (windows % stride).any()
            a0, b0 = windows[np.searchsorted(mine, i)]
            found.append(_window_centre(points, a0, b0, bins[i] * step, pitch=1 / config.scale))
    return policy, observation, dense, pick, bins[pick] * step, [np.array(c) for c in centres]


def test_dense_q_is_the_network_on_each_pixels_window():
    # refine 0: the dense map itself. At every valid pixel its q is the thumbnail network's q on
    # the thumbnail centred on the pixel's lattice window, at its bin's angle, with the pixel's own
    # pose: normalisation, pose rows, window indices and bins all checked together (a one-stream net).
    from suctionbench.learning.checkpoint import GQCNNModel
    from suctionbench.learning.data import NormStats
    from suctionbench.learning.models import build_model

    stats = NormStats(0.58, 0.1, (0.57, 0.2), (0.1, 1.0), count=1)  # wide: random weights stay unsaturated
    model = GQCNNModel(build_model("compact", torch.Generator().manual_seed(3)), stats, {"arch": "compact"})
    policy, observation, dense, pick, turn, [centres] = _dense_windows(model, [THUMBNAIL_GQCNN], 60, 0)
    thumbnails = extract_thumbnails(observation.depth, centres, turn)
    want = model.predict(thumbnails, dense["poses"][pick])
    assert want.std() > 1e-3  # the check can tell positions apart
    np.testing.assert_allclose(dense["q"][pick], want, rtol=0, atol=1e-5)
    action = policy.plan(observation, np.random.default_rng(0))
    assert action.q == pytest.approx(float(dense["q"].max()))


@pytest.mark.parametrize("change", [{"sampling": "point"}, {"sampling": "mean"}, {"crop_size": 64},
                                    {"crop_size": 48}], ids=["point", "mean", "crop-64", "crop-48"])
def test_dense_q_of_a_context_net_reads_both_lattices(change):
    # A two-stream (context) net: each pixel's dense q is the network's on the pair (grasp thumbnail
    # centred on its 3-px-lattice window, 2 px for a 64 px crop, context thumbnail centred on its
    # 9-px-lattice window of the box-filtered image), both at the bin's angle, with the pixel's own
    # pose; the grasp lattice reads the image as the model's dataset did (point samples, 3 x 3
    # block means, or a 64 px crop). A 48 px crop's lattice has a 1.5 px pitch, finer than the
    # policy's 3 px window pitch: every second window along each axis is scored (stride 2, windows
    # 3 px apart), so a pixel's window centre is at most 3 sqrt(2) / 2 px from it.
    from suctionbench.config import to_dict
    from suctionbench.learning.checkpoint import GQCNNModel
    from suctionbench.learning.data import NormStats
    from suctionbench.learning.models import build_model
    from suctionbench.sensing.thumbnails import THUMBNAIL_CONTEXT, extract_context_thumbnails, sample_thumbnails

    stats = NormStats((0.57, 0.59), (0.02, 0.01), (0.57, 0.2), (0.02, 0.1), count=1)
    thumbnail = dataclasses.replace(THUMBNAIL_GQCNN, **change)
    model = GQCNNModel(build_model("context", torch.Generator().manual_seed(2)), stats,
                       {"arch": "context", "dataset": {"thumbnail": to_dict(thumbnail)}})
    stride = 2 if thumbnail.crop_size == 48 else 1
    _, observation, dense, pick, turn, (grasp, context) = _dense_windows(
        model, [thumbnail, THUMBNAIL_CONTEXT], 40, 1, [stride, 1])
    off = np.linalg.norm(context - dense["pixels"][pick], axis=1)
    assert off.max() <= 9 * math.sqrt(2) / 2 + 1e-9  # half the context lattice's diagonal
    off = np.linalg.norm(grasp - dense["pixels"][pick], axis=1)
    assert off.max() <= stride * thumbnail.crop_size / 32 * math.sqrt(2) / 2 + 1e-9  # half the windows' diagonal
    pairs = np.stack([sample_thumbnails(observation.depth, grasp, turn, thumbnail),
                      extract_context_thumbnails(observation.depth, context, turn)], axis=1)
    want = model.predict(pairs, dense["poses"][pick])
    assert want.std() > 1e-3  # the check can tell positions apart
    np.testing.assert_allclose(dense["q"][pick], want, rtol=0, atol=1e-5)


@pytest.fixture(scope="module")
def policy():
    return make_policy("fc-gqcnn", model=str(MODEL_DIR))


def test_dense_plan_on_rendered_scenes(policy):
    exact = make_policy("gqcnn", model=load_model(MODEL_DIR))
    for key in OBJECTS:
        scene = Scene(key)
        action = policy.plan(scene.observation(mask=scene.mask), np.random.default_rng(0))
        u, v = np.round(action.pixel).astype(int)
        assert scene.mask[v, u], key  # on the object
        q_map = action.info["quality_map"]
        scored = np.isfinite(q_map)
        assert scored.sum() == action.info["evaluations"] == len(action.candidates["q"]) > 0
        assert np.all((q_map[scored] >= 0) & (q_map[scored] <= 1))
        assert not scored[~scene.mask].any()  # nothing off the object is scored
        # the reported q is the network's own for the executed grasp (its thumbnail, refined exactly)
        observation = scene.observation(mask=scene.mask)
        cloud = scene_cloud(observation, policy.config.sampler)
        own = exact.score(observation, cloud, np.array([v]), np.array([u]))["q"][0]
        assert action.q == pytest.approx(own, abs=1e-6)


def test_dense_policy_refuses_a_model_it_cannot_convert():
    from suctionbench.errors import InputError
    from suctionbench.learning.checkpoint import GQCNNModel
    from suctionbench.learning.data import NormStats
    from suctionbench.learning.models import build_model

    scene = Scene("basic/box_tea")
    observation = scene.observation(mask=scene.mask)
    stats = NormStats(0.6, 0.05, (0.6, 0.3), (0.05, 0.2))
    dn3 = GQCNNModel(build_model("dn3", torch.Generator().manual_seed(0)), stats, {"arch": "dn3"})
    with pytest.raises(InputError, match="dense GQ-CNN: only VALID"):
        make_policy("fc-gqcnn", model=dn3).plan(observation, np.random.default_rng(0))

    class Scores:  # a model that only predicts (a stub): nothing to make dense
        def predict(self, images, poses):
            return np.full(len(images), 0.5)

    with pytest.raises(InputError, match="no network to convert"):
        make_policy("fc-gqcnn", model=Scores()).plan(observation, np.random.default_rng(0))


def test_an_object_context_net_gets_each_grasps_context_from_both_policies():
    # A context-pose net reads 8 pose values: the 2 of every net, then where the grasp lies on the
    # object the cloud segments, in metres (object_context on the world-frame points). The dense
    # map's q at a pixel is the network's on that pixel's windows with that pose; the CEM policy
    # scores the same pose rows for the same pixels.
    from suctionbench.learning.checkpoint import GQCNNModel
    from suctionbench.learning.data import NormStats
    from suctionbench.learning.models import build_model
    from suctionbench.sensing.object_context import object_context
    from suctionbench.sensing.thumbnails import THUMBNAIL_CONTEXT, extract_context_thumbnails

    stats = NormStats((0.57, 0.59), (0.02, 0.01), (0.57, 0.2, 0.05, 0, 0, 0.1, 0.05, 0.05),
                      (0.02, 0.1, 0.03, 0.02, 0.02, 0.05, 0.02, 0.02), count=1)
    model = GQCNNModel(build_model("context-pose", torch.Generator().manual_seed(4)), stats, {"arch": "context-pose"})
    _, observation, dense, pick, turn, (grasp, context) = _dense_windows(
        model, [THUMBNAIL_GQCNN, THUMBNAIL_CONTEXT], 30, 2)
    cloud = scene_cloud(observation, make_policy("gqcnn", model=model).config.sampler)
    pose = observation.camera_pose
    world = cloud.object_points @ pose[:3, :3].T + pose[:3, 3]
    expected = object_context(world, dense["points"][pick] @ pose[:3, :3].T + pose[:3, 3],
                              dense["approaches"][pick] @ pose[:3, :3].T)
    assert dense["poses"].shape[1] == 8 and expected[:, 0].std() > 1e-3  # the offsets differ across the box
    np.testing.assert_allclose(dense["poses"][pick][:, 2:], expected, rtol=0, atol=1e-6)
    pairs = np.stack([extract_thumbnails(observation.depth, grasp, turn),
                      extract_context_thumbnails(observation.depth, context, turn)], axis=1)
    np.testing.assert_allclose(dense["q"][pick], model.predict(pairs, dense["poses"][pick]), rtol=0, atol=1e-5)
    cem = make_policy("gqcnn", model=model)
    rows, cols = dense["pixels"][pick, 1].astype(int), dense["pixels"][pick, 0].astype(int)
    scored = cem.score(observation, cloud, rows, cols)
    np.testing.assert_allclose(scored["poses"], dense["poses"][pick], rtol=0, atol=1e-6)


def test_window_pitch_sets_each_streams_stride():
    # Windows at least `window_pitch` image pixels apart: the largest power of 2 of the thumbnail's
    # pitch (crop / 32 px) not above it, capped by the stream's pools. 96 px crop: pitch 3 -> every
    # window; 48 px: 1.5 -> every 2nd (3 px apart); 24 px: 0.75 -> every 4th (3 px), or every 2nd
    # where the stream has only one pool (max stride 2); the 288 px context: 9 -> every window. The
    # bench's reference pitch lies under any pitch: every window.
    from suctionbench.bench import _EVERY_WINDOW
    from suctionbench.errors import InputError
    from suctionbench.policies.fc_gqcnn import DenseConfig, lattice_stride
    from suctionbench.sensing.thumbnails import THUMBNAIL_CONTEXT

    def crop(size):
        return dataclasses.replace(THUMBNAIL_GQCNN, crop_size=size)

    assert [lattice_stride(crop(c), 3.0, 4) for c in (96, 64, 48, 24)] == [1, 1, 2, 4]
    assert lattice_stride(crop(24), 3.0, 2) == 2
    assert lattice_stride(THUMBNAIL_CONTEXT, 3.0, 4) == 1
    assert lattice_stride(crop(24), _EVERY_WINDOW, 4) == 1
    with pytest.raises(InputError, match="window_pitch = 0 must be a number > 0"):
        DenseConfig(window_pitch=0)


def test_distinct_is_np_unique_with_inverse():
    from suctionbench.policies.fc_gqcnn import _distinct

    index = np.random.default_rng(3).integers(0, 500, 2000)
    values, inverse = _distinct(index, 500)
    want_values, want_inverse = np.unique(index, return_inverse=True)
    np.testing.assert_array_equal(values, want_values)
    np.testing.assert_array_equal(inverse, want_inverse)


def test_smoothed_ranking_prefers_a_good_region_to_a_lone_spike():
    # quality_sigma ranks a pixel by its Gaussian-weighted neighbourhood, no-grasp pixels (NaN) as
    # q = 0: a lone q = 1 among q = 0.1 pixels ranks under the middle of a 9 x 9 patch of q = 0.8
    # (its smoothed value ~0.1 + 0.9 / (2 pi sigma^2) = 0.14 at sigma 2, the patch's ~0.8 * 0.95),
    # and the patch's rim ranks under its middle; sigma 0 is the raw map.
    from suctionbench.errors import InputError
    from suctionbench.policies.fc_gqcnn import DenseConfig, ranking

    q_map = np.full((40, 60), 0.1, np.float32)
    q_map[:, 50:] = np.nan  # no grasps there
    q_map[10, 10] = 1.0
    q_map[16:25, 30:39] = 0.8
    rows, cols = np.array([10, 20, 20, 16]), np.array([10, 34, 30, 30])  # spike, middle, rim, corner
    raw = q_map[rows, cols]
    assert int(np.argmax(raw)) == 0
    smooth = ranking(q_map, rows, cols, 2.0)
    assert int(np.argmax(smooth)) == 1 and smooth[1] > smooth[2] > smooth[3]
    assert smooth[0] == pytest.approx(0.1 + 0.9 / (2 * math.pi * 4.0), abs=0.01)
    # next to the no-grasp region a uniform map ranks lower than far from it
    edge = ranking(np.where(np.isnan(q_map), np.nan, 0.5), np.array([20, 20]), np.array([49, 25]), 2.0)
    assert edge[0] < edge[1] == pytest.approx(0.5)
    with pytest.raises(InputError, match="quality_sigma = -1 must be in"):
        DenseConfig(quality_sigma=-1)
