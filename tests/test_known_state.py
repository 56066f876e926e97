"""The known-state policies' candidates: the image bound (`analytic-image`) ranks only grasps the
camera sees, and ranking in the true state prefers a sealing grasp to a leaking one."""

from __future__ import annotations

import numpy as np
import trimesh

from suctionbench.config import CUP_DEFAULT
from suctionbench.policies.analytic import image_candidates, rank_grasps
from suctionbench.sim.pick import PickRequest, PickRunner


def test_image_candidates_lie_on_the_surface_the_camera_sees():
    runner = PickRunner(PickRequest("basic/box_tea", policy="analytic-image", seed=3))
    runner.reset()
    mesh, _ = runner.posed_object()
    observation = runner.observe()
    points, approaches = image_candidates(observation, 300, np.random.default_rng(0))
    assert len(points) == 300
    # A depth pixel deprojects to the first surface its ray meets, read with the sensor's axial
    # noise (~1.3 mm at 0.6 m, sensing.noise): every candidate lies within a few sigma of the mesh
    # (6 mm allows 4.5 sigma) ...
    closest, distance, faces = trimesh.proximity.closest_point(mesh, points)
    assert distance.max() < 0.006
    # ... on a face turned towards the camera (the ray meets its outside), never on the hidden side ...
    camera = observation.camera_pose[:3, 3]
    facing = np.einsum("ij,ij->i", mesh.face_normals[faces], camera - closest)
    assert (facing > 0).all()
    # ... and approached from above within the seed sampler's 80 deg of straight down.
    assert (-approaches[:, 2] >= np.cos(np.radians(80.0)) - 1e-9).all()


def test_ranking_prefers_the_grasp_that_seals():
    # A 10 cm cube of 0.2 kg resting on the table (top face at z = 0.1 m). A cup centred on the top
    # face seals on flat material all round its lip; one centred on the top edge has half its lip
    # over air, so no seal forms and every metric scores it 0. The ranking must take the first.
    mesh = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    mesh.apply_translation((0.0, 0.0, 0.05))
    points = np.array([[0.05, 0.0, 0.1], [0.0, 0.0, 0.1]])  # on the edge, then the face's centre
    approaches = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, -1.0]])
    chosen = rank_grasps(mesh, mesh.center_mass, 0.2, CUP_DEFAULT, 0, points, approaches)
    assert chosen.chosen_index == 1 and chosen.score > 0.5
    assert chosen.candidate_scores[0] == 0.0
