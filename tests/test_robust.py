"""Wrench resistance against gravity and the robust (Monte-Carlo) label, with derived expectations.

Default cup: V = 60 kPa x pi (6.5 mm)^2 = 7.96 N over the effective area (payload V / g = 0.81 kg).
Its tilt (peel) limit is the ring-pressure circle ||(tau_x, tau_y)|| <= r (V + f_z) / 2: 29.9 mN m
with no axial load, r (V - m g) / 2 with the object's weight m g pulling along the approach.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from conftest import box
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

from suctionbench.config import STANDARD_GRAVITY, LabelConfig, PerturbationConfig
from suctionbench.contact import METRICS, SuctionLabeller
from suctionbench.contact.robust import arrivals, sample_perturbations
from suctionbench.contact.swing import lip_load
from suctionbench.contact.wrench import resists
from suctionbench.errors import InputError
from suctionbench.geometry.sampling import sample_surface_grasps
from suctionbench.geometry.shapes import superellipsoid

DOWN = np.array([[0.0, 0.0, -1.0]])


def test_flat_face_centre_resists_gravity_until_the_payload(cup):
    # Top-face centre of a box, COM straight below: gravity pulls along v with no torque and no
    # tangential force, so the only active constraint is suction, f_z = -m g >= -V: resisted iff
    # m <= V / g = 7.96 N / 9.81 m/s^2 = 0.81 kg.
    mesh = box((0.12, 0.08, 0.04))
    payload = cup.vacuum_force / STANDARD_GRAVITY
    for mass, holds in ((0.3, True), (0.99 * payload, True), (1.01 * payload, False), (1.0, False)):
        labeller = SuctionLabeller(mesh, mass=mass)
        assert labeller.wrench_resistance([[0, 0, 0.02]], DOWN)[0] == holds, mass


def test_long_heavy_bar_drops_off_centre_but_holds_at_its_centre(cup):
    # A 30 x 4 x 4 cm bar of 0.3 kg (2.94 N < V) gripped on its top (a long side face). At the
    # centre the COM is on the cup axis: no torque, pull 2.94 N < 7.96 N: held. 10 cm off-centre
    # the weight exerts 0.10 m x 2.94 N = 0.29 N m about the contact, over 15 times the ring limit
    # r (V - m g) / 2 = 7.5 mm x 5.02 N / 2 = 18.8 mN m: the lip peels and the bar drops. Under
    # perturbation the centre grasp still holds in most samples (COM noise 2.5 mm and 0.1 rad of
    # object rotation about the COM 2 cm below shift the lever by ~3 mm, ~9 mN m per axis), while
    # the far one never does.
    labeller = SuctionLabeller(box((0.30, 0.04, 0.04)), mass=0.3)
    points = np.array([[0.0, 0.0, 0.02], [0.10, 0.0, 0.02]])
    approaches = np.repeat(DOWN, 2, axis=0)
    seal = labeller.seal(points, approaches)
    assert seal.seal.all()  # both are flat-face seals: the failure is the wrench, not the seal
    assert labeller.wrench_resistance(points, approaches).tolist() == [True, False]
    torque = 0.10 * 0.3 * STANDARD_GRAVITY
    limit = cup.radius * (cup.vacuum_force - 0.3 * STANDARD_GRAVITY) / 2.0
    assert limit == pytest.approx(0.0188, abs=1e-4)
    assert torque > 15 * limit
    rwr, _ = labeller.robust(points, approaches, seed=3)
    assert rwr[0] > 0.5 and rwr[1] == 0.0


def test_side_grasp_needs_friction_against_gravity(cup):
    # Grasp on a vertical face, v horizontal: gravity is tangential, so friction must carry it,
    # sqrt(3) m g <= mu (f_z + V) with f_z = 0 (no load along v): m <= mu V / (sqrt(3) g) = 0.23 kg
    # at mu = 0.5. The tilting torque about the contact, m g times the 2 cm lever to the COM, must
    # also stay within the ring limit r V / 2 = 29.9 mN m (f_z = 0): m <= 0.0299 / (0.02 g) =
    # 0.152 kg. So on a cup rigid in bending 0.14 kg holds, 0.17 kg does not (peel, well before
    # friction gives).
    # The cup bends instead (bellows k_b and lip ring k_l = K r^2 / 2 in series): it cannot hold
    # m g d (27 mN m at 0.14 kg) at any tilt below its stop (it returns at most k_b t_max =
    # 12.1 mN m there), so a cube above ~0.07 kg droops past it, where the squeezed wall (k_st)
    # joins the bellows, in series with the lip: R(t) = k_c (t - t_max k_st / (k_b + k_st)),
    # k_c = 1 / (1 / k_l + 1 / (k_b + k_st)).
    # Turned by t the weight has the moment m g d cos t about the lip, a pull m g sin t along the
    # approach and a shear m g cos t. Resting (the load applied slowly, swing_overshoot off) at
    # m g d cos t = R(t), the ring holds iff R(t) <= r (V - m g sin t) / 2: the heaviest cube is
    # m* = 0.159 kg (friction, sqrt(3) m g cos t <= mu (V - m g sin t), allows more). Applied at
    # once (the default) the droop overshoots into the stop and the catch peels the lip of far
    # lighter cubes: held at 0.03 kg, dropped already at 0.9 m*.
    mesh = box((0.04, 0.04, 0.04))
    point, approach = np.array([[0.02, 0.0, 0.0]]), np.array([[-1.0, 0.0, 0.0]])
    assert cup.radius * cup.vacuum_force / 2 / (0.02 * STANDARD_GRAVITY) == pytest.approx(0.152, abs=1e-3)
    rigid = LabelConfig(cup=dataclasses.replace(cup, bellows_swing=False))
    assert SuctionLabeller(mesh, rigid, mass=0.14).wrench_resistance(point, approach)[0]
    assert not SuctionLabeller(mesh, rigid, mass=0.17).wrench_resistance(point, approach)[0]
    stop, k_b, k_st = cup.approach_tolerance, cup.bending_stiffness, cup.stop_stiffness
    k_lip = 0.5 * cup.lip_rate * cup.radius**2
    k_c = 1.0 / (1.0 / k_lip + 1.0 / (k_b + k_st))
    assert k_b * stop < 0.1 * STANDARD_GRAVITY * 0.02 * math.cos(stop * (1 + k_b / k_lip))  # 0.1 kg: past the stop

    def returned(t: float) -> float:
        return k_c * (t - stop * k_st / (k_b + k_st))

    def margin(m: float) -> float:
        w = m * STANDARD_GRAVITY
        t = brentq(lambda t: w * 0.02 * math.cos(t) - returned(t), stop, 0.5 * math.pi)
        return cup.radius * (cup.vacuum_force - w * math.sin(t)) / 2 - returned(t)

    heaviest = brentq(margin, 0.1, 0.3)
    assert heaviest == pytest.approx(0.159, abs=1e-3)
    slow = LabelConfig(cup=dataclasses.replace(cup, swing_overshoot=False))
    assert SuctionLabeller(mesh, slow, mass=0.97 * heaviest).wrench_resistance(point, approach)[0]
    assert not SuctionLabeller(mesh, slow, mass=1.03 * heaviest).wrench_resistance(point, approach)[0]
    assert SuctionLabeller(mesh, LabelConfig(), mass=0.03).wrench_resistance(point, approach)[0]
    assert not SuctionLabeller(mesh, LabelConfig(), mass=0.9 * heaviest).wrench_resistance(point, approach)[0]


@pytest.fixture(scope="module")
def soap():
    return superellipsoid((0.10, 0.07, 0.05), exponent=0.3, count=40)


def test_same_seed_same_labels_and_batch_independence(soap):
    labeller = SuctionLabeller(soap, mass=0.15)
    points, approaches = sample_surface_grasps(soap, 60, np.random.default_rng(0))
    a, sa = labeller.robust(points, approaches, seed=11)
    b, sb = labeller.robust(points, approaches, seed=11)
    np.testing.assert_array_equal(sa, sb)
    c, _ = labeller.robust(points, approaches, seed=12)
    assert not np.array_equal(a, c)  # a different seed draws different perturbations
    # A grasp's label depends on (seed, grasp id) only, not on the batch it is computed in.
    d, _ = labeller.robust(points[7:9], approaches[7:9], seed=11, grasp_ids=np.array([7, 8]))
    np.testing.assert_array_equal(a[7:9], d)


def test_robust_label_is_the_composition_of_its_parts(soap):
    # rwr = mean_j [seal_j and resist_j]: recompute each sample's seal with the full (unstaged)
    # seal model and its wrench test (on the load the bellows' swing leaves as the object tips off
    # the table, with the vacuum that
    # seal holds) separately, then compose, and compare with the fast path.
    labeller = SuctionLabeller(soap, mass=0.15)
    points, approaches = sample_surface_grasps(soap, 40, np.random.default_rng(1))
    rwr, outcomes = labeller.robust(points, approaches, seed=5)
    samples = sample_perturbations(
        points, labeller.frames(points, approaches), labeller.object, labeller.config.cup,
        labeller.config.perturbation, seed=5,
    )
    seal = labeller.seal_model.evaluate(samples.points, samples.frames)
    assert samples.loads.shape == (len(samples.points), 1, 3)  # no inertial load by default
    (lift,) = arrivals(labeller.object, labeller.config.perturbation, labeller.config.cup, samples.force,
                       samples.inertial)  # the lift-off is the only load case
    wrench = lip_load(samples.force, samples.com, seal.ring_centre, samples.frames, labeller.config.cup, lift)
    resisted = resists(wrench, samples.friction, labeller.config.cup, seal.vacuum_force, seal.lip_heights)
    composed = (seal.seal & resisted).reshape(outcomes.shape)
    np.testing.assert_array_equal(outcomes, composed)
    np.testing.assert_array_equal(rwr, composed.mean(axis=1))
    assert 0.0 < rwr.mean() < 1.0  # both outcomes occur, so the comparison means something


def test_reference_path_agrees_with_the_fast_path(soap):
    labeller = SuctionLabeller(soap, mass=0.15)
    points, approaches = sample_surface_grasps(soap, 8, np.random.default_rng(2))
    # include two good top-face grasps so that positives are compared too
    points = np.vstack([points, [[0.0, 0.0, 0.025], [0.005, 0.0, 0.025]]])
    approaches = np.vstack([approaches, DOWN, DOWN])
    fast, fast_samples = labeller.robust(points, approaches, seed=9)
    ref, ref_samples = labeller.robust(points, approaches, seed=9, reference=True)
    np.testing.assert_array_equal(fast_samples, ref_samples)
    assert fast_samples.any()


def test_labels_are_invariant_to_a_rigid_motion_of_object_and_grasp(soap):
    # Moving mesh, grasps, centre of mass and gravity by the same rigid transform changes
    # nothing physical; frames (x toward the COM) and perturbations (drawn in contact frames)
    # move along. Only single-precision ray casting (~1e-7 m) differs, so stretches agree to
    # 1e-4 and discrete outcomes agree except for samples that sit on a threshold.
    rng = np.random.default_rng(3)
    points, approaches = sample_surface_grasps(soap, 80, rng)
    rot = Rotation.random(random_state=4).as_matrix()
    shift = np.array([0.3, -0.2, 0.5])
    moved = soap.copy()
    moved.apply_transform(np.block([[rot, shift[:, None]], [np.zeros((1, 3)), np.ones((1, 1))]]))
    gravity = np.array([0.0, 0.0, -STANDARD_GRAVITY])
    a = SuctionLabeller(soap, mass=0.1)
    b = SuctionLabeller(moved, mass=0.1, com=rot @ a.object.com + shift, gravity=rot @ gravity)
    la = a.label(points, approaches, seed=21)
    lb = b.label(points @ rot.T + shift, approaches @ rot.T, seed=21)
    finite = np.isfinite(la.seal.max_stretch)
    np.testing.assert_array_equal(finite, np.isfinite(lb.seal.max_stretch))
    np.testing.assert_allclose(la.seal.max_stretch[finite], lb.seal.max_stretch[finite], atol=1e-4)
    clear = ~finite | (np.abs(la.seal.max_stretch - 0.1) > 1e-3)
    np.testing.assert_array_equal(la.seal.seal[clear], lb.seal.seal[clear])
    np.testing.assert_array_equal(la.wr[clear], lb.wr[clear])
    assert (la.samples == lb.samples).mean() >= 0.995
    assert np.abs(la.rwr - lb.rwr).max() <= 0.04
    assert la.seal.seal.any() and la.rwr.max() > 0


def test_metric_scores_are_ordered_and_bounded(soap):
    labeller = SuctionLabeller(soap, mass=0.15)
    points, approaches = sample_surface_grasps(soap, 100, np.random.default_rng(4))
    labels = labeller.label(points, approaches, seed=0)
    for name in METRICS:
        score = labels.score(name)
        assert score.shape == (100,) and np.all((score >= 0) & (score <= 1)), name
    # SS ranks by stretch, and is 0.5 exactly at the stretch limit (so > 0.5 means "seals" for
    # the stretch check alone).
    ss = labels.score("ss")
    order = np.argsort(labels.seal.max_stretch)
    assert np.all(np.diff(ss[order]) <= 1e-12)
    assert np.all((ss > 0.5) == (labels.seal.max_stretch < 0.1))
    # WR needs a seal, and a robust label above 0 needs some sample to seal.
    assert not np.any(labels.wr & ~labels.seal.seal)
    # PC3D is zero on non-planar patches (RMS deviation over 1 mm).
    assert np.all(labels.score("pc3d")[labels.seal.planarity_rms > 1e-3] == 0.0)
    with pytest.raises(InputError, match="unknown"):
        labeller.label(points, approaches, seed=0, metrics=("nope",))


def test_paper_preset_uses_the_papers_literal_constants():
    # V = 250 N: a 5 kg object hangs from a centred top grasp (49 N < 250 N), but kappa = 0.005
    # allows only pi r kappa / sqrt(2) = 83 uN m of tilting torque, so 1 mm of COM offset under
    # 1 kg (9.8 mN m) already fails.
    from suctionbench.config import CUP_PAPER

    mesh = box((0.12, 0.08, 0.04))
    config = LabelConfig(cup=CUP_PAPER)
    assert SuctionLabeller(mesh, config, mass=5.0).wrench_resistance([[0, 0, 0.02]], DOWN)[0]
    off = SuctionLabeller(mesh, config, mass=1.0, com=[0.001, 0.0, 0.0])
    assert not off.wrench_resistance([[0, 0, 0.02]], DOWN)[0]


def test_bad_object_parameters_are_rejected(soap):
    for kwargs in ({"mass": -1.0}, {"mass": float("nan")}, {"com": [0.0, np.nan, 0.0]}):
        with pytest.raises(InputError):
            SuctionLabeller(soap, **kwargs)
    labeller = SuctionLabeller(soap)
    with pytest.raises(InputError, match="unit vector"):
        labeller.seal([[0, 0, 0.025]], [[0, 0, 0]])
    with pytest.raises(InputError):
        PerturbationConfig(num_samples=0)


def test_grasp_sampler_is_uniform_by_area_with_inward_normals(rng):
    # Box 10 x 6 x 2 cm: the top face holds 60 / (2 (60 + 20 + 12)) = 32.6 % of the area, so
    # about that share of uniform samples lands on it with approach (0, 0, -1) (inward).
    mesh = box((0.10, 0.06, 0.02))
    points, approaches = sample_surface_grasps(mesh, 4000, rng)
    on_top = np.isclose(points[:, 2], 0.01)
    share = 60.0 / (2 * (60.0 + 20.0 + 12.0))
    assert abs(on_top.mean() - share) < 4 * math.sqrt(share * (1 - share) / 4000)
    np.testing.assert_allclose(approaches[on_top], np.tile([0.0, 0.0, -1.0], (on_top.sum(), 1)))
    _, distance, _ = mesh.nearest.on_surface(points)
    assert distance.max() < 1e-9
