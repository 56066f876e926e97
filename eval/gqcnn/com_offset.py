"""Where each executed grasp lay against the object's centre of mass and against its shape's centre.

A depth image shows an object's shape, not how its mass is spread: a bottle part-filled with
liquid has its centre of mass towards its base, away from the shape's centre. This reads the
runs' MCAP logs (the grasp point in the world and the object's pose at the first /tf message) and
the objects' own records (centre of mass, mesh; a liquid levelled in that pose, as the simulation
of SuctionPick-v3 levels it: objects.liquid), and prints per trial the horizontal distance of
the grasp from the centre of mass and from the shape's centre (the centroid of the solid its mesh
bounds), beside the outcome.

Usage: python eval/gqcnn/com_offset.py RUN_DIR [RUN_DIR ...] [--objects NAME,NAME] [--json]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from suctionbench.objects.liquid import Liquid, com_at_rest
from suctionbench.objects.registry import load_object
from suctionbench.runlog.reader import iter_messages, read_run


def object_pose(log_path: str) -> tuple[np.ndarray, np.ndarray]:
    """Rotation matrix and translation of the object frame in the world at the first /tf message."""
    for _, message in iter_messages(log_path, "/tf"):
        for tf in message["transforms"]:
            if tf["child_frame_id"] == "object":
                q, t = tf["rotation"], tf["translation"]
                return (Rotation.from_quat([q["x"], q["y"], q["z"], q["w"]]).as_matrix(),
                        np.array([t["x"], t["y"], t["z"]]))
    raise ValueError(f"{log_path}: no object pose on /tf")


def trial_offsets(run_dir: Path, objects: list[str] | None) -> list[dict]:
    """One row per trial of `run_dir` (of the named objects only, if given)."""
    rows, shapes = [], {}
    for log in read_run(run_dir / "trials"):
        result = log["result"]
        name = result["object"]
        if objects and not any(o in name for o in objects):
            continue
        if name not in shapes:
            record = load_object(name)
            mesh = record.mesh()
            shapes[name] = (record, Liquid.of(record, mesh), mesh.center_mass)
        record, liquid, centre = shapes[name]
        rotation, translation = object_pose(log["path"])
        com = com_at_rest(record, rotation, liquid)
        grasp = np.array(result["grasp_world"][:3])
        com_w, centre_w = rotation @ com + translation, rotation @ centre + translation
        rows.append({"run": run_dir.name, "object": name, "success": bool(result["success"]),
                     "label_rwr": result["label_rwr"], "q": result["policy_q"],
                     "grasp_to_com_mm": round(1000 * float(np.linalg.norm((grasp - com_w)[:2])), 1),
                     "grasp_to_shape_centre_mm": round(1000 * float(np.linalg.norm((grasp - centre_w)[:2])), 1),
                     "com_to_shape_centre_mm": round(1000 * float(np.linalg.norm((com_w - centre_w)[:2])), 1)})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", type=Path)
    parser.add_argument("--objects", help="comma-separated parts of object names to keep")
    parser.add_argument("--json", action="store_true", help="one JSON object per trial")
    args = parser.parse_args()
    objects = args.objects.split(",") if args.objects else None
    rows = [row for run in args.runs for row in trial_offsets(run, objects)]
    if args.json:
        print("\n".join(json.dumps(row) for row in rows))
        return
    print("| run | object | success | label rwr | q | grasp to com (mm) | grasp to shape centre (mm) "
          "| com to shape centre (mm) |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['run']} | {r['object']} | {int(r['success'])} | {r['label_rwr']:.2f} | {r['q']:.2f} | "
              f"{r['grasp_to_com_mm']} | {r['grasp_to_shape_centre_mm']} | {r['com_to_shape_centre_mm']} |")


if __name__ == "__main__":
    main()
