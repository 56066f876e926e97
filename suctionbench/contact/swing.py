"""The bellows' swing: the wrench the lip carries for a load on the held object.

A bellows is soft in bending, so a load whose moment tips the lip does not hold the object
rigidly: object and lip swing together, as a pendulum, and the lip carries the cup's return at the
swing's turning point or its static equilibrium (`Swing`, `lip_load`), or, where the pick's motion
is planned, at the worst instants of the swing followed in time (contact/swing_path.py). Whether
the lip then holds that wrench is contact/wrench.py's (`resists`).
"""

from __future__ import annotations

import math

import numpy as np

from suctionbench.config import CupConfig
from suctionbench.contact.arrival import Arrival, quarter_swing_share, response_factor
from suctionbench.contact.swing_path import swing_through
from suctionbench.contact.wrench import external_wrench_at_contact

SWING_BISECTIONS = 36
"""Bisection steps of the swing's tilts: the bracket [0, pi/2] shrinks to ~2e-11 rad."""

SWING_CAP = 0.5 * math.pi
"""Largest tilt (rad) the swing is solved over: far beyond where any lip peels (the lip's tilt
past the stop reaches the ring's limit within (r V / 2 - k_b theta_max) / k_c = 0.13 rad for the
default cup)."""


class Swing:
    """The cup's swing as a one-axis pendulum: the load's moment about the tilt axis n at the
    object's tilt phi is A cos(phi) - B sin(phi), the cup returns R(phi). At the static
    equilibrium (`static_tilt`) the object feels the same force, turned with it about the lip
    centre (`turned`); `lip_load` judges the lip there or at the swing's first turning point.

    Why. A bellows is soft in bending (k_b = cup.bending_stiffness, 0.032 N m/rad by default), so a
    load whose moment tips the lip does not hold the object rigidly: the object and the lip swing
    together, as a pendulum, until the moment about the lip centre has fallen to what the bent
    cup returns. A heavy box held at the centre of its top face and carried sideways at
    a = 3.1 m/s^2 would, rigidly, put m a d (41 mN m for 0.37 kg with its centre 4 cm below the
    lip) on a lip that holds r (V - m g) / 2 = 16 mN m; swung it hangs along g - a and the lip
    carries ~8 mN m.

    The cup's return R(phi) at the object's tilt phi (`returned`): the bellows (k_b) and the
    lip ring (k_l = cup.lip_tilt_stiffness, 0.22 N m/rad: its springs, which the ring-pressure
    limit already assumes elastic) in series, k_s = k_b k_l / (k_b + k_l), until the bellows
    reaches its tilt stop theta_max = cup.approach_tolerance (one side of the wall at full stroke)
    at phi_stop = theta_max (1 + k_b / k_l). Beyond it the folded wall itself is squeezed
    (k_st = cup.stop_stiffness, 0.35 N m/rad) beside the bellows' spring, both in series with the
    lip: R rises at k_c = 1 / (1 / k_l + 1 / (k_b + k_st)) = 0.14 N m/rad, 5x the swing's 0.028.

    Derivation (contact frame, z = approach, arm r = c - o from the lip centre o to the centre of
    mass, force f). The in-plane moment tau = (r x f)_xy tips the lip about n = tau / |tau|. Tilting
    the object by phi about n turns a fixed external force, seen from the object, by -phi
    about n (Rodrigues: f cos phi - (n x f) sin phi + n (n.f)(1 - cos phi)); its moment about
    n becomes A cos phi - B sin phi with A = |tau| and B = r.f - (n.f)(n.r) (B > 0 for a
    hanging load: the pendulum's restoring term). Equilibrium: A cos phi - B sin phi = R(phi),
    solved by bisection on [0, pi/2] (the left side less R is A >= 0 at 0 and falls with phi for
    B >= 0). Twisting moments (about z) are not relieved: the bellows is stiff in torsion. Left
    out: the bellows' own tilt from sealing on a face off the approach (its moment k_b alpha, and
    the range it leaves). The swing's dynamics (a suddenly applied load overshoots the static
    tilt) are `lip_load`'s.
    """

    def __init__(self, force: np.ndarray, com: np.ndarray, ring_centre: np.ndarray, frames: np.ndarray,
                 cup: CupConfig, axis: np.ndarray | None = None):
        self.f = np.einsum("nji,nj->ni", frames, force)
        self.r = np.einsum("nji,nj->ni", frames, np.asarray(com, dtype=float) - ring_centre)
        tau = np.cross(self.r, self.f)
        if axis is None:  # the load's own tilt axis
            self.a = np.hypot(tau[:, 0], tau[:, 1])
            self.tips = self.a > 1e-15
            self.n = np.zeros_like(self.f)
            self.n[self.tips, :2] = tau[self.tips, :2] / self.a[self.tips, None]
        else:  # another load's axis (in the cup plane): this load's moment about it, tilting the other way if < 0
            self.n = np.asarray(axis, dtype=float)
            self.a = np.einsum("ni,ni->n", tau, self.n)
            self.tips = self.a > 1e-15
        self.n_f = np.einsum("ni,ni->n", self.n, self.f)
        self.b = np.einsum("ni,ni->n", self.r, self.f) - self.n_f * np.einsum("ni,ni->n", self.n, self.r)
        self.k, self.k_lip, self.theta_max = cup.bending_stiffness, cup.lip_tilt_stiffness, cup.approach_tolerance
        self.k_stop = cup.stop_stiffness
        self.k_series = self.k * self.k_lip / (self.k + self.k_lip)
        self.k_caught = 1.0 / (1.0 / self.k_lip + 1.0 / (self.k + self.k_stop))
        self.phi_stop = self.theta_max * (1.0 + self.k / self.k_lip)

    def returned(self, phi: np.ndarray) -> np.ndarray:
        """The cup's return R(phi): bellows and lip in series up to the stop; beyond it the stop
        (k_st) joins the bellows: R = k_c (phi - theta_max k_st / (k_b + k_st)), k_c the lip in
        series with k_b + k_st (continuous at phi_stop, where R = k_b theta_max)."""
        return np.where(phi <= self.phi_stop, self.k_series * phi,
                        self.k_caught * (phi - self.theta_max * self.k_stop / (self.k + self.k_stop)))

    def stored(self, phi: np.ndarray) -> np.ndarray:
        """Energy the cup stores at tilt phi (the integral of R): the bellows', the stop's and the
        lip's, each carrying R (the lip tilts by R / k_l, the bellows by the rest)."""
        lip = self.returned(phi) / self.k_lip
        bellows = phi - lip
        squeezed = np.maximum(bellows - self.theta_max, 0.0)
        return 0.5 * (self.k * bellows * bellows + self.k_stop * squeezed * squeezed + self.k_lip * lip * lip)

    def moment(self, phi: np.ndarray) -> np.ndarray:
        """The load's moment about n at tilt phi, less the cup's return."""
        return self.a * np.cos(phi) - self.b * np.sin(phi) - self.returned(phi)

    def work(self, phi: np.ndarray) -> np.ndarray:
        """Work done by the load from rest at 0 to phi, less the cup's stored energy: the swing's
        kinetic energy at phi when the load is applied at once."""
        return self.a * np.sin(phi) + self.b * (np.cos(phi) - 1.0) - self.stored(phi)

    def turned(self, phi: np.ndarray) -> np.ndarray:
        """The load seen from the object tilted by phi about n (contact frame)."""
        c, s = np.cos(phi)[:, None], np.sin(phi)[:, None]
        return self.f * c - np.cross(self.n, self.f) * s + self.n * self.n_f[:, None] * (1.0 - c)

    def stiffness(self, phi: np.ndarray) -> np.ndarray:
        """The swing's stiffness at phi, -d moment / d phi: the cup's return rate (k_s below the
        stop, k_c beyond) plus the pendulum's A sin(phi) + B cos(phi)."""
        rate = np.where(phi <= self.phi_stop, self.k_series, self.k_caught)
        return rate + self.a * np.sin(phi) + self.b * np.cos(phi)

    def static_tilt(self) -> np.ndarray:
        """Equilibrium tilt: moment(phi) = 0 on [0, SWING_CAP] (SWING_CAP if none)."""
        cap = np.full_like(self.a, SWING_CAP)
        phi = _bisect(self.moment, np.zeros_like(self.a), cap)
        phi = np.where(self.moment(cap) > 0.0, cap, phi)
        return np.where(self.tips, phi, 0.0)


