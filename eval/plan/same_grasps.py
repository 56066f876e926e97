"""Do two versions of the code plan the same grasps? Plans on the scenes `bench plan` renders (one
per object of the typical set, every len // SCENES-th) with each image policy and compares.

    PYTHONPATH=OLD .venv/bin/python eval/plan/same_grasps.py --out old.npz      # the code in OLD
    .venv/bin/python eval/plan/same_grasps.py --out new.npz                     # this checkout
    .venv/bin/python eval/plan/same_grasps.py --compare old.npz new.npz

Prints, per policy, the largest difference of the grasp point (m), of q, and of the dense
policy's quality map over the scenes.
"""

import argparse

import numpy as np

POLICIES = ("gqcnn", "fc-gqcnn", "planarity-centroid", "planarity", "centroid")


def plan_all(scenes: int, seed: int, out: str) -> None:
    import torch

    from suctionbench.objects.registry import list_objects
    from suctionbench.policies.base import make_policy
    from suctionbench.sim.pick import PickRequest, PickRunner

    torch.set_num_threads(2)
    typical = list_objects("typical")
    observations = []
    for i, record in enumerate(typical[:: max(1, len(typical) // scenes)][:scenes]):
        runner = PickRunner(PickRequest(record.key, seed=seed + i, record=record))
        runner.reset()
        observations.append(runner.observe())
    saved = {}
    for name in POLICIES:
        policy = make_policy(name)
        actions = [policy.plan(obs, np.random.default_rng(seed + k)) for k, obs in enumerate(observations)]
        saved[f"{name}/point"] = np.stack([a.point for a in actions])
        saved[f"{name}/q"] = np.array([a.q for a in actions])
        if "quality_map" in actions[0].info:
            saved[f"{name}/quality_map"] = np.stack([a.info["quality_map"] for a in actions])
    np.savez_compressed(out, **saved)


def compare(a: str, b: str) -> None:
    old, new = np.load(a), np.load(b)
    for name in POLICIES:
        row = [f"{name}: point {np.abs(old[f'{name}/point'] - new[f'{name}/point']).max():.3g} m",
               f"q {np.abs(old[f'{name}/q'] - new[f'{name}/q']).max():.3g}"]
        if f"{name}/quality_map" in old:
            row.append(f"quality map {np.nanmax(np.abs(old[f'{name}/quality_map'] - new[f'{name}/quality_map'])):.3g}")
        print(", ".join(row))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", type=int, default=20)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out")
    parser.add_argument("--compare", nargs=2, metavar=("A", "B"))
    args = parser.parse_args()
    if args.compare:
        compare(*args.compare)
    else:
        plan_all(args.scenes, args.seed, args.out)
