"""The dense suction policy (policies/fc_gqcnn.py) with the shipped GQ-CNN."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch
from scipy import ndimage
from test_policies import OBJECTS, Scene

from suctionbench.learning.checkpoint import load_model
from suctionbench.learning.dense import DenseGQCNN
from suctionbench.policies.base import make_policy, scene_cloud
from suctionbench.policies.fc_gqcnn import lattice_positions
from suctionbench.resources import asset_path
from suctionbench.sensing.thumbnails import extract_thumbnails

MODEL_DIR = asset_path("models", "gqcnn-compact")


def test_lattice_window_is_the_thumbnail_of_its_centre():
    # A window of the turned lattice is, sample for sample, the thumbnail extract_thumbnails cuts
    # at the window's centre and the lattice's angle, so the dense q there is the network's q.
    rng = np.random.default_rng(0)
    depth = (0.6 + 0.05 * rng.random((120, 140))).astype(np.float32)
    pixels = np.array([[60.0, 50.0], [75.0, 66.0], [52.0, 71.0]])
    angle, pitch, size = 2 * math.pi * 5 / 16, 3.0, 32
    points, windows = lattice_positions(pixels, angle, pitch, size)
    lattice = ndimage.map_coordinates(depth, [points[..., 1], points[..., 0]], order=1, mode="nearest")
    d = np.array([math.cos(angle), math.sin(angle)])
    e = np.array([math.sin(angle), -math.cos(angle)])
    for (a0, b0), pixel in zip(windows, pixels, strict=True):
        centre = points[a0, b0] + pitch * 15.5 * (d + e)
        # the window nearest the pixel is centred within half the lattice's diagonal of it
        assert np.linalg.norm(centre - pixel) <= pitch * math.sqrt(2) / 2 + 1e-9
        want = extract_thumbnails(depth, centre[None], np.array([angle]))[0]
        np.testing.assert_allclose(lattice[a0:a0 + size, b0:b0 + size], want, rtol=0, atol=1e-6)


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


def test_dense_policy_refuses_a_network_it_cannot_convert():
    from suctionbench.errors import InputError
    from suctionbench.learning.models import build_model

    with pytest.raises(InputError, match="dense GQ-CNN"):
        DenseGQCNN(build_model("dn3", torch.Generator().manual_seed(0)))


def test_pick_with_the_dense_policy_is_a_valid_episode():
    from suctionbench.sim.pick import PickRequest, PickRunner

    result = PickRunner(PickRequest("basic/box_tea", policy="fc-gqcnn", seed=1)).run()
    assert result["valid"] and result["policy_q"] is not None and 0 <= result["policy_q"] <= 1
