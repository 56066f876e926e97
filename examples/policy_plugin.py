"""A suction policy plug-in: grasp the middle of the object's top surface.

    suctionbench eval --policy examples/policy_plugin.py:make_policy --policy-arg band=0.01 --set basic --trials 5
    suctionbench plan --depth scene.npy --camera primesense --policy examples/policy_plugin.py:make_policy

`make_policy` is the factory: `--policy-arg key=value` options arrive as its keyword arguments.
"""

import numpy as np

from suctionbench.policies.base import GraspAction, SamplerConfig, scene_cloud


class TopCentrePolicy:
    name = "top-centre"

    def __init__(self, band: float = 0.01):
        self.band = float(band)  # metres below the highest object point that count as "top"

    def plan(self, observation, rng: np.random.Generator) -> GraspAction:
        cloud = scene_cloud(observation, SamplerConfig())  # object pixels, normals, valid grasp pixels
        rows, cols = np.nonzero(cloud.valid)
        pixels, points, approaches = cloud.grasps_at(rows, cols)
        height = points @ cloud.table_normal  # up is the table normal
        top = height >= height.max() - self.band
        centre = points[top].mean(axis=0)
        distance = np.where(top, np.linalg.norm(points - centre, axis=1), np.inf)
        best = int(rng.choice(np.flatnonzero(distance == distance.min())))  # ties broken by the rng
        q = float(np.exp(-distance[best] / 0.01))  # 1 on the centre of the top, 1/e 1 cm away
        return GraspAction(point=points[best], approach=approaches[best], pixel=pixels[best], q=q,
                           camera_pose=observation.camera_pose, policy=self.name)


def make_policy(band: float = 0.01) -> TopCentrePolicy:
    return TopCentrePolicy(band=band)
