"""The pick's arrivals at the swinging cup (suctionbench.contact.arrival): each figure against an
independent derivation (closed forms, scipy's solve_ivp)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from suctionbench.config import CUP_DEFAULT, STANDARD_GRAVITY
from suctionbench.contact.arrival import (
    Arrival,
    min_jerk_at,
    quarter_swing_share,
    response_factor,
    table_support,
)
from suctionbench.contact.swing import Swing, _arrived_tilt

G = STANDARD_GRAVITY


def test_min_jerk_speed_halfway_and_ends():
    # s(u) = 10 u^3 - 15 u^4 + 6 u^5 is 1/2 at u = 1/2 (odd about it), where s' = 30 u^2 (1 - u)^2
    # = 30 / 16 = 1.875: the peak speed, 1.875 x the mean H / T. At both ends s' = 0.
    speed, _ = min_jerk_at(np.array([0.0, 0.075, 0.15, 0.3]), 0.15, 1.0)
    assert speed[1] == pytest.approx(1.875 * 0.15, rel=1e-9)
    assert speed[0] == pytest.approx(0.0, abs=1e-12) and speed[2] == pytest.approx(0.0, abs=1e-9)
    assert speed[3] == pytest.approx(0.0, abs=1e-9)  # beyond the lift: clipped to its end


def test_quarter_swing_share_is_the_damped_peak():
    # x'' + 2 zeta w x' + w^2 x = 0 from x = 0, x' = v0: its first maximum over the undamped v0 / w.
    zeta, w = 0.05, 10.0

    def top(_t, y):
        return y[1]

    top.terminal, top.direction = True, -1
    sol = solve_ivp(lambda _t, y: [y[1], -2 * zeta * w * y[1] - w * w * y[0]], (0, 5), [0.0, 1.0],
                    events=top, rtol=1e-11, atol=1e-13)
    assert quarter_swing_share(zeta) == pytest.approx(sol.y_events[0][0][0] * w, rel=1e-7)
    assert quarter_swing_share(0.0) == pytest.approx(1.0)


@pytest.mark.parametrize("ratio", [0.3, 1.0, 3.0, 20.0])
def test_response_factor_against_an_integration(ratio):
    # A linear oscillator (natural period T_n, zeta 0.05) driven from rest by a min-jerk move's
    # acceleration over T = ratio T_n, normalised to its peak 10 / sqrt 3, then left free for 1.5
    # periods (the hold): its largest displacement over its static displacement at the peak.
    # Slow motions follow statically (-> 1); a motion lasting about one period pumps the swing
    # past a step's 2 (the acceleration reverses half way).
    zeta, w = 0.05, 2 * math.pi  # T_n = 1

    def drive(t):
        u = t / ratio
        return (60 * u - 180 * u * u + 120 * u**3) / (10 / math.sqrt(3)) if u < 1 else 0.0

    sol = solve_ivp(lambda t, y: [y[1], w * w * (drive(t) - y[0]) - 2 * zeta * w * y[1]],
                    (0, ratio + 1.5), [0.0, 0.0], max_step=1e-3, rtol=1e-10, atol=1e-12)
    assert response_factor(np.array([ratio]), zeta)[0] == pytest.approx(sol.y[0].max(), rel=5e-3)
    assert response_factor(np.array([1.0]), zeta)[0] > 2.0
    assert response_factor(np.array([200.0]), zeta)[0] == pytest.approx(1.0, abs=0.01)


def test_table_support_is_the_resting_face():
    # A 4 x 2 x 1 cm box resting on its 4 x 2 face: its four bottom corners.
    hull = np.array([[x, y, z] for x in (-0.02, 0.02) for y in (-0.01, 0.01) for z in (0.0, 0.01)])
    support = table_support(hull, np.array([0.0, 0.0, -G]))
    assert len(support) == 4 and np.all(support[:, 2] == 0.0)


def _bar_arrival(mass, length, weight, transport=None):
    """A uniform bar along x (length, 1 cm square), lying on the table, as one Arrival row."""
    inertia = np.diag([mass * 2e-4 / 12, mass * (length**2 + 1e-4) / 12, mass * (length**2 + 1e-4) / 12])
    support = np.array([[x, y, -0.005] for x in (-length / 2, length / 2) for y in (-0.005, 0.005)])
    return Arrival(weight, transport, inertia, mass, support, 0.15, 1.0, 0.9, CUP_DEFAULT.axial_stiffness, 0.0)


def test_lift_off_rate_and_turning_point_of_a_bar():
    # A 0.1 kg bar, 20 cm long, held on its top face 4 cm from its centre (cup plane z = 5 mm
    # above the centre line). Lifted, it turns about its far bottom edge, L_p = 10 + 4 = 14 cm
    # from the grasp; it leaves the table at the swing's static tilt phi_s when the tool has risen
    # m g / k_a + L_p sin(phi_s), turning at v / (L_p cos phi_s) (v the min-jerk speed there), then
    # swings on the cup from phi_s with that rate: I phi'' = M(phi) - R(phi), I about the tilt axis
    # through the lip centre. Integrated without loss, its first turning point is the labeller's.
    cup = dataclasses.replace(CUP_DEFAULT, bellows_loss_factor=0.0)
    m, length, d = 0.1, 0.2, 0.04
    ring = np.array([[d, 0.0, 0.005]])
    com = np.zeros((1, 3))
    frame = np.diag([1.0, -1.0, -1.0])[None]  # approach straight down (contact z = -world z)
    weight = np.array([[0.0, 0.0, -m * G]])
    arrival = _bar_arrival(m, length, weight)
    swing = Swing(weight, com, ring, frame, cup)
    phi_s = swing.static_tilt()
    lever = length / 2 + d
    risen = m * G / cup.axial_stiffness + lever * math.sin(phi_s[0])
    expected_rate = float(min_jerk_at(np.array([risen]), 0.15, 1.0)[0][0]) / (lever * math.cos(phi_s[0]))
    rate, _ = arrival.lift_off(swing.n, phi_s, ring, com, frame)
    assert rate[0] == pytest.approx(expected_rate, rel=1e-9)

    inertia = float(arrival.inertia_about(swing.n, swing.r, frame)[0])
    assert inertia == pytest.approx(m * (length**2 + 1e-4) / 12 + m * (d * d + 0.005**2), rel=1e-9)

    def rhs(_t, y):
        return [y[1], float(swing.moment(np.array([y[0]]))[0]) / inertia]

    def top(_t, y):
        return y[1]

    top.terminal, top.direction = True, -1
    sol = solve_ivp(rhs, (0, 5), [phi_s[0], rate[0]], events=top, rtol=1e-11, atol=1e-13, max_step=1e-3)
    turned = _arrived_tilt(swing, phi_s, arrival, com, ring, frame, cup)
    assert turned[0] == pytest.approx(sol.y_events[0][0][0], rel=1e-6)
    # The step from rest at 0 would turn further: the bar arrives gentler than the bound.
    step = float(Swing(weight, com, ring, frame, cup).static_tilt()[0])
    assert phi_s[0] < turned[0] < 2.0 * step


def test_transport_swing_of_a_hanging_box():
    # A 0.2 kg, 6 cm cube held at the centre of its top face hangs straight (no tilt under its
    # weight, phi_0 = 0). The transport's inertial load m a(t), horizontal, min-jerk over 0.9 s
    # with peak 3.1 m/s^2, swings it; for small tilts below the bellows' stop the swing is linear:
    # I phi'' = -k phi + m |r| a(t) (k the swing's stiffness: the cup's series rate plus the
    # pendulum's m g |r|), whose peak the labeller reads as phi_s + (DAF - 1) (phi_u - phi_s)
    # from the step's turning point. Integrated directly (no loss), the peaks agree within the
    # small-angle error.
    cup = dataclasses.replace(CUP_DEFAULT, bellows_loss_factor=0.0)
    m, side, a_max, duration = 0.2, 0.06, 3.1, 0.9
    ring = np.array([[0.0, 0.0, side / 2]])
    com = np.zeros((1, 3))
    frame = np.diag([1.0, -1.0, -1.0])[None]
    weight = np.array([[0.0, 0.0, -m * G]])
    push = np.array([[-m * a_max, 0.0, 0.0]])  # the d'Alembert force of the cup accelerating along +x
    inertia_com = np.eye(3) * m * side * side / 6
    support = np.array([[x, y, -side / 2] for x in (-side / 2, side / 2) for y in (-side / 2, side / 2)])
    arrival = Arrival(weight, push, inertia_com, m, support, 0.15, 1.0, duration, cup.axial_stiffness, 0.0)
    swing = Swing(weight + push, com, ring, frame, cup)
    phi_s = swing.static_tilt()
    turned = float(_arrived_tilt(swing, phi_s, arrival, com, ring, frame, cup)[0])

    inertia = m * side * side / 6 + m * (side / 2) ** 2
    arm = side / 2

    def accel(t):
        u = t / duration
        return a_max * (60 * u - 180 * u * u + 120 * u**3) / (10 / math.sqrt(3)) if u < 1 else 0.0

    def rhs(t, y):
        returned = float(swing.returned(np.array([y[0]]))[0])
        return [y[1], (m * arm * (accel(t) * math.cos(y[0]) - G * math.sin(y[0])) - returned) / inertia]

    period = 2 * math.pi * math.sqrt(inertia / float(swing.stiffness(phi_s)[0]))
    sol = solve_ivp(rhs, (0, duration + 1.5 * period), [0.0, 0.0], max_step=1e-3, rtol=1e-10, atol=1e-12)
    assert turned == pytest.approx(sol.y[0].max(), rel=0.03)
    assert turned > phi_s[0]  # the swing overshoots its static tilt under the peak acceleration


def test_labeller_motion_is_the_episodes():
    # The labeller's arrivals are timed by the motion the simulated episode executes: its lift
    # height and time (EpisodeConfig: height / mean speed), and a lift acceleration equal to that
    # min-jerk lift's peak 5.774 H / T^2.
    from suctionbench.config import PerturbationConfig
    from suctionbench.sim.episode_config import EpisodeConfig

    episode, labels = EpisodeConfig(), PerturbationConfig.for_episode(CUP_DEFAULT)
    assert labels.lift_height == episode.lift_height
    assert labels.lift_time == pytest.approx(episode.lift_height / episode.lift_speed)
    assert labels.lift_acceleration == pytest.approx(10 / math.sqrt(3) * 0.15, rel=1e-12)
    assert labels.hold_time == episode.hold_time  # the planned swing is followed through the hold


def test_lip_wrench_at_the_bars_turning_point_is_newton_euler_with_its_inertia():
    # The bar of the lift-off test, at its first turning point phi_p (at rest, turning back): the
    # lip holds it against its weight f and turns it back with the angular acceleration alpha the
    # unbalanced moment gives its whole inertia about the tilt axis n through the lip centre,
    # I_n = n.I_c n + m |n x r|^2 = m (L^2 + 1e-4) / 12 + m |n x r|^2 (parallel axes), not the
    # centre of mass's share alone. From the object's side (Newton, Euler about the lip centre):
    # lip force F = f' - m alpha (n x r), moment M = r x f' - m alpha r x (n x r) - alpha I_c n, with
    # f' the load in the tilted frame and alpha I_n = n.(r x f') - R(phi_p).
    from suctionbench.contact.swing import _arrived_tilt, lip_load

    cup = dataclasses.replace(CUP_DEFAULT, bellows_loss_factor=0.0)
    m, length, d = 0.1, 0.2, 0.04
    ring = np.array([[d, 0.0, 0.005]])
    com = np.zeros((1, 3))
    frame = np.diag([1.0, -1.0, -1.0])[None]
    weight = np.array([[0.0, 0.0, -m * G]])
    arrival = _bar_arrival(m, length, weight)
    swing = Swing(weight, com, ring, frame, cup)
    phi = _arrived_tilt(swing, swing.static_tilt(), arrival, com, ring, frame, cup)
    n, r = swing.n[0], swing.r[0]
    f = swing.turned(phi)[0]
    inertia_c = frame[0].T @ arrival.inertia @ frame[0]  # the bar's, in the contact frame
    i_n = n @ inertia_c @ n + m * np.cross(n, r) @ np.cross(n, r)
    assert n @ inertia_c @ n == pytest.approx(m * (length**2 + 1e-4) / 12, rel=1e-9)  # n is the bar's y axis
    alpha = (float(swing.moment(phi)[0])) / i_n
    assert alpha < 0  # beyond its equilibrium: the cup turns it back
    want_force = f - m * alpha * np.cross(n, r)
    want_moment = np.cross(r, f) - m * alpha * np.cross(r, np.cross(n, r)) - alpha * inertia_c @ n
    wrench = lip_load(weight, com, ring, frame, cup, arrival)[0]
    np.testing.assert_allclose(wrench[:3], want_force, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(wrench[3:], want_moment, rtol=1e-9, atol=1e-12)
    assert n @ wrench[3:] == pytest.approx(float(swing.returned(phi)[0]), rel=1e-9)  # what the cup returns
    # The point-mass bound (no inertia known) turns it back harder by I_n / (m |n x r|^2): for this
    # bar held 4 cm off its centre 1 + (L^2 + 1e-4) / (12 |n x r|^2) = 3.1 (docs/physics.md, "What
    # the lip carries there": "3.1x").
    bound = m * float(swing.moment(phi)[0]) / (m * np.cross(n, r) @ np.cross(n, r))
    assert bound / (m * alpha) == pytest.approx(3.1, abs=0.05)
