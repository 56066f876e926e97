"""How far each trial's grasp approach is from the object's true surface normal at the grasp point,
against the simulated outcome: whether the normals a policy reads from the depth image are what
its grasps fail on.

Usage: python eval/gqcnn/approach_error.py RUN [RUN ...]   (each an `eval --out` directory)

Per trial: the object's pose at the first logged transform (the placement, before the cup moves),
the object's mesh in that pose, the mesh face nearest the logged grasp point, and the angle
between minus the approach and that face's normal. A known-state run's grasps are the mesh's own
(0 deg); an image policy's carry the depth image's noise and smoothing. Prints per run the median
and 90th percentile angle, and success and `no_seal` shares by angle band.
"""

from __future__ import annotations

import sys
from functools import cache
from pathlib import Path

import numpy as np
import trimesh

from suctionbench.errors import InputError
from suctionbench.objects.registry import load_object
from suctionbench.runlog.reader import frame_pose, read_run

BANDS = ((0.0, 5.0), (5.0, 10.0), (10.0, 15.0), (15.0, 25.0), (25.0, 180.0))
"""Angle bands (deg) of the summary."""


@cache
def object_mesh(key: str) -> trimesh.Trimesh:
    """An object's mesh in its own frame, loaded once per object of a run."""
    return load_object(key).mesh()


def approach_errors(run: Path) -> list[tuple[str, bool, str | None, float]]:
    """(object, success, failure, angle deg) of every valid trial with a grasp."""
    rows = []
    for record in read_run(run / "trials"):
        result = record["result"]
        grasp = result.get("grasp_world")
        if not result.get("valid", True) or grasp is None:
            continue
        try:
            pose = frame_pose(record["path"], "object")  # the placement, before the cup moves it
        except InputError:
            continue
        mesh = object_mesh(result["object"]).copy()
        mesh.apply_transform(pose)
        point, approach = np.asarray(grasp[:3]), np.asarray(grasp[3:6])
        _, _, face = trimesh.proximity.closest_point(mesh, [point])
        cosine = float(np.clip(-approach @ mesh.face_normals[face[0]], -1.0, 1.0))
        angle = float(np.degrees(np.arccos(cosine)))
        rows.append((result["object"], bool(result["success"]), result.get("failure"), angle))
    return rows


def main(runs: list[Path]) -> None:
    for run in runs:
        rows = approach_errors(run)
        angle = np.array([r[3] for r in rows])
        success = np.array([r[1] for r in rows])
        no_seal = np.array([r[2] == "no_seal" for r in rows])
        print(f"{run}: {len(rows)} grasps, angle to the surface normal median {np.median(angle):.1f} deg, "
              f"90th percentile {np.percentile(angle, 90):.1f} deg")
        print("| angle (deg) | grasps | success % | no_seal % |")
        print("|---|---|---|---|")
        for low, high in BANDS:
            band = (angle >= low) & (angle < high)
            if band.any():
                print(f"| {low:g}-{high:g} | {band.sum()} | {100 * success[band].mean():.0f} | "
                      f"{100 * no_seal[band].mean():.0f} |")


if __name__ == "__main__":
    if len(sys.argv) < 2 or not all(Path(p, "trials").is_dir() for p in sys.argv[1:]):
        sys.exit("usage: python eval/gqcnn/approach_error.py RUN [RUN ...] (eval --out directories)")
    main([Path(p) for p in sys.argv[1:]])
