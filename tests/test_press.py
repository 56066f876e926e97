"""The touch-down's statics (suctionbench.contact.press): does the object stay put under the press?
Each case against a hand derivation of the rigid body on the table."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
import trimesh

from suctionbench.config import CUP_DEFAULT, STANDARD_GRAVITY, LabelConfig, PerturbationConfig
from suctionbench.contact import SuctionLabeller
from suctionbench.contact.press import Footprint, stays_put

G = STANDARD_GRAVITY
DOWN = np.array([0.0, 0.0, -G])


def lying_cylinder(radius: float = 0.033, length: float = 0.2) -> trimesh.Trimesh:
    """A cylinder on its side, axis along x, a line of vertices at the bottom (its support)."""
    mesh = trimesh.creation.cylinder(radius=radius, height=length, sections=64)
    mesh.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, [0, 1, 0]))
    return mesh


def flank(angle_deg: float, radius: float = 0.033) -> tuple[np.ndarray, np.ndarray]:
    """A grasp on a lying cylinder's flank, `angle_deg` from its top, along the inward normal."""
    a = math.radians(angle_deg)
    outward = np.array([0.0, math.sin(a), math.cos(a)])
    return radius * outward[None], -outward[None]


@pytest.mark.parametrize("mu", [0.3, 0.5, 0.8])
def test_a_lying_cylinder_rolls_beyond_twice_the_lips_friction_angle(mu):
    # Cylinder of radius R on its side, touching the table along a line L below its axis; the lip
    # presses at angle a from the top along the normal (through the axis). The object stays only
    # if the lip's force can pass through L (a line support carries no moment, and the weight acts
    # through L): the chord from the grasp to L makes the angle a / 2 with the radius (inscribed
    # angle), and the lip's friction tilts its force by up to atan(mu) from the normal. So it stays
    # for a < 2 atan(mu) and rolls beyond, whatever the press and the weight (a light bottle).
    mesh = lying_cylinder()
    footprint = Footprint(mesh.convex_hull.vertices, DOWN)
    limit = math.degrees(2 * math.atan(mu))
    weight = 0.0145 * DOWN
    for angle, expected in [(0.0, True), (limit - 2.0, True), (limit + 2.0, False)]:
        point, approach = flank(angle)
        assert stays_put(point, approach, np.zeros(3), weight[None], 6.0, mu, 0.6, footprint)[0] == expected, angle


def test_a_box_pressed_straight_down_anywhere_on_its_top_stays():
    # A vertical press anywhere over the footprint puts the resultant of press and weight inside
    # it: no tipping; a vertical force cannot slide it.
    mesh = trimesh.creation.box((0.2, 0.1, 0.05))
    footprint = Footprint(mesh.convex_hull.vertices, DOWN)
    xs = np.linspace(-0.099, 0.099, 7)
    points = np.column_stack([xs, np.zeros_like(xs), np.full_like(xs, 0.025)])
    approaches = np.tile([0.0, 0.0, -1.0], (len(xs), 1))
    assert stays_put(points, approaches, np.zeros(3), np.tile(0.05 * DOWN, (len(xs), 1)), 6.0, 0.5, 0.6,
                     footprint).all()


def test_a_tall_box_pushed_sideways_tips_above_the_height_the_statics_give():
    # A box of width 2b = 0.06 m, mass m, pushed horizontally (+x) at height h on its face by the
    # lip (friction mu). It slides once the push N exceeds the table's friction: with the lip
    # pressing down by up to mu N, N = mu_t (m g + mu N), so N_s = mu_t m g / (1 - mu_t mu). Below
    # that the press is capped at N_s. About the far bottom edge, the push tips with N h, the lip's
    # downward friction holds with mu N 2b (it acts on the near face, 2b from the edge) and the
    # weight with m g b: it tips once N_s (h - 2 mu b) > m g b, i.e. above
    # h* = 2 mu b + m g b / N_s.
    b, height, mass, mu, mu_t = 0.03, 0.3, 0.2, 0.5, 0.6
    mesh = trimesh.creation.box((2 * b, 2 * b, height))
    mesh.apply_translation([0, 0, height / 2])
    footprint = Footprint(mesh.convex_hull.vertices, DOWN)
    weight = mass * DOWN
    slide = mu_t * mass * G / (1 - mu_t * mu)
    critical = 2 * mu * b + mass * G * b / slide
    com = np.array([0.0, 0.0, height / 2])
    for h, expected in [(critical - 0.01, True), (critical + 0.01, False)]:
        point = np.array([[-b, 0.0, h]])
        assert stays_put(point, np.array([[1.0, 0.0, 0.0]]), com, weight[None], 6.0, mu, mu_t, footprint)[0] == expected


def test_pressing_an_overhang_tips_the_object():
    # A 4 x 4 x 2 cm base with a light 20 x 4 x 1 cm plank on top, centred: the plank overhangs the
    # base by 8 cm on each side. Pressed straight down at the plank's end (x = 0.1 m, 3 cm above
    # the table), it tips about the base's edge (x = 0.02 m) once the press's moment N x 0.08 m
    # beats the weight's m g x 0.02 m and the lip's friction, which can pull the plank's end back
    # horizontally with up to mu N at 0.03 m above the edge: N > m g 0.02 / (0.08 - 0.03 mu).
    base = trimesh.creation.box((0.04, 0.04, 0.02))
    base.apply_translation([0, 0, 0.01])
    plank = trimesh.creation.box((0.2, 0.04, 0.01))
    plank.apply_translation([0, 0, 0.025])
    mesh = trimesh.util.concatenate([base, plank])
    footprint = Footprint(mesh.convex_hull.vertices, DOWN)
    mass, mu = 0.1, 0.5
    point, approach = np.array([[0.1, 0.0, 0.03]]), np.array([[0.0, 0.0, -1.0]])
    com = np.array([0.0, 0.0, 0.02])
    threshold = mass * G * 0.02 / (0.08 - 0.03 * mu)
    assert stays_put(point, approach, com, (mass * DOWN)[None], 0.95 * threshold, mu, 0.6, footprint)[0]
    assert not stays_put(point, approach, com, (mass * DOWN)[None], 1.05 * threshold, mu, 0.6, footprint)[0]


