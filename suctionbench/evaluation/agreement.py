"""Agreement study: the analytic labeller against the simulated cup, grasp by grasp.

Trial i of a set drops object i mod |set| (seed base + i), draws one surface grasp uniformly
(known state, no ranking: the `random-surface` policy), labels it analytically in the true pose and
executes it in MuJoCo. Grasps the robot cannot execute (unreachable, arm collision, unstable
placement) are counted and left out, so the study scores the two cup models on reachable grasps only.

Per set and overall it reports seal agreement (labeller's nominal seal vs the simulated cup sealing),
lift accuracy / precision / recall of `rwr > threshold` against simulated success, AP and Spearman of
rwr against success, and every disagreement classified by cause from the trial's physics: the
approach's tilt from the surface normal (against the cup's approach tolerance) and the gravity torque
about the grasp (against the ring-pressure peel limit r (V - m g) / 2). The two models compute
independently; this module only compares them.
"""

from __future__ import annotations

import math
from collections import Counter
from typing import Any

import numpy as np

from suctionbench.config import STANDARD_GRAVITY
from suctionbench.errors import InputError

NOT_EXECUTED = ("unreachable", "collision", "unstable", "no_grasp")
"""Outcomes that mean the robot never tested a grasp (none reachable, none facing the gripper, an
unstable placement): left out of the study."""

SETS = ("basic", "typical", "adversarial")
"""The object sets the study covers by default."""


def grasp_physics(runner: Any, pose: np.ndarray, record: dict[str, Any]) -> dict[str, float]:
    """Physical quantities that explain a disagreement, computed from the object at `pose` (where the
    grasp was chosen and labelled):
    the approach's tilt from the surface normal at the target (deg; the cup's approach tolerance
    bounds it), and the ratio of the object's gravity torque about the target to the ring-pressure
    peel limit r (V - m g) / 2 (above 1 the lip must peel under gravity alone, before any
    acceleration; a load above V leaves no limit at all: ratio inf)."""
    mesh, com = runner.posed_object(pose)
    grasp = np.asarray(record["grasp_world"], dtype=float)
    point, approach = grasp[:3], grasp[3:] / np.linalg.norm(grasp[3:])
    _, _, face = mesh.nearest.on_surface(point[None])
    normal = mesh.face_normals[int(face[0])]
    tilt = math.degrees(math.acos(float(np.clip(-approach @ normal, -1.0, 1.0))))
    cup, mass = runner.request.cup, runner.record.mass
    weight = mass * STANDARD_GRAVITY
    torque = float(np.linalg.norm(np.cross(com - point, np.array([0.0, 0.0, -weight]))))
    limit = cup.radius * (cup.vacuum_force - weight) / 2.0
    return {
        "approach_tilt_deg": round(tilt, 2),
        "gravity_torque": round(torque, 5),
        "torque_ratio": round(torque / limit, 3) if limit > 0 else math.inf,
    }


def _trials_for_object(set_name: str, key: str, seeds: list[int]) -> list[dict[str, Any]]:
    """Run the random-surface trials of one object (one scene, many seeds); picklable for pools."""
    from suctionbench.objects.registry import load_object
    from suctionbench.sim.pick import PickRequest, PickRunner

    record = load_object(key)
    runner = PickRunner(PickRequest(key, policy="random-surface", record=record))
    rows = []
    for seed in seeds:
        runner.request.seed = seed
        runner.reset()
        pose = runner.object_pose()  # the state the grasp was chosen and labelled in
        result = runner.run_after_reset()
        row = {
            "set": set_name, "object": key, "seed": seed, "label_seal": result["label_seal"],
            "label_seal_failure": result["label_seal_failure"],
            "label_wr": result["label_wr"], "label_rwr": result["label_rwr"],
            "sim_seal": result["seal_time"] is not None, "success": bool(result["success"]),
            "failure": result["failure"], "valid": bool(result["valid"]), "mass": record.mass,
        }
        if result["grasp_world"] is not None and row["valid"] and row["failure"] not in NOT_EXECUTED:
            row.update(grasp_physics(runner, pose, result))
        rows.append(row)
    return rows


def seal_cause(row: dict[str, Any], tolerance_deg: float) -> str | None:
    """Why the labeller's nominal seal and the simulated seal disagree (None if they agree)."""
    if row["label_seal"] == row["sim_seal"]:
        return None
    if row.get("label_seal_failure") == "pushed_away":
        return "sim seals, labeller does not: object pushed away by the touch-down's press"
    near_limit = row["approach_tilt_deg"] > 0.8 * tolerance_deg
    if row["label_seal"]:
        return ("labeller seals, sim does not: approach near the tilt tolerance" if near_limit
                else "labeller seals, sim does not: lip contact (curvature/edge) at a flat-looking target")
    return ("sim seals, labeller does not: approach near the tilt tolerance" if near_limit
            else "sim seals, labeller does not: surface under the lip (leak/curvature) judged stricter")


