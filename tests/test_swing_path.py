"""The planned pick's swing followed in time (contact/swing_path.py) against what is exact."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from suctionbench.config import CUP_DEFAULT, STANDARD_GRAVITY
from suctionbench.contact.arrival import Arrival
from suctionbench.contact.swing import Swing
from suctionbench.contact.swing_path import swing_through

G = STANDARD_GRAVITY
SIDE = 0.06
FRAME = np.diag([1.0, -1.0, -1.0])[None]  # a grasp straight down: z into the object
RING = np.array([[0.0, 0.0, SIDE / 2]])  # the centre of the cube's top face
SUPPORT = np.array([[x, y, -SIDE / 2] for x in (-SIDE / 2, SIDE / 2) for y in (-SIDE / 2, SIDE / 2)])


def _cube(mass, com, a_peak, duration, cup, lift_height=0.15, hold=0.5):
    """A cube of `mass` held at the centre of its top face, centre of mass `com` (1, 3), carried
    along +x at peak `a_peak` over `duration` after a 1 s lift of `lift_height`."""
    weight = np.array([[0.0, 0.0, -mass * G]])
    push = np.array([[-mass * max(a_peak, 1e-9), 0.0, 0.0]])  # -m a: the cup accelerates along +x
    arrival = Arrival(weight, push, np.eye(3) * mass * SIDE * SIDE / 6, mass, SUPPORT, lift_height, 1.0,
                      duration, cup.axial_stiffness, cup.swing_damping_ratio, planned=True,
                      transport_peak=a_peak, hold_time=hold)
    swing = Swing(weight, com, RING, FRAME, cup)
    return swing, arrival, swing_through(swing, arrival, com, RING, FRAME, cup)[0]


def test_a_slow_transport_holds_the_static_swing_at_its_peak_load():
    # Quasi-static: in a transport lasting 40 natural periods of the swing (T_n = 2 pi sqrt(I / k),
    # ~0.37 s for this cube) the tilt follows the load's equilibrium, and at the peak acceleration
    # the lip carries the cup's return at the static tilt of m (g - a_peak) (`Swing.static_tilt`
    # of that load), the most of the carry. Not quite without loss: a min-jerk acceleration starts
    # as a ramp, a'(0) = 10.4 a_peak / T, and a ramp c t sets a swing ringing about its equilibrium
    # with amplitude (dphi/da) c / omega (0.018 rad at T = 7 s, 8 % of the static tilt; an exact
    # integration of the lossless swing peaks at 0.230 rad against the static 0.211); the
    # silicone's loss (zeta = 0.05) damps it by exp(-zeta omega 0.21 T) = 0.07 by the peak, and its
    # own moment c phi' is ~1e-4 of the return there.
    cup = CUP_DEFAULT
    mass, a_peak = 0.2, 3.1
    com = np.zeros((1, 3))
    loaded = Swing(np.array([[-mass * a_peak, 0.0, -mass * G]]), com, RING, FRAME, cup)
    inertia = mass * SIDE * SIDE / 6 + mass * (SIDE / 2) ** 2
    period = 2 * math.pi * math.sqrt(inertia / float(loaded.stiffness(np.zeros(1))[0]))
    _, _, (lift, carry) = _cube(mass, com, a_peak, 40 * period, cup)
    expected = float(loaded.returned(loaded.static_tilt())[0])
    assert math.hypot(carry[3], carry[4]) == pytest.approx(expected, rel=0.02)
    assert math.hypot(lift[3], lift[4]) == pytest.approx(0.0, abs=1e-9)  # centred: the lift does not tip it


@pytest.mark.parametrize("duration", [0.3, 0.9])
def test_transport_swing_against_an_accurate_integration(duration):
    # The same cube carried in about one natural period (0.3 s) and in 0.9 s: the swing is dynamic
    # (it overshoots its static tilt and rings after the braking). The reference integrates the
    # exact one-axis pendulum, I phi'' = m h (a(t) cos phi - g sin phi) - R(phi), h = SIDE / 2 the
    # centre of mass below the lip, I about the lip centre, with a tight-tolerance Runge-Kutta
    # through the transport and the hold; its largest tilt sets the largest return R, which the
    # lip carries at the carry's worst instant (lossless: the swing turns there, at rest). The
    # 2 ms semi-implicit (symplectic Euler) step must agree within 3 %.
    cup = dataclasses.replace(CUP_DEFAULT, bellows_loss_factor=0.0)
    mass, a_peak, hold = 0.2, 3.1, 0.5
    swing, _, (_, carry) = _cube(mass, np.zeros((1, 3)), a_peak, duration, cup, hold=hold)
    inertia, arm = mass * SIDE * SIDE / 6 + mass * (SIDE / 2) ** 2, SIDE / 2

    def accel(t):
        u = t / duration
        return a_peak * (60 * u - 180 * u * u + 120 * u**3) / (10 / math.sqrt(3)) if u < 1 else 0.0

    def rhs(t, y):
        tilt = abs(y[0])
        returned = math.copysign(float(swing.returned(np.array([tilt]))[0]), y[0])
        return [y[1], (mass * arm * (accel(t) * math.cos(y[0]) - G * math.sin(y[0])) - returned) / inertia]

    sol = solve_ivp(rhs, (0.0, duration + hold), [0.0, 0.0], max_step=1e-3, rtol=1e-10, atol=1e-12)
    largest = float(np.abs(sol.y[0]).max())
    assert math.hypot(carry[3], carry[4]) == pytest.approx(float(swing.returned(np.array([largest]))[0]), rel=0.03)


def test_an_off_centre_grasp_lifted_gently_hangs_at_its_static_tilt():
    # Held 2 cm beside its centre of mass, the cube hangs at the weight's static tilt phi_s
    # (`Swing.static_tilt`). Lifted 1 mm in 1 s it leaves the table turning at ~0.002 rad/s: no
    # swing to speak of; with no transport the lip carries the cup's return R(phi_s) throughout the
    # carry, here with the silicone's loss (it has nothing to damp).
    cup = CUP_DEFAULT
    com = np.array([[0.02, 0.0, 0.0]])
    swing, _, (_, carry) = _cube(0.2, com, 0.0, 0.9, cup, lift_height=0.001)
    phi_s = swing.static_tilt()
    assert phi_s[0] > 0.05
    assert math.hypot(carry[3], carry[4]) == pytest.approx(float(swing.returned(phi_s)[0]), rel=0.01)


def test_each_row_swings_on_its_own():
    # Rows are samples of one batch stepped on one clock, each from its own lift-off time: a row
    # must come out as it does alone (a row waiting for its lift-off once drifted at its start
    # rate, tripling a perturbed brick's lift moment).
    cup = CUP_DEFAULT
    mass = 0.2
    com = np.array([[0.02, 0.0, 0.0], [0.0, 0.005, 0.0], [-0.012, 0.01, 0.0]])
    weight = np.tile([0.0, 0.0, -mass * G], (3, 1))
    push = np.tile([-mass * 3.1, 0.0, 0.0], (3, 1))
    ring, frames = np.repeat(RING, 3, axis=0), np.repeat(FRAME, 3, axis=0)
    arrival = Arrival(weight, push, np.eye(3) * mass * SIDE * SIDE / 6, mass, SUPPORT, 0.15, 1.0,
                      np.array([0.8, 1.0, 1.3]), cup.axial_stiffness, cup.swing_damping_ratio, planned=True,
                      transport_peak=3.1, hold_time=0.5)
    together = swing_through(Swing(weight, com, ring, frames, cup), arrival, com, ring, frames, cup)
    for row in range(3):
        one = slice(row, row + 1)
        alone = swing_through(Swing(weight[one], com[one], ring[one], frames[one], cup), arrival.take(one),
                              com[one], ring[one], frames[one], cup)
        lift_off = arrival.take(one).lift_off(Swing(weight[one], com[one], ring[one], frames[one], cup).n,
                                              np.zeros(1), ring[one], com[one], frames[one])[1]
        assert lift_off[0] > 0.0
        np.testing.assert_allclose(together[row], alone[0], rtol=0.02, atol=1e-6)


def test_the_trace_holds_the_returned_worst_instants():
    # `trace` reports the lip's wrench at every step of the swing the function integrates, and the
    # wrench it returns for each phase is formed at one of those steps from the same state: so
    # the lift's (before the lift's 1 s) and the carry's (after it) are each found, to rounding,
    # among the traced steps of their phase. An off-centre grasp, so both phases tip the lip.
    cup = CUP_DEFAULT
    mass, com = 0.2, np.array([[0.012, 0.004, 0.0]])
    weight = np.array([[0.0, 0.0, -mass * G]])
    push = np.array([[-mass * 3.1, 0.0, 0.0]])
    arrival = Arrival(weight, push, np.eye(3) * mass * SIDE * SIDE / 6, mass, SUPPORT, 0.15, 1.0, 0.6,
                      cup.axial_stiffness, cup.swing_damping_ratio, planned=True, transport_peak=3.1, hold_time=0.5)
    steps = []
    out = swing_through(Swing(weight, com, RING, FRAME, cup), arrival, com, RING, FRAME, cup,
                        trace=lambda t, w, active: steps.append((t, w[0].copy(), bool(active[0]))))
    lift = [w for t, w, active in steps if active and t < 1.0]
    carry = [w for t, w, active in steps if active and t >= 1.0]
    assert len(carry) > 500  # 0.6 s of transport and 0.5 s of hold at 2 ms
    for traced, returned in ((lift, out[0, 0]), (carry, out[0, 1])):
        assert math.hypot(returned[3], returned[4]) > 1e-3  # the lip is tipped: not a trivial match
        assert min(np.abs(w - returned).max() for w in traced) < 1e-12
