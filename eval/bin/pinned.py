"""Why robust-labelled grasps are lost in the lift in a bin: replay a bin run's bins (the same seeds
give the same attempts) and, before each attempt the label calls robust (rwr > 0.5) but the
simulation lost in the lift, sum the contact forces the other objects press onto the target with
(`BinEpisode.resting_load`). A neighbour resting on the target is load the cup must also lift.

    .venv/bin/python eval/bin/pinned.py RUN_DIR [--bins N]

Prints one line per such attempt (bin, attempt, object, its weight, the neighbours' downward
load on it) and the attempt's outcome on replay (it must match the run's).
"""

import argparse
import json
import os
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402

from suctionbench.clutter.runner import BinRequest, BinRunner  # noqa: E402
from suctionbench.clutter.tasks import load_bin_task  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path)
    parser.add_argument("--bins", type=int, default=None)
    args = parser.parse_args()
    run = json.loads((args.run / "run.json").read_text())
    task = load_bin_task(run["task"])
    loads = []
    for record in run["bins"][: args.bins]:
        wanted = {a["attempt"] for a in record["attempts"]
                  if a["failure"] == "seal_lost_lift" and (a["label_rwr"] or 0) > 0.5}
        if not wanted:
            continue
        runner = BinRunner(BinRequest(task, trial=record["trial"], policy=run["policy"], masks=run["masks"]))
        runner.episode.reset(np.random.default_rng((task.seed, record["trial"], 0)))
        runner.failed = []
        for attempt in range(max(wanted) + 1):
            if attempt not in wanted:
                runner.attempt(attempt)
                continue
            point, approach, q, info = runner.plan(attempt)
            target = runner.episode.target_at(point, approach)
            load, _ = runner.episode.resting_load(target)
            weight = runner.objects[target][0].mass * 9.81
            replay = runner.attempt_grasp(attempt, point, approach, q, info)
            loads.append(load / weight)
            print(f"bin {record['trial']} attempt {attempt}: {runner.keys[runner.episode.bodies.index(target)]:28s} "
                  f"weight {weight:.2f} N, neighbours press {load:.2f} N ({load / weight:.0%}); "
                  f"replay: {replay['failure']}")
    if loads:
        print(f"{len(loads)} attempts; neighbours' load / weight: median {np.median(loads):.0%}, "
              f"{sum(x > 0.1 for x in loads)} above 10 %")


if __name__ == "__main__":
    main()