def _bisect(fn, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """Vectorised bisection of fn, positive at `low` and not at `high`."""
    for _ in range(SWING_BISECTIONS):
        mid = 0.5 * (low + high)
        right = fn(mid) > 0.0
        low, high = np.where(right, mid, low), np.where(right, high, mid)
    return 0.5 * (low + high)


def lip_load(
    force: np.ndarray, com: np.ndarray, ring_centre: np.ndarray, frames: np.ndarray, cup: CupConfig,
    arrival: Arrival | None = None,
) -> np.ndarray:
    """The wrench (N, 6) the lip must carry (external wrench about the ring centre, contact frame,
    as `wrench.resists` takes it) for a load `force` (N, 3) at `com`.

    A cup rigid in bending (`cup.bellows_swing` off) carries the load as it is; with
    `cup.swing_overshoot` off the lip carries the swing's static equilibrium (`Swing`).

    The swing's first turning point (default). The load does not arrive slowly: it meets the lip
    as the object tips off the table (a brick's tilt built up over ~0.2 s in the simulation) and as
    the transport's acceleration rises (~0.2 s), about one swing period (0.2-0.65 s for the basic
    objects above 0.15 kg). With `arrival` (the pick's motion and the object's inertia and support,
    contact/arrival.py) the swing follows the two arrivals: from the lift-off's speed, or from rest
    at the weight's tilt as the transport's acceleration rises. Without it, the bound: whatever the
    load's history, as long as it grows from zero without reversing, an undamped spring-mass system
    swings furthest when the whole load comes at once (a dynamic amplification of 2 for a linear
    spring). From rest at phi = 0 the swing then turns where the load's work equals the cup's
    stored energy (energy conservation, `Swing.work`):

        A sin(phi_u) + B (cos(phi_u) - 1) = int_0^phi_u R,

    the first root beyond the equilibrium phi_s (small angles, below the stop: phi_u = 2 phi_s).
    The silicone's loss leaves a share D = exp(-pi zeta / sqrt(1 - zeta^2)) of the overshoot,
    zeta = eta / 2 (`CupConfig.swing_overshoot_fraction`): phi_p = phi_s + D (phi_u - phi_s). At
    phi_p the object is momentarily at rest, so the lip carries the cup's return R(phi_p) about n,
    and what turns the object back: Newton about the lip centre, I_n alpha = M_n - R(phi_p),
    M_n = A cos(phi_p) - B sin(phi_p). The centre of mass accelerates by alpha (n x r) and the
    object's angular momentum about the lip centre changes by m alpha r x (n x r) + alpha I_c n,
    so the lip carries (Newton and Euler, the object at rest)

        force:  f(phi_p) - m alpha (n x r)
        moment: r x f(phi_p) - m alpha r x (n x r) - alpha I_c n,

    whose part along n is R(phi_p); at phi_s both reduce to the static swing. With the pick's
    arrivals the object's inertia is known (`Arrival.inertia`, about its centre of mass, I_c):
    I_n = n . I_c n + m |n x r|^2 (parallel axes). Without (the bound), all the mass at the centre
    of mass: I_c = 0, the largest angular acceleration any mass distribution can have.

    The stop's catch. A swing that reaches the bellows' stop with speed left is caught by the
    squeezed wall and the lip (`Swing`: R rises at 0.14 N m/rad instead of the swing's 0.028):
    the energy it still carries there goes into them, the lip's moment rises steeply, and a fast
    swing peels it. A box_shoe held 26 mm off its centre of mass reaches the
    stop with ~7 mJ and, caught, needs ~36 mN m of its lip (the ring holds ~24); the simulated lip
    opened ~9 deg beyond the stopped bellows and peeled. A slow arrival is caught within the
    ring's limit.
    """
    force = np.asarray(force, dtype=float)
    if not cup.bellows_swing:
        return external_wrench_at_contact(force, com, ring_centre, frames)
    swing = Swing(force, com, ring_centre, frames, cup)
    phi_p = swing.static_tilt()  # the static swing: the formula below with nothing unbalanced
    if cup.swing_overshoot and arrival is not None:
        phi_p = np.where(swing.tips, _arrived_tilt(swing, phi_p, arrival, com, ring_centre, frames, cup), 0.0)
    elif cup.swing_overshoot:
        phi_s, share = phi_p, cup.swing_overshoot_fraction
        phi_u = _turning_tilt(swing.work, phi_s)
        phi_p = np.where(swing.tips, phi_s + share * (phi_u - phi_s), 0.0)
    f = swing.turned(phi_p)
    torque = np.cross(swing.r, f)
    unbalanced = np.where(swing.tips, np.minimum(swing.moment(phi_p), 0.0), 0.0)
    arm = np.cross(swing.n, swing.r)
    arm2 = np.einsum("ni,ni->n", arm, arm)
    if arrival is None:  # a point mass (docstring): m alpha = (M_n - R) / |n x r|^2
        spin = np.where(arm2 > 1e-12, unbalanced / np.maximum(arm2, 1e-12), 0.0)[:, None]
        return np.concatenate([f - spin * arm, torque - spin * np.cross(swing.r, arm)], axis=1)
    own = arrival.inertia_along(swing.n, frames)  # I_c n, contact frame
    inertia = np.einsum("ni,ni->n", swing.n, own) + arrival.mass * arm2  # arrival.inertia_about, arm2 at hand
    alpha = np.where(inertia > 1e-15, unbalanced / np.maximum(inertia, 1e-15), 0.0)[:, None]
    spin = arrival.mass * alpha  # m alpha
    return np.concatenate([f - spin * arm, torque - spin * np.cross(swing.r, arm) - alpha * own], axis=1)


def lip_loads(
    loads: np.ndarray, com: np.ndarray, ring_centre: np.ndarray, frames: np.ndarray, cup: CupConfig,
    cases: list[Arrival] | None = None,
) -> np.ndarray:
    """(N, L, 6) the wrench the lip carries in each of the L load cases `loads` (N, L, 3) at `com`
    (`lip_load`, with each case's arrival `cases[l]`, None for the step bound). Where the pick's
    motion is planned (`Arrival.planned`) the swing is followed in time once for all cases
    (contact/swing_path.py: the lift's worst instant, then the carry's)."""
    if cases is not None and cases[0].planned and cup.bellows_swing and cup.swing_overshoot:
        swing = Swing(cases[0].weight, com, ring_centre, frames, cup)
        return swing_through(swing, cases[-1], np.broadcast_to(com, swing.f.shape), ring_centre, frames, cup)
    return np.stack([lip_load(loads[:, case], com, ring_centre, frames, cup, None if cases is None else cases[case])
                     for case in range(loads.shape[1])], axis=1)


def _turning_tilt(energy, phi_s: np.ndarray) -> np.ndarray:
    """Where the swing's kinetic energy `energy(phi)` (positive at phi_s, falling beyond it) runs
    out on [phi_s, SWING_CAP] (SWING_CAP if it never does)."""
    cap = np.full_like(phi_s, SWING_CAP)
    return np.where(energy(cap) > 0.0, cap, _bisect(energy, phi_s, cap))


def _lift_turn(swing: Swing, phi_s: np.ndarray, arrival: Arrival, com: np.ndarray, ring_centre: np.ndarray,
               frames: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The swing's first turning point after the lift-off (contact/arrival.py), less the
    silicone's loss over that quarter swing; with the moment of inertia about n and the lift-off's
    time into the lift."""
    inertia = arrival.inertia_about(swing.n, swing.r, frames)
    rate, time = arrival.lift_off(swing.n, phi_s, ring_centre, com, frames)
    start = swing.work(phi_s) - 0.5 * inertia * rate * rate
    turn = _turning_tilt(lambda p: swing.work(p) - start, phi_s)
    return phi_s + quarter_swing_share(arrival.zeta) * (turn - phi_s), inertia, time


def _arrived_tilt(swing: Swing, phi_s: np.ndarray, arrival: Arrival, com: np.ndarray, ring_centre: np.ndarray,
                  frames: np.ndarray, cup: CupConfig) -> np.ndarray:
    """The swing's first turning point for the pick's arrivals (contact/arrival.py): the lift
    leaves the table at phi_s turning at the lift-off's rate; a transport starts at the weight's
    tilt, the inertial load arriving with the transport's response factor, on top of what is left
    of the lift's swing."""
    com = np.broadcast_to(np.asarray(com, dtype=float), swing.f.shape)
    if arrival.transport_force is None:
        return _lift_turn(swing, phi_s, arrival, com, ring_centre, frames)[0]
    inertia = arrival.inertia_about(swing.n, swing.r, frames)
    still = Swing(arrival.weight, com, ring_centre, frames, cup, axis=swing.n).static_tilt()
    rest = swing.work(still)
    step = _turning_tilt(lambda p: swing.work(p) - rest, phi_s)  # the step's turning point from phi_0
    period = 2.0 * np.pi * np.sqrt(inertia / np.maximum(swing.stiffness(phi_s), 1e-12))
    factor = response_factor(arrival.transport_time / np.maximum(period, 1e-12), arrival.zeta)
    carried = np.where(still < phi_s, phi_s + (factor - 1.0) * (step - phi_s), phi_s)
    hanging = Swing(arrival.weight, com, ring_centre, frames, cup)
    hang = hanging.static_tilt()
    peak, hang_inertia, lifted_at = _lift_turn(hanging, hang, arrival, com, ring_centre, frames)
    omega = np.sqrt(hanging.stiffness(hang) / np.maximum(hang_inertia, 1e-15))
    ringing = (peak - hang) * np.exp(-arrival.zeta * omega * (arrival.lift_time - lifted_at))
    ringing *= np.abs(np.einsum("ni,ni->n", hanging.n, swing.n))
    return carried + np.where(hanging.tips, ringing, 0.0)
