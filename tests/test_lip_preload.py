"""The lip's preload from the surface shape under the ring (contact/wrench.py, "Lip preload").

The lip is a ring of springs of rate K / 2 pi per radian (K = cup.lip_rate = V / (0.5 lip_travel)
= 7964 N/m) between the bellows' end plane and the surface. The plane takes the profile's mean and
first harmonic; what remains, z(theta) (zero mean, zero first harmonic, positive away from the
cup), is fold the lip lacks there, so its pressure is p(theta) = p0 + p_x cos(theta) +
p_y sin(theta) - (K / 2 pi) z(theta) with 2 pi p0 = V + f_z and tau = pi r (p_y, -p_x). The lip stays
on while p >= 0 at every place theta_k:

    (V + f_z) + (2 / r)(tau_x sin theta_k - tau_y cos theta_k) >= K z_k.

Tested here: the closed form and the cone-program reference decide the same set on 10,000 random
wrenches with random lip profiles and on every place's half-space (on, inside, outside), a flat
profile gives back the ring's circle, and the largest mass a lying cylinder holds on a centred
grasp is (V - K z_max) / g with z_max from the cylinder's exact profile.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import trimesh
from test_wrench import force_and_com, random_cases

from suctionbench.config import CUP_DEFAULT, STANDARD_GRAVITY
from suctionbench.contact import SuctionLabeller
from suctionbench.contact.wrench import (
    external_wrench_at_contact,
    lip_angles,
    resists,
    resists_qp,
)

CUP = CUP_DEFAULT
K_PLACES = 48  # the seal model's lip samples (SealConfig.lip_samples)
THETA = lip_angles(K_PLACES)
N_RANDOM = 10_000
EPS = 1e-3


def random_profiles(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, K) lip profiles with zero mean and zero first harmonic: harmonics 2..6 with random
    phases and amplitudes, scaled so that K max(z) spans 0 to ~1.2 V (from a flat face to a
    cylinder the lip cannot hold even unloaded)."""
    orders = np.arange(2, 7)
    amp = rng.uniform(0.0, 1.0, (n, len(orders))) / orders**1.5
    phase = rng.uniform(0.0, 2 * np.pi, (n, len(orders)))
    z = (amp[:, :, None] * np.cos(orders[None, :, None] * THETA[None, None, :] + phase[:, :, None])).sum(axis=1)
    scale = rng.uniform(0.0, 1.2, n) * CUP.vacuum_force / CUP.lip_rate / np.abs(z).max(axis=1)
    return z * scale[:, None]


def qp(force, com, centre, frame, mu, heights) -> bool:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return bool(resists_qp(force, com, centre, frame, float(mu), CUP, lip_heights=heights)[0])


def place_slacks(alpha: np.ndarray, heights: np.ndarray) -> np.ndarray:
    """(n, K) slack of each place's half-space at alpha, in newtons."""
    f_n = alpha[:, 2] + CUP.vacuum_force
    lhs = f_n[:, None] + (2 / CUP.radius) * (
        alpha[:, 3, None] * np.sin(THETA) - alpha[:, 4, None] * np.cos(THETA)
    )
    return lhs - CUP.lip_rate * heights


_RANDOM: dict[str, dict] = {}


def random_results() -> dict:
    if not _RANDOM:
        rng = np.random.default_rng(20261124)
        force, com, centres, frames, mu = random_cases(CUP, N_RANDOM, 20261124)
        heights = random_profiles(rng, N_RANDOM)
        w_c = external_wrench_at_contact(force, com, centres, frames)
        closed = resists(w_c, mu, CUP, lip_heights=heights)
        ref = np.array([qp(force[i], com[i], centres[i], frames[i], mu[i], heights[i]) for i in range(N_RANDOM)])
        _RANDOM.update(w_c=w_c, mu=mu, heights=heights, closed=closed, qp=ref)
    return _RANDOM


