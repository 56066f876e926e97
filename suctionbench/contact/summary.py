"""Plain-data views of labels: one grasp as a JSON-ready record, a batch as a summary and a file."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.config import to_dict
from suctionbench.contact.metrics import METRICS, GraspLabels
from suctionbench.contact.seal import FAILURES
from suctionbench.io import save_npz

POSITIVE_THRESHOLD = 0.2
"""Robust label above which a grasp counts as positive (Dex-Net 3.0 training threshold)."""


def _num(x: float) -> float | None:
    """JSON-safe float: None for inf/NaN."""
    x = float(x)
    return x if np.isfinite(x) else None


def grasp_record(labels: GraspLabels, i: int) -> dict[str, Any]:
    """Everything known about grasp i, JSON-ready."""
    seal = labels.seal
    record: dict[str, Any] = {
        "point": labels.points[i].tolist(),
        "approach": labels.approaches[i].tolist(),
        "seal": bool(seal.seal[i]),
        "seal_failure": seal.failure_names[i],
        "max_stretch": _num(seal.max_stretch[i]),
        "perimeter_stretch": _num(seal.perimeter_stretch[i]),
        "flexion_stretch": _num(seal.flexion_stretch[i]),
        "cone_stretch": _num(seal.cone_stretch[i]),
        "cone_collision": bool(seal.cone_collision[i]),
        "hole": bool(seal.hole[i]),
        "ring_off_surface": bool(seal.ring_off_surface[i]),
        "tilt_deg": _num(np.degrees(seal.tilt[i])),
        "leak_area_mm2": _num(1e6 * seal.leak_area[i]),
        "vacuum_force": _num(seal.vacuum_force[i]),
        "contact_point": [_num(c) for c in seal.surface_point[i]],
        "wr": bool(labels.wr[i]),
    }
    if labels.rwr is not None:
        record["rwr"] = float(labels.rwr[i])
    for name in ("pc3d", "ss"):
        record[name] = float(labels.score(name)[i])
    return record


def batch_summary(labels: GraspLabels) -> dict[str, Any]:
    """Counts and rates over a batch of labelled grasps."""
    seal = labels.seal
    failures = Counter(FAILURES[f] for f in seal.failure if f)
    summary: dict[str, Any] = {
        "grasps": len(labels.points),
        "seal_rate": float(seal.seal.mean()),
        "seal_failures": dict(sorted(failures.items())),
        "wr_rate": float(labels.wr.mean()),
    }
    if labels.rwr is not None:
        summary["samples_per_grasp"] = int(labels.samples.shape[1])
        summary["rwr_mean"] = float(labels.rwr.mean())
        summary["positive_rate"] = float((labels.rwr > POSITIVE_THRESHOLD).mean())
        summary["positive_threshold"] = POSITIVE_THRESHOLD
    return summary


def save_labels(path: str | Path, labels: GraspLabels) -> None:
    """Write labels to an .npz (atomically): grasps, seal diagnostics, every computed metric."""
    seal = labels.seal
    arrays = {
        "points": labels.points,
        "approaches": labels.approaches,
        "seal": seal.seal,
        "seal_failure": seal.failure,
        "seal_failure_names": np.array(FAILURES),
        "max_stretch": seal.max_stretch,
        "leak_area": seal.leak_area,
        "vacuum_force": seal.vacuum_force,
        "contact_points": seal.surface_point,
        "com": labels.com,
        "config_json": np.array(json.dumps(to_dict(labels.config))),
    }
    for name in METRICS:
        if name != "rwr" or labels.rwr is not None:
            arrays[name] = labels.score(name)
    save_npz(path, **arrays)
