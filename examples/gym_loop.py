"""A gymnasium loop with a hand-written policy: grasp the object's middle, straight down.

    .venv/bin/python examples/gym_loop.py --episodes 5 --seed 0

The environment `suctionbench/SuctionPick-v4` shows an overhead depth image with the object's
mask; one step is one grasp: a point and an approach direction in the camera frame (OpenCV: x
right, y down, z along the optical axis). Reward 1 for a successful pick, else 0.
"""

import argparse

import gymnasium
import numpy as np

import suctionbench  # noqa: F401  (registers suctionbench/SuctionPick-v4)


def middle_straight_down(observation: dict) -> np.ndarray:
    """The object pixel nearest the mask's centroid, deprojected; the approach is world "down"."""
    depth, mask, k = observation["depth"], observation["mask"].astype(bool) & (observation["depth"] > 0), \
        observation["intrinsics"]
    rows, cols = np.nonzero(mask)
    if len(rows) == 0:  # the object is out of view: any action ends the attempt
        return np.zeros(6, dtype=np.float32)
    nearest = np.argmin((rows - rows.mean()) ** 2 + (cols - cols.mean()) ** 2)
    v, u = rows[nearest], cols[nearest]
    z = float(depth[v, u])
    point = np.array([(u - k[0, 2]) * z / k[0, 0], (v - k[1, 2]) * z / k[1, 1], z])
    down = observation["camera_pose"][:3, :3].T @ np.array([0.0, 0.0, -1.0])  # world -z in the camera frame
    return np.concatenate([point, down]).astype(np.float32)


def main(episodes: int = 3, seed: int = 0, object_set: str = "basic") -> float:
    env = gymnasium.make("suctionbench/SuctionPick-v4", object_set=object_set)
    successes = 0.0
    for episode in range(episodes):
        observation, info = env.reset(seed=seed + episode)
        observation, reward, terminated, truncated, info = env.step(middle_straight_down(observation))
        successes += reward
        print(f"episode {episode}: {info['object']:28s} reward {reward:.0f}  failure {info['failure']}")
    env.close()
    print(f"success rate {successes / episodes:.2f} over {episodes} episodes")
    return successes / episodes


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--set", dest="object_set", default="basic")
    main(**vars(parser.parse_args()))