def test_random_cases_exercise_the_lip_half_spaces():
    # Both verdicts occur, and in many cases a lip place's half-space is violated while the ring
    # circle of an evenly pressed lip is not: exactly the grasps the preload changes.
    data = random_results()
    share = data["closed"].mean()
    assert 0.2 <= share <= 0.8, share
    alpha = -data["w_c"]
    on_circle_only = resists(data["w_c"], data["mu"], CUP) & ~data["closed"]
    assert on_circle_only.sum() >= 200, on_circle_only.sum()
    # the closed form is exactly "every slack >= 0" (rows of place_slacks) plus the linear rows
    violated = (place_slacks(alpha, data["heights"]) < -1e-9 * CUP.vacuum_force).any(axis=1)
    assert not (data["closed"] & violated).any()


def test_closed_form_agrees_with_the_cone_program_on_random_wrenches():
    # Both decide whether alpha* = -w_c lies in F (the linear rows plus the K lip half-spaces):
    # they may differ only within ~1e-8 of the boundary, which random cases essentially never hit.
    data = random_results()
    disagree = np.flatnonzero(data["qp"] != data["closed"])
    assert len(disagree) <= N_RANDOM // 1000, disagree[:20]


def boundary_case(k: int, scale: float, rng: np.random.Generator):
    """A pull f_z = -0.3 V and a tilting moment that lifts the lip at place k, of magnitude
    `scale` times the largest place k allows, on the profile z = A cos(2 (theta - theta_k))
    (zero mean and first harmonic, deepest at k). Place k binds: its half-space reads
    (V + f_z) - (2 / r) |tau| >= K A, so |tau|_max = r (V + f_z - K A) / 2; at place j,
    Delta = theta_j - theta_k, the slack is (V + f_z)(1 - cos Delta) + K A (cos Delta - cos 2 Delta)
    > 0 on the boundary, so no other place binds."""
    v, r = CUP.vacuum_force, CUP.radius
    f_n = 0.7 * v
    amp = 0.5 * f_n / CUP.lip_rate
    heights = amp * np.cos(2 * (THETA - THETA[k]))
    tau = scale * r * (f_n - CUP.lip_rate * amp) / 2
    tau_xy = tau * np.array([-math.sin(THETA[k]), math.cos(THETA[k])])
    alpha = np.array([0.0, 0.0, f_n - v, tau_xy[0], tau_xy[1], 0.0])
    frame = trimesh.transformations.random_rotation_matrix(rng.random(3))[:3, :3]
    centre = rng.uniform(-0.05, 0.05, 3)
    force, com = force_and_com(alpha, frame, centre)
    return alpha, heights, force, com, centre, frame


@pytest.mark.parametrize("k", [0, 5, 13, 24, 47])
def test_each_place_boundary_on_inside_outside(k):
    rng = np.random.default_rng(k)
    for scale, expected in ((1.0, True), (1.0 - EPS, True), (1.0 + EPS, False)):
        alpha, heights, force, com, centre, frame = boundary_case(k, scale, rng)
        slack = place_slacks(alpha[None], heights[None])[0]
        others = np.delete(slack, k)
        assert (others > 0.01 * CUP.vacuum_force * EPS).all()  # only place k binds
        w_c = external_wrench_at_contact(force[None], com[None], centre[None], frame[None])
        assert resists(w_c, CUP.friction, CUP, lip_heights=heights[None])[0] == expected, scale
        assert qp(force, com, centre, frame, CUP.friction, heights) == expected, scale


def test_flat_profile_gives_back_the_ring_circle():
    # z = 0: the K half-spaces are the tangents of the circle ||tau|| <= r (V + f_z) / 2 at the K
    # bearings, i.e. the K-gon circumscribing it: a moment 1e-3 inside the circle is held at every
    # bearing, one 1e-3 outside the circumscribed polygon (1 / cos(pi / K) = 1.0021 x the circle)
    # is not, and a moment between them is held only between places.
    v, r = CUP.vacuum_force, CUP.radius
    flat = np.zeros((1, K_PLACES))
    for f_z in (-0.5 * v, 0.0, v):
        circle = r * (v + f_z) / 2
        for bearing in np.linspace(0.0, 2 * np.pi, 97):
            u = np.array([math.cos(bearing), math.sin(bearing)])
            for s, expected in ((1 - EPS, True), ((1 + EPS) / math.cos(math.pi / K_PLACES), False)):
                w_c = np.array([[0.0, 0.0, -f_z, *(s * circle * u), 0.0]])
                assert resists(w_c, CUP.friction, CUP, lip_heights=flat)[0] == expected
    between = np.array([[0.0, 0.0, 0.0, 0.0, 1.001 * r * v / 2, 0.0]])
    tau = -between[0, 3:5]  # alpha's moment; rotate it to fall half-way between two places
    half = math.pi / K_PLACES
    rot = np.array([[math.cos(half), -math.sin(half)], [math.sin(half), math.cos(half)]])
    between[0, 3:5] = -(rot @ tau)
    assert resists(between, CUP.friction, CUP, lip_heights=flat)[0]
    assert not resists(between, CUP.friction, CUP)[0]


