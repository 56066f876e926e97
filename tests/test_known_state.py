"""The known-state policies' candidates: the image bound (`analytic-image`) ranks only grasps the
camera sees, and ranking in the true state prefers a sealing grasp to a leaking one."""

from __future__ import annotations

import numpy as np
import trimesh

from suctionbench.config import CUP_DEFAULT
from suctionbench.policies.analytic import image_candidates, rank_grasps, uniform_density_com
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


def test_believing_uniform_density_moves_the_choice_to_the_shape_centre():
    # A 30 x 4 x 4 cm bar of 0.15 kg lying on the table (top face at z = 0.04 m), its mass weighted
    # towards one end: true centre of mass 8 cm along it from the shape's centre. The cup's vacuum
    # force is 60 kPa on its 5.5 mm inner radius, 5.7 N: right above the centre of mass it holds
    # the bar's 0.15 kg x (9.81 + 3.1 peak) m/s^2 = 1.9 N axially with the 1.5 safety factor to
    # spare, with no gravity moment. Above the shape's centre it must resist also 0.15 kg x 9.81
    # m/s^2 x 0.08 m = 0.118 N m, about three times what 5.7 N holds at the 7.5 mm lip (~0.04 N m),
    # so that grasp drops the bar. `analytic-image-uniform` believes the density
    # uniform: the centre of mass at the shape's, where it then expects no moment, so it chooses
    # the other grasp from the same two, and the truth calls that one not robust.
    mesh = trimesh.creation.box(extents=(0.3, 0.04, 0.04))
    mesh.apply_translation((0.0, 0.0, 0.02))
    true_com = np.array([0.08, 0.0, 0.02])
    points = np.array([[0.0, 0.0, 0.04], [0.08, 0.0, 0.04]])  # above the shape's centre, above the mass's
    approaches = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, -1.0]])
    belief = uniform_density_com(mesh)
    assert np.allclose(belief, (0.0, 0.0, 0.02))
    truth = rank_grasps(mesh, true_com, 0.15, CUP_DEFAULT, 0, points, approaches)
    blind = rank_grasps(mesh, belief, 0.15, CUP_DEFAULT, 0, points, approaches)
    assert truth.chosen_index == 1 and truth.score > 0.5 and truth.candidate_scores[0] < 0.5
    assert blind.chosen_index == 0 and blind.score > 0.5 and blind.candidate_scores[1] < 0.5
