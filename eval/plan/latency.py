"""Latency of `suctionbench plan` on a 640 x 480 depth image (examples/scene_mug.png, PrimeSense).

    .venv/bin/python eval/plan/latency.py --repeats 10 > eval/plan/latency.json

For each policy: the first call in the process (the GQ-CNN's model loading included; scikit-learn
and torch are imported before timing starts) and the median / max of `--repeats` further calls, each split into the
support-plane fit, segmentation and planning (`PlanResult.timings`). One process, one thread per
library default, the allocator set as the command line sets it (`suctionbench.allocator`); the
machine's other load is not controlled, so read the figures as indicative.
"""

import argparse
import json
import os
import platform
import statistics
import time
from pathlib import Path

import numpy as np
import sklearn.linear_model  # noqa: F401  (imported before timing: the CLI pays this once per process)
import torch  # noqa: F401

from suctionbench.allocator import keep_large_blocks
from suctionbench.bench import cpu_model
from suctionbench.planning import plan_grasp, read_depth

IMAGE = Path(__file__).resolve().parents[2] / "examples" / "scene_mug.png"


def measure(policy: str, depth: np.ndarray, repeats: int) -> dict:
    start = time.perf_counter()
    plan_grasp(depth, "primesense", policy=policy, seed=0)
    first = time.perf_counter() - start
    runs = [plan_grasp(depth, "primesense", policy=policy, seed=k).timings for k in range(1, repeats + 1)]
    row = {"policy": policy, "first_call_s": round(first, 4)}
    for key in ("plane", "segment", "plan", "total"):
        values = [r[key] for r in runs]
        row[f"{key}_median_s"] = round(statistics.median(values), 4)
    row["total_max_s"] = round(max(r["total"] for r in runs), 4)
    return row


def main(repeats: int) -> None:
    keep_large_blocks()  # as the command line does at start
    depth = read_depth(IMAGE)
    rows = [measure(p, depth, repeats) for p in ("random", "centroid", "planarity-centroid", "gqcnn", "fc-gqcnn")]
    print(json.dumps({"image": f"{IMAGE.name} {depth.shape[1]} x {depth.shape[0]}", "repeats": repeats,
                      "machine": f"{platform.machine()}, {platform.python_implementation()} "
                                 f"{platform.python_version()}", "cpu": cpu_model(),
                      "cores": len(os.sched_getaffinity(0)), "rows": rows}, indent=1))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=10)
    main(parser.parse_args().repeats)
