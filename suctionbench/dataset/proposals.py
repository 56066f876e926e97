"""On-policy datapoints: the grasps a trained network itself would choose, labelled.

Why. A GQ-CNN is trained on grasps sampled uniformly on the surface but judged where its maximum
over thousands of candidates lands, and a maximum finds the network's errors: the shipped model
picked a pentagonal prism's ridge at q 0.8 whose label was 0.0-0.08, a D cell at q 0.9 that drops.
Such grasps are rare among uniform samples and common among a policy's choices. Labelling the
grasps a trained network ranks highest on the training objects' images and training on them beside
the uniform ones is data aggregation (Ross, Gordon and Bagnell 2011, "DAgger"): the next network
sees its predecessor's mistakes with their labels.

`Proposer` runs the dense policy (`fc-gqcnn`) of a trained model on a generated image (the noisy
depth, the camera and the object's pixels from the clean render, as the benchmark's simulated
segmentation gives them: the noisy image's depth scale error lifts the table by up to ~1 cm, which a
height threshold would take for object) and keeps its best
`per_image` pixels at least `spacing` apart (the top of a quality map is one blob; the next
maxima are other places). Their grasp points come from the noisy image at their pixels and their
approaches from its normals, exactly what the policy would execute; `generate_unit` labels them in
the object's frame with the same labeller as the uniform grasps.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.errors import InputError

PROPOSAL_SPACING = 0.01
"""Proposals of one image lie at least this far apart (m), about the cup's diameter."""


def model_fingerprint(model_dir: str | Path) -> str:
    """The proposing model's weights checksum (its model card's `weights_sha256`): what the
    dataset's configuration fingerprint records, so a resumed run with other weights is refused."""
    from suctionbench.learning.checkpoint import read_model_card

    try:
        card = read_model_card(model_dir)
    except InputError as exc:
        raise InputError(f"--proposals '{model_dir}': not a trained model ({exc})") from None
    if not isinstance(card.get("weights_sha256"), str):
        raise InputError(f"--proposals '{model_dir}': not a trained model (its card has no weights_sha256)")
    return card["weights_sha256"]


def spaced_top(q: np.ndarray, points: np.ndarray, count: int, spacing: float) -> np.ndarray:
    """Indices of up to `count` candidates in order of falling q, each at least `spacing` (m) from
    every one chosen before (greedy non-maximum suppression)."""
    chosen: list[int] = []
    for i in np.argsort(-np.asarray(q), kind="stable"):
        if len(chosen) >= count:
            break
        if chosen and np.min(np.linalg.norm(points[chosen] - points[i], axis=1)) < spacing:
            continue
        chosen.append(int(i))
    return np.asarray(chosen, dtype=np.intp)


class Proposer:
    """The dense policy of one trained model, proposing grasps on generated images."""

    def __init__(self, model_dir: str, per_image: int, spacing: float = PROPOSAL_SPACING) -> None:
        from suctionbench.policies.fc_gqcnn import make_fc_gqcnn_policy

        self.policy = make_fc_gqcnn_policy(model_dir, refine=0)  # only the dense q is read: no exact re-scoring
        self.per_image, self.spacing = per_image, spacing

    def propose(self, depth: np.ndarray, mask: np.ndarray, intrinsics: Any, camera_pose: np.ndarray,
                rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Points (K, 3) and approaches (K, 3) in the camera frame of the policy's K <= per_image
        best spaced grasps on the image `depth` whose object pixels are `mask` (none where it
        finds no grasp)."""
        from suctionbench.policies.base import NoGraspError, Observation

        observation = Observation(depth=depth, intrinsics=intrinsics, camera_pose=camera_pose, mask=mask)
        try:
            action = self.policy.plan(observation, rng)
        except NoGraspError:
            return np.zeros((0, 3)), np.zeros((0, 3))
        cands = action.candidates
        keep = spaced_top(cands["q"], cands["points"], self.per_image, self.spacing)
        return cands["points"][keep], cands["approaches"][keep]


@functools.lru_cache(maxsize=2)
def proposer(model_dir: str, per_image: int) -> Proposer:
    """One `Proposer` per worker process and model (the network loads once)."""
    return Proposer(model_dir, per_image)