def test_the_labeller_calls_a_rolled_bottle_pushed_away_only_with_the_press():
    # The episode's labeller presses (PerturbationConfig.for_episode); the paper's quasi-static
    # model does not. A grasp 60 deg from the top of a light lying cylinder (beyond 2 atan 0.5 =
    # 53 deg) is pushed away under the first and seals under the second.
    mesh = lying_cylinder()
    point, approach = flank(60.0)
    episode = SuctionLabeller(mesh, LabelConfig.for_episode(CUP_DEFAULT), mass=0.0145)
    paper = SuctionLabeller(mesh, LabelConfig(), mass=0.0145)
    pressed, quasi = episode.seal(point, approach), paper.seal(point, approach)
    assert quasi.seal[0]
    assert not pressed.seal[0] and pressed.failure_names[0] == "pushed_away"
    top_point, top_approach = flank(0.0)
    assert episode.seal(top_point, top_approach).seal[0]
    # the nominal wrench resistance asks the same seal, press included, whether or not it is given one
    assert not episode.wrench_resistance(point, approach)[0]
    assert episode.wrench_resistance(top_point, top_approach)[0] == episode.wrench_resistance(
        top_point, top_approach, episode.seal(top_point, top_approach))[0]


def test_the_labellers_press_is_the_episodes_touch_down():
    # The press is the episode's: its guarded approach stops at EpisodeConfig.compression_stop of
    # the bellows, and the object lies on the scene's table (SceneConfig.friction; MuJoCo takes the
    # larger of two coefficients and the objects' are at most 0.5).
    from suctionbench.sim.episode_config import EpisodeConfig
    from suctionbench.sim.scene import SceneConfig

    labels = PerturbationConfig.for_episode(CUP_DEFAULT)
    assert labels.press_compression == EpisodeConfig().compression_stop
    assert labels.table_friction == SceneConfig().friction
    assert PerturbationConfig().press_compression == 0.0  # the paper's model has no press


def lying_tube_and_bore_line() -> tuple[trimesh.Trimesh, np.ndarray]:
    """A lying paper-towel core (R_o = 22, R_i = 19 mm, along x, its axis through the origin) and
    the unit direction (1, 3) from its axis to the bore's wall 30 deg past the bore's bottom."""
    outer = trimesh.creation.cylinder(radius=0.022, height=0.22, sections=64)
    inner = trimesh.creation.cylinder(radius=0.019, height=0.24, sections=64)
    tube = outer.difference(inner)
    tube.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, [0, 1, 0]))
    a = math.radians(30.0)
    return tube, np.array([[0.0, -math.sin(a), -math.cos(a)]])


def test_the_press_acts_where_the_lip_lands_not_at_a_target_behind_a_surface():
    # A target inside a lying tube's bore (R_o = 22, R_i = 19 mm), on the bore's wall 30 deg past
    # its bottom, approached along that wall's inward direction (through the tube's axis): the cup
    # meets the outer wall 30 deg from the top first and seals there (the seal model's rays start
    # outside the object), so it presses there, its force along the normal through the axis,
    # which the lip's friction need only tilt by half the grasp's angle, 15 deg < atan(0.5) = 26.6
    # deg, to pass through the tube's line of support: it stays put. Pressed at the target, the
    # chord to the support line lies ~90 deg off the force: it would roll away.
    tube, out = lying_tube_and_bore_line()
    target, approach = 0.019 * out, out
    labeller = SuctionLabeller(tube, LabelConfig.for_episode(CUP_DEFAULT), mass=0.064)
    seal = labeller.seal(target, approach)
    assert seal.seal[0], seal.failure_names[0]
    crown = -0.022 * out[0]
    assert np.linalg.norm(seal.ring_centre[0] - crown) < 2e-3  # where the lip lands (less its sag)
    assert not labeller.stays_put(target, approach)[0]


def test_the_perturbed_presses_act_where_each_lip_lands():
    # The robust label's samples press where each perturbed lip lands, as the nominal label does.
    # A target inside the lying tube's bore and the crown point on the same approach line are one
    # grasp: the seal model casts from outside the object, so both land the lip on the crown; the
    # samples are drawn in the nominal contact frame from the same (seed, grasp id) stream, so each
    # pair of samples shifts both lines alike and lands where the other does (the approach's own
    # rotation is left out: it turns each line about its own target, 41 mm apart along it, and so
    # would move the two lips apart). Their robust labels are therefore equal, sample by sample.
    # Pressed at the bore's targets instead (the code before), 21 of the 50 samples differed.
    tube, out = lying_tube_and_bore_line()
    config = LabelConfig.for_episode(CUP_DEFAULT)
    config = replace(config, perturbation=replace(config.perturbation, approach_rotation_std=0.0))
    labeller = SuctionLabeller(tube, config, mass=0.064)
    bore, bore_samples = labeller.robust(0.019 * out, out, seed=3, grasp_ids=np.array([0]))
    crown, crown_samples = labeller.robust(-0.022 * out, out, seed=3, grasp_ids=np.array([0]))
    assert crown[0] > 0.0  # some samples hold: the equality below is not two zeros
    np.testing.assert_array_equal(bore_samples, crown_samples)