def lift_cause(row: dict[str, Any], threshold: float) -> str | None:
    """Why `rwr > threshold` and the simulated pick disagree (None if they agree)."""
    predicted, actual = row["label_rwr"] > threshold, row["success"]
    if predicted == actual:
        return None
    if predicted:
        return f"labeller robust, sim fails: {row['failure']}"
    if not row["label_seal"]:
        return "sim succeeds, labeller: no seal"
    if row["torque_ratio"] > 1.0:
        return "sim succeeds, labeller: gravity torque above the peel limit (sim holds more torque)"
    if row["label_wr"]:
        return "sim succeeds, labeller: resists nominally, fails under perturbation (rwr <= threshold)"
    return "sim succeeds, labeller: nominal wrench rejected below the peel limit (friction/inertial load)"


def summarize(rows: list[dict[str, Any]], threshold: float, tolerance_deg: float) -> dict[str, Any]:
    """Agreement figures of executed trials (see module docstring)."""
    from suctionbench.evaluation.runner import score_stats

    executed = [r for r in rows if r["valid"] and r["failure"] not in NOT_EXECUTED]
    out: dict[str, Any] = {"trials": len(rows), "executed": len(executed),
                           "not_executed": dict(Counter(r["failure"] or "invalid" for r in rows
                                                        if r not in executed))}
    if not executed:
        return out
    label_seal = np.array([r["label_seal"] for r in executed])
    sim_seal = np.array([r["sim_seal"] for r in executed])
    rwr = np.array([r["label_rwr"] for r in executed], dtype=float)
    success = np.array([r["success"] for r in executed])
    predicted = rwr > threshold
    tp, fp = int((predicted & success).sum()), int((predicted & ~success).sum())
    fn, tn = int((~predicted & success).sum()), int((~predicted & ~success).sum())
    stats = score_stats(rwr, success)
    out.update({
        "seal_agreement": round(float((label_seal == sim_seal).mean()), 4),
        "seal_confusion": {
            "both": int((label_seal & sim_seal).sum()), "label_only": int((label_seal & ~sim_seal).sum()),
            "sim_only": int((~label_seal & sim_seal).sum()), "neither": int((~label_seal & ~sim_seal).sum()),
        },
        "lift_confusion": {"label_pos_sim_success": tp, "label_pos_sim_fail": fp,
                           "label_neg_sim_success": fn, "label_neg_sim_fail": tn},
        "accuracy": round((tp + tn) / len(executed), 4),
        "precision": round(tp / (tp + fp), 4) if tp + fp else None,
        "recall": round(tp / (tp + fn), 4) if tp + fn else None,
        "ap": stats["ap"],
        "spearman": stats["spearman"],
        "sim_success_rate": round(float(success.mean()), 4),
        "label_positive_rate": round(float(predicted.mean()), 4),
        "seal_disagreements": dict(Counter(c for r in executed if (c := seal_cause(r, tolerance_deg))).most_common()),
        "lift_disagreements": dict(Counter(c for r in executed if (c := lift_cause(r, threshold))).most_common()),
        "sim_outcomes": dict(sorted(Counter(r["failure"] or "success" for r in executed).items())),
    })
    return out


BYTES_PER_TRIAL_ROW = 4096
"""Memory per trial of the study: its result row (about 20 entries) and its share of the tables."""


def run_agreement(*, sets: tuple[str, ...] = SETS, trials: int = 1000, seed: int = 0, threshold: float = 0.5,
                  workers: int = 1) -> dict[str, Any]:
    """The agreement study over `sets`: `trials` grasps in total, split over the sets in proportion
    to their object counts (at least one per object), run on `workers` processes."""
    from suctionbench.config import CUP_DEFAULT
    from suctionbench.objects.registry import list_objects
    from suctionbench.parallel import map_ordered
    from suctionbench.validate import require_memory

    if trials < 1 or not 0.0 <= threshold <= 1.0 or workers < 1:
        raise InputError(f"bench agreement: need --trials >= 1, 0 <= --threshold <= 1 and --workers >= 1 "
                         f"(got {trials}, {threshold}, {workers})")
    require_memory(trials * BYTES_PER_TRIAL_ROW, f"--trials {trials}")  # every trial's row is kept
    records = {s: list_objects(s) for s in sets}
    total = sum(len(r) for r in records.values())
    tasks = []
    for set_name, objs in records.items():
        n = max(len(objs), round(trials * len(objs) / total))
        for k, rec in enumerate(objs):
            seeds = [seed + i for i in range(k, n, len(objs))]
            if seeds:
                tasks.append((set_name, rec.key, seeds))
    rows = [row for chunk in map_ordered(_trials_for_object, tasks, workers=workers) for row in chunk]
    tolerance = math.degrees(CUP_DEFAULT.approach_tolerance)
    per_set = {s: summarize([r for r in rows if r["set"] == s], threshold, tolerance) for s in sets}
    return {"threshold": threshold, "seed": seed, "approach_tolerance_deg": round(tolerance, 2),
            "overall": summarize(rows, threshold, tolerance), "sets": per_set, "per_trial": rows}
