"""What the simulated robot does to a planned grasp, measured over every object of the three sets.

For each object and seed: drop it (the episode's placement), time how long it takes to come to rest,
then pick it straight down through its centre of mass and record
- the landing offset: how far the bellows' axis passes from the planned grasp point when the lip
  first touches (the arm's tracking error across the approach; the labeller judges the grasp at
  the planned point),
- the cup's peak acceleration in the lift and the transport (the labeller's inertial load assumes
  `CupConfig.peak_acceleration`).

Usage: python eval/episode/execution.py [--seeds N] [--out FILE]   (prints a JSON summary)
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from suctionbench.objects.registry import list_objects
from suctionbench.sim.pick import PickRequest, PickRunner


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    rows = []
    for record in (r for s in ("basic", "typical", "adversarial") for r in list_objects(s)):
        key = f"{record.set}/{record.name}"
        runner = PickRunner(PickRequest(key, record=record))
        for seed in range(args.seeds):
            runner.request.seed = seed
            runner.reset()
            episode = runner.episode
            row = {"object": key, "seed": seed, "settle_s": round(float(episode.data.time), 3),
                   "placement_error": episode.placement_error}
            if episode.placement_error is None:
                mesh, com = runner.posed_object()
                hits, _, _ = mesh.ray.intersects_location([com + [0.0, 0.0, 1.0]], [[0.0, 0.0, -1.0]])
                if len(hits):
                    top, down = hits[np.argmax(hits[:, 2])], np.array([0.0, 0.0, -1.0])
                    offset, result = episode.execute_measuring_landing(top, down)
                    row.update({"landing_offset_mm": None if offset is None else round(offset * 1e3, 3),
                                "failure": result.failure, "peak_acceleration": result.peak_acceleration})
            rows.append(row)

    def stats(values: list[float]) -> dict[str, float]:
        a = np.asarray(values, dtype=float)
        return {"n": int(a.size), "median": round(float(np.median(a)), 3),
                "p90": round(float(np.percentile(a, 90)), 3), "max": round(float(a.max()), 3)}

    summary = {
        "episodes": len(rows),
        "unstable_placements": sum(r["placement_error"] is not None for r in rows),
        "settle_s": stats([r["settle_s"] for r in rows]),
        "landing_offset_mm": stats([r["landing_offset_mm"] for r in rows if r.get("landing_offset_mm") is not None]),
        "peak_acceleration_lift": stats([r["peak_acceleration"]["lift"] for r in rows
                                         if "lift" in r.get("peak_acceleration", {})]),
        "peak_acceleration_transport": stats([r["peak_acceleration"]["transport"] for r in rows
                                              if "transport" in r.get("peak_acceleration", {})]),
    }
    if args.out is not None:
        args.out.write_text(json.dumps({"summary": summary, "rows": rows}, indent=1) + "\n")
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