def lying_cylinder(radius: float) -> trimesh.Trimesh:
    mesh = trimesh.creation.cylinder(radius=radius, height=0.10, sections=512)
    mesh.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, [0, 1, 0]))
    return mesh


@pytest.mark.parametrize("radius", [0.020, 0.025, 0.030])
def test_lying_cylinder_holds_up_to_the_mass_its_flanks_allow(radius):
    # A cylinder of radius R lying along x, grasped straight down on its top line, its centre of
    # mass on the cup's axis: no moment, the weight m g pulls straight off (f_z = -m g). The lip
    # circle lands at depth d(theta) = R - sqrt(R^2 - r^2 sin^2 theta) (theta from the cylinder's
    # axis), even in theta, so it has no first harmonic: z = d - mean(d). Its flanks (theta = 90 deg)
    # are where the lip lacks fold: p >= 0 there needs V - m g >= K z_max, so the heaviest cylinder
    # held is m* = (V - K z_max) / g (R = 20 mm: z_max = 0.77 mm, 0.184 kg; the 8 mm sag is
    # within lip_travel, no leak, so V is the full vacuum). A 0.14 kg D cell (R = 17 mm) is beyond
    # it (0.10 kg), which the ring circle alone (r (V - m g) / 2 > 0 for any m g < V) missed.
    r, v, k, g = CUP.radius, CUP.vacuum_force, CUP.lip_rate, STANDARD_GRAVITY
    theta = 2 * np.pi * np.arange(4096) / 4096
    d = radius - np.sqrt(radius**2 - (r * np.sin(theta)) ** 2)
    z_max = float((d - d.mean()).max())
    m_star = (v - k * z_max) / g
    assert 0.0 < m_star < v / g
    mesh = lying_cylinder(radius)
    grasp, down = np.array([[0.0, 0.0, radius]]), np.array([[0.0, 0.0, -1.0]])
    held = SuctionLabeller(mesh, mass=0.97 * m_star, com=np.zeros(3)).wrench_resistance(grasp, down)[0]
    dropped = SuctionLabeller(mesh, mass=1.03 * m_star, com=np.zeros(3)).wrench_resistance(grasp, down)[0]
    assert held and not dropped, (radius, m_star)


def test_d_cell_on_its_side_is_not_held_though_the_ring_circle_would_hold_it():
    # The agreement study's most common false positive before the preload: a D cell (R = 17 mm,
    # 0.14 kg) gripped on its side. z_max = 0.87 mm of missing fold asks K z_max = 6.9 N of the
    # lip's 7.96 - 1.37 = 6.6 N: the flanks open. Without the profile (the evenly pressed circle)
    # the same grasp resists.
    radius, mass = 0.017, 0.14
    labeller = SuctionLabeller(lying_cylinder(radius), mass=mass, com=np.zeros(3))
    grasp, down = np.array([[0.0, 0.0, radius]]), np.array([[0.0, 0.0, -1.0]])
    seal = labeller.seal(grasp, down)
    assert seal.seal[0]
    assert not labeller.wrench_resistance(grasp, down, seal)[0]
    frames = labeller.frames(grasp, down)
    w_c = external_wrench_at_contact(
        labeller.object.gravity_force[None], labeller.object.com[None], seal.ring_centre, frames
    )
    assert resists(w_c, CUP.friction, CUP, seal.vacuum_force)[0]
