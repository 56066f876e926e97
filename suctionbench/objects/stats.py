"""How hard each set is for the analytic labeller, and whether each object can be picked at all.

Per object, in its most probable stable pose (gravity along -z): the share of surface grasps that
seal and that are robust (rwr > 0.2, the training threshold). And its known-state pickability: over
its stable poses, the share of stable-pose probability in which at least one grasp is robust
(rwr > PICK_THRESHOLD) and approaches within the policies' cone (APPROACH_CONE from straight down).
Labels are those of the benchmark's known-state policy (LabelConfig.for_episode: the disturbing
wrench includes the inertial load of the episode's peak acceleration); the same share under the
weight alone (LabelConfig()) tells an object too heavy to carry through the transport from one with
no usable surface. An object with none is flagged (under gqcnn's 30 deg cone, a triangular prism
lying on a face offers only faces tilted 60 deg), not removed: it measures what no top-down policy
can do.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from suctionbench.config import CUP_DEFAULT, LabelConfig
from suctionbench.contact import SuctionLabeller
from suctionbench.contact.summary import POSITIVE_THRESHOLD
from suctionbench.evaluation.runner import PREDICT_THRESHOLD
from suctionbench.geometry.sampling import sample_surface_grasps
from suctionbench.objects.build import ObjectRecord
from suctionbench.objects.liquid import Liquid, com_at_rest
from suctionbench.objects.mass import mass_cap
from suctionbench.policies.base import SamplerConfig

PICK_THRESHOLD = PREDICT_THRESHOLD
"""rwr above which a grasp counts as robust for pickability: the benchmark's (0.5, evaluation.runner),
where an analytic label predicts a successful pick."""

APPROACH_CONE = SamplerConfig().max_optical_axis_angle
"""Largest angle (rad) between a grasp's approach and straight down that the image policies (heuristics,
CEM, GQ-CNN) sample: 60 deg from the optical axis (policies.base.SamplerConfig), taken here with the
camera looking straight down."""

CONE_EDGE = 1e-6
"""Slack on the cone's cosine (about 1e-4 deg): a face exactly at the cone's edge counts as inside,
whichever way rounding tilts it (a lying triangular prism's faces at 60 deg come out of its stable
pose 59.999999 or 60.000001 deg from vertical)."""

PICK_BATCH = 64
"""Grasps labelled at a time per pose; a pose stops at the first batch holding a robust grasp."""


def object_label_stats(record: ObjectRecord, grasps: int, seed: int, config: LabelConfig | None = None) -> dict:
    """Seal share, mean robust label and robust share (rwr > 0.2) of uniform surface grasps."""
    pose = record.most_probable_pose()
    mesh = record.mesh()
    liquid = Liquid.of(record, mesh.copy())
    mesh.apply_transform(pose)
    com = pose[:3, :3] @ com_at_rest(record, pose[:3, :3], liquid) + pose[:3, 3]
    labeller = SuctionLabeller(mesh, config, mass=record.mass, com=com)
    points, approaches = sample_surface_grasps(mesh, grasps, np.random.default_rng(seed))
    labels = labeller.label(points, approaches, seed, metrics=("wr", "rwr"))
    return {
        "seal_share": float(labels.seal.seal.mean()),
        "rwr_mean": float(labels.rwr.mean()),
        "robust_share": float((labels.rwr > POSITIVE_THRESHOLD).mean()),
    }


def pickability(
    record: ObjectRecord, grasps: int, seed: int, config: LabelConfig | None = None,
    threshold: float = PICK_THRESHOLD, cone: float = APPROACH_CONE,
) -> dict[str, Any]:
    """Known-state pickability: per recorded stable pose, whether any of up to `grasps` uniform
    surface grasps approaching within `cone` of straight down has rwr > `threshold` (labelled with
    `config`, default the episode's: weight and inertial load). `pickability` is the pickable share
    of the recorded poses' probability; `pose_coverage` is how much probability they hold (the rest
    lies in poses less probable than the build keeps, e.g. a polygonal cylinder's many sides)."""
    config = config or LabelConfig.for_episode(CUP_DEFAULT)
    mesh0 = record.mesh()
    liquid = Liquid.of(record, mesh0)
    poses, pickable_mass = [], 0.0
    for index, pose_data in enumerate(record.stable_poses):
        pose = np.asarray(pose_data["transform"], dtype=float)
        mesh = mesh0.copy()
        mesh.apply_transform(pose)
        com = pose[:3, :3] @ com_at_rest(record, pose[:3, :3], liquid) + pose[:3, 3]
        labeller = SuctionLabeller(mesh, config, mass=record.mass, com=com)
        rng = np.random.default_rng((seed, index))
        points, approaches = sample_surface_grasps(mesh, 8 * grasps, rng)
        inside = approaches[:, 2] <= -np.cos(cone) + CONE_EDGE
        points, approaches = points[inside][:grasps], approaches[inside][:grasps]
        best, labelled = 0.0, 0
        for start in range(0, len(points), PICK_BATCH):
            batch = slice(start, start + PICK_BATCH)
            rwr = labeller.label(points[batch], approaches[batch], seed + index, metrics=("rwr",)).rwr
            labelled += len(rwr)
            best = max(best, float(rwr.max()))
            if best > threshold:
                break
        ok = best > threshold
        pickable_mass += pose_data["probability"] * ok
        poses.append({"probability": pose_data["probability"], "in_cone": int(len(points)), "labelled": labelled,
                      "best_rwr": round(best, 4), "pickable": ok})
    total = sum(p["probability"] for p in record.stable_poses)
    share = pickable_mass / total if total > 0 else 0.0
    return {"pickability": round(share, 4), "unpickable": share == 0.0, "pose_coverage": round(total, 4),
            "poses": poses}


def object_pickability(record: ObjectRecord, grasps: int, seed: int) -> dict[str, Any]:
    """Pickability with the episode's load (`pickability`, per pose in `poses`) and under the weight
    alone (`pickability_static`); `flag` says why an object has none: "no_surface" (no grasp within
    the cone is robust even statically) or "load" (robust under its weight, not with the inertial
    load of the transport)."""
    episode = pickability(record, grasps, seed)
    static = pickability(record, grasps, seed, LabelConfig())
    flag = None
    if episode["unpickable"]:
        flag = "no_surface" if static["unpickable"] else "load"
    return {**episode, "pickability_static": static["pickability"], "flag": flag}


def set_stats(
    records: list[ObjectRecord], grasps: int, seed: int, progress: Callable[[int], None] | None = None,
    *, pick: bool = True,
) -> dict[str, Any]:
    """Per-set summary: counts, faces, parts, mass range, label shares (means over objects) and, with
    `pick`, known-state pickability per object, its mean and the objects flagged with none."""
    per_object = []
    for record in records:
        row: dict[str, Any] = {"key": record.key, "mass": record.mass, "mass_source": record.mass_source}
        row.update(object_label_stats(record, grasps, seed))
        if pick:
            row.update(object_pickability(record, grasps, seed))
        per_object.append(row)
        if progress:
            progress(1)
    summary = {
        "objects": len(records),
        "faces": [min(r.faces for r in records), max(r.faces for r in records)],
        "parts": [min(len(r.parts) for r in records), max(len(r.parts) for r in records)],
        "mass_kg": [round(min(r.mass for r in records), 4), round(max(r.mass for r in records), 4)],
        "seal_share": round(float(np.mean([o["seal_share"] for o in per_object])), 4),
        "robust_share": round(float(np.mean([o["robust_share"] for o in per_object])), 4),
        "rwr_mean": round(float(np.mean([o["rwr_mean"] for o in per_object])), 4),
    }
    if pick:
        summary["pickability"] = round(float(np.mean([o["pickability"] for o in per_object])), 4)
        summary["pickability_static"] = round(float(np.mean([o["pickability_static"] for o in per_object])), 4)
        summary["unpickable"] = {o["key"]: o["flag"] for o in per_object if o["unpickable"]}
    summary["per_object"] = per_object
    return summary


def pick_criteria() -> dict[str, Any]:
    """What pickability counts and the mass cap objects are held to, for reports."""
    return {
        "pick_threshold_rwr": PICK_THRESHOLD,
        "approach_cone_deg": round(float(np.degrees(APPROACH_CONE)), 3),
        "mass_cap": mass_cap(CUP_DEFAULT),
    }


def stats_rows(sets: dict[str, dict[str, Any]]) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Rows for the human tables of `objects stats`: one per set, one per object (pickability)."""
    set_rows, object_rows = [], []
    for name, result in sets.items():
        row = {"set": name, **{k: v for k, v in result.items() if k not in ("per_object", "unpickable")}}
        if "unpickable" in result:
            row["unpickable"] = len(result["unpickable"])
        set_rows.append(row)
        for obj in result["per_object"]:
            if "pickability" in obj:
                object_rows.append({"object": obj["key"], "mass_kg": obj["mass"], "pickability": obj["pickability"],
                                    "static": obj["pickability_static"], "poses": obj["pose_coverage"],
                                    "flag": obj["flag"] or ""})
    return set_rows, object_rows
