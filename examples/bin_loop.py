"""Clearing a bin with a hand-written policy: the topmost object region's middle, straight down.

    .venv/bin/python examples/bin_loop.py --task bin-smoke --seed 0

`suctionbench/SuctionBin-v5` shows the bin's depth image with its object regions (`regions`, 1 =
the largest); one step is one grasp in the camera frame, as in SuctionPick-v4. The reward counts
the objects carried to the receptacle; the episode ends when the bin is clear or after K failed
attempts in a row.
"""

import argparse

import gymnasium
import numpy as np

import suctionbench  # noqa: F401  (registers the environments)


def topmost_region_middle(observation: dict) -> np.ndarray:
    """The pixel nearest the centroid of the region closest to the camera, approached straight down."""
    depth, regions, k = observation["depth"], observation["regions"], observation["intrinsics"]
    labels = [r for r in np.unique(regions) if r > 0]
    if not labels:  # nothing seen in the bin: an empty action ends the attempt
        return np.zeros(6, dtype=np.float32)
    top = min(labels, key=lambda r: float(np.median(depth[regions == r])))
    rows, cols = np.nonzero(regions == top)
    nearest = np.argmin((rows - rows.mean()) ** 2 + (cols - cols.mean()) ** 2)
    v, u = rows[nearest], cols[nearest]
    z = float(depth[v, u])
    point = np.array([(u - k[0, 2]) * z / k[0, 0], (v - k[1, 2]) * z / k[1, 1], z])
    down = observation["camera_pose"][:3, :3].T @ np.array([0.0, 0.0, -1.0])
    return np.concatenate([point, down]).astype(np.float32)


def main(task: str = "bin-smoke", seed: int = 0) -> float:
    env = gymnasium.make("suctionbench/SuctionBin-v5", task=task)
    observation, info = env.reset(seed=seed)
    removed, terminated = 0.0, False
    while not terminated:
        observation, reward, terminated, truncated, step = env.step(topmost_region_middle(observation))
        removed += reward
        print(f"attempt {step['attempt']}: reward {reward:.0f}  failure {step['failure']}  left {step['remaining']}")
    env.close()
    print(f"removed {removed:.0f} of {len(info['in_bin'])} objects")
    return removed / len(info["in_bin"])


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="bin-smoke")
    parser.add_argument("--seed", type=int, default=0)
    main(**vars(parser.parse_args()))
