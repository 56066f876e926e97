"""How the depth segmentation's regions match the objects in the bins (the renderer's instance masks).

For the first view of each bin of a task (the same bins, drops, camera and noise as the benchmark's
first attempt), every region of `sensing.segmentation.segment_regions` is compared with the objects
under it:
- merged: a second object holds at least 15 % of the region's pixels;
- partial: the region's main object has under 60 % of its visible pixels in it (split into parts);
and per object: split when no region holds 60 % of it, and its share of pixels in no region;
and, for the region's main object, how far the region's centroid and length are from the object's own
(`sensing.object_context.ObjectShape`, what the GQ-CNN's object context reads).

    .venv/bin/python eval/bin/segmentation.py --task bin-typical [--bins 10] [--cut-convex-creases]
"""

from __future__ import annotations

import argparse
import collections
import json

import numpy as np

from suctionbench.clutter.runner import BinRequest, BinRunner
from suctionbench.clutter.tasks import load_bin_task
from suctionbench.sensing.camera import DepthRenderer, body_image
from suctionbench.sensing.object_context import ObjectShape
from suctionbench.sensing.segmentation import SegmentationConfig, segment_regions

MERGED_SHARE = 0.15
"""A second object's share of a region that makes it merged."""

PARTIAL_SHARE = 0.60
"""A region holding less than this share of its main object's visible pixels is a part of it."""


def bin_view(task, trial: int):
    """The first view of bin `trial` as the benchmark's first attempt sees it (`BinRunner.observe`):
    the observation (noisy depth, the workspace as its mask), each object's instance mask inside the
    workspace (what the segmentation can see) by its key, and the runner."""
    runner = BinRunner(BinRequest(task=task, trial=trial, policy="planarity-centroid"))
    episode = runner.episode
    episode.reset(np.random.default_rng((task.seed, trial, 0)))  # as BinRunner.run fills the bin
    observation, _ = runner.observe(0)
    with DepthRenderer(runner.scene.model, runner.intrinsics) as renderer:
        body = body_image(runner.scene.model, renderer.segment(episode.data, runner.scene.camera))
    keys = dict(zip(episode.bodies, runner.keys, strict=True))
    objects = {keys[b]: (body == b) & observation.mask for b in episode.present}
    return observation, {k: m for k, m in objects.items() if m.sum() >= 20}, runner


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="bin-typical")
    parser.add_argument("--bins", type=int, default=10)
    parser.add_argument("--cut-convex-creases", action="store_true", help="the segmentation before 2026-11-28")
    args = parser.parse_args()
    task = load_bin_task(args.task)
    config = SegmentationConfig(cut_convex_creases=args.cut_convex_creases)
    counts = {"bins": args.bins, "objects": 0, "regions": 0, "merged": 0, "partial": 0}
    centroid_error, length_error, unlabelled = [], [], []
    split = collections.Counter()
    for trial in range(args.bins):
        observation, objects, runner = bin_view(task, trial)
        rotation, origin = runner.camera_pose[:3, :3], runner.camera_pose[:3, 3]
        world = runner.intrinsics.deproject(np.asarray(observation.depth, float)) @ rotation.T + origin
        counts["objects"] += len(objects)
        regions = segment_regions(observation.depth, runner.intrinsics, observation.mask, config)
        labelled = np.any(regions, axis=0) if regions else np.zeros_like(observation.mask)
        for key, mask in objects.items():  # an object no region holds PARTIAL_SHARE of: split
            unlabelled.append(1.0 - (mask & labelled).sum() / mask.sum())
            if max((int((mask & r).sum()) for r in regions), default=0) < PARTIAL_SHARE * mask.sum():
                split[key.split("/")[-1]] += 1
        for region in regions:
            counts["regions"] += 1
            size = int(region.sum())
            shares = sorted(((int((m & region).sum()) / size, k) for k, m in objects.items()), reverse=True)
            if not shares:
                continue
            main = shares[0][1]
            counts["merged"] += int(len(shares) > 1 and shares[1][0] >= MERGED_SHARE)
            counts["partial"] += int((objects[main] & region).sum() < PARTIAL_SHARE * objects[main].sum())
            seen, true = ObjectShape.of(world[region]), ObjectShape.of(world[objects[main]])
            centroid_error.append(float(np.linalg.norm(seen.centroid[:2] - true.centroid[:2])))
            length_error.append(seen.length - true.length)
    counts["split_objects"] = sum(split.values())
    counts["split_by_object"] = dict(split.most_common())
    counts["median_unlabelled_share"] = round(float(np.median(unlabelled)), 3)
    counts["median_centroid_error_mm"] = round(1000 * float(np.median(centroid_error)), 1)
    counts["median_length_error_mm"] = round(1000 * float(np.median(length_error)), 1)
    print(json.dumps({"task": args.task, "cut_convex_creases": args.cut_convex_creases, **counts}))


if __name__ == "__main__":
    main()
