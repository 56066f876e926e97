"""Shared fixtures: small analytic meshes with known suction behaviour (all in metres)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from suctionbench.config import CUP_DEFAULT


def box(extents, center=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    """An axis-aligned box."""
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation(center)
    return mesh


def difference(a: trimesh.Trimesh, b: trimesh.Trimesh) -> trimesh.Trimesh:
    """Boolean a - b through manifold3d."""
    return trimesh.boolean.difference([a, b], engine="manifold")


def union(*meshes: trimesh.Trimesh) -> trimesh.Trimesh:
    """Boolean union through manifold3d."""
    return trimesh.boolean.union(list(meshes), engine="manifold")


@pytest.fixture(scope="session")
def cup():
    return CUP_DEFAULT


@pytest.fixture
def rng():
    return np.random.default_rng(1234)
