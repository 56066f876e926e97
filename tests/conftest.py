"""Shared fixtures: small analytic meshes with known suction behaviour (all in metres)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import trimesh

from suctionbench.config import CUP_DEFAULT
from suctionbench.dataset.storage import shard_file_name


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


def pytest_collection_modifyitems(config, items):
    """Skip tests marked `gpu` where torch sees no CUDA device (CI, the 2-core development machine)."""
    import torch

    if torch.cuda.is_available():
        return
    skip = pytest.mark.skip(reason="needs a CUDA device")
    for item in items:
        if "gpu" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def cup():
    return CUP_DEFAULT


@pytest.fixture
def rng():
    return np.random.default_rng(1234)


def remove_dataset_field(directory: Path, name: str) -> Path:
    """Make the dataset in `directory` look as written before field `name` existed: its files gone,
    and neither the shard manifests nor the card listing it (in place; returns `directory`)."""
    for manifest_path in sorted((directory / "tensors").glob("shard_*.json")):
        manifest = json.loads(manifest_path.read_text())
        file = shard_file_name(name, manifest["shard"])
        del manifest["files"][file]
        (directory / "tensors" / file).unlink()
        manifest_path.write_text(json.dumps(manifest))
    card = json.loads((directory / "config.json").read_text())
    del card["fields"][name]
    (directory / "config.json").write_text(json.dumps(card))
    return directory
