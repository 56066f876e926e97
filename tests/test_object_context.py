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
    # 0.1 m ahead of the lean; leaning away, 0.1 m behind; leaning across, beside (0).
    points, grasp = plank_top(), np.array([[0.1, 0.0, 0.02]])
    s, c = math.sin(math.radians(30)), math.cos(math.radians(30))
    leans = np.array([[-s, 0.0, -c], [s, 0.0, -c], [0.0, s, -c]])
    along = object_context(points, np.repeat(grasp, 3, axis=0), leans)[:, 1]
    np.testing.assert_allclose(along, [0.1, -0.1, 0.0], atol=1e-9)


def test_no_object_seen_gives_zeros():
    assert not object_context(np.zeros((0, 3)), np.zeros((2, 3)), np.tile([0.0, 0.0, -1.0], (2, 1))).any()
