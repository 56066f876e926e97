"""How hard each set is for the analytic labeller: per object, in its most probable stable pose
(gravity along -z), the share of surface grasps that seal and that are robust."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from suctionbench.config import LabelConfig
from suctionbench.contact import SuctionLabeller
from suctionbench.contact.summary import POSITIVE_THRESHOLD
from suctionbench.geometry.sampling import sample_surface_grasps
from suctionbench.objects.build import ObjectRecord


def object_label_stats(record: ObjectRecord, grasps: int, seed: int, config: LabelConfig | None = None) -> dict:
    """Seal share, mean robust label and robust share (rwr > 0.2) of uniform surface grasps."""
    pose = record.most_probable_pose()
    mesh = record.mesh()
    mesh.apply_transform(pose)
    com = pose[:3, :3] @ np.asarray(record.com) + pose[:3, 3]
    labeller = SuctionLabeller(mesh, config, mass=record.mass, com=com)
    points, approaches = sample_surface_grasps(mesh, grasps, np.random.default_rng(seed))
    labels = labeller.label(points, approaches, seed, metrics=("wr", "rwr"))
    return {
        "seal_share": float(labels.seal.seal.mean()),
        "rwr_mean": float(labels.rwr.mean()),
        "robust_share": float((labels.rwr > POSITIVE_THRESHOLD).mean()),
    }


def set_stats(
    records: list[ObjectRecord], grasps: int, seed: int, progress: Callable[[int], None] | None = None
) -> dict[str, Any]:
    """Per-set summary: counts, faces, parts, mass range, label shares (means over objects)."""
    per_object = []
    for record in records:
        per_object.append({"key": record.key, **object_label_stats(record, grasps, seed)})
        if progress:
            progress(1)
    return {
        "objects": len(records),
        "faces": [min(r.faces for r in records), max(r.faces for r in records)],
        "parts": [min(len(r.parts) for r in records), max(len(r.parts) for r in records)],
        "mass_kg": [round(min(r.mass for r in records), 4), round(max(r.mass for r in records), 4)],
        "seal_share": round(float(np.mean([o["seal_share"] for o in per_object])), 4),
        "robust_share": round(float(np.mean([o["robust_share"] for o in per_object])), 4),
        "rwr_mean": round(float(np.mean([o["rwr_mean"] for o in per_object])), 4),
        "per_object": per_object,
    }
