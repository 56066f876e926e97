"""Wrench resistance under the suction-ring contact model (Dex-Net 3.0, "Wrench Space Analysis"
and the appendix "Suction Contact Model").

Contact frame: origin at the centre of the contact ring, z = v (into the object), x and y in the
cup plane. The contact applies to the object the wrench alpha = (f_x, f_y, f_z, tau_x, tau_y,
tau_z) in that frame, on top of the vacuum pull V toward the cup; the lip's normal force is
f_N = f_z + V. V is the vacuum force the seal actually holds (full vacuum x effective area for a
tight seal, less when the lip leaks: see seal.py and suctionbench.vacuum). The admissible set F:

    friction   sqrt(3)|f_x| <= mu f_N,  sqrt(3)|f_y| <= mu f_N,  sqrt(3)|tau_z| <= r mu f_N
    tilt       ||(tau_x, tau_y)|| <= r f_N / 2                     (ring pressure, default)
               f_N + (2/r)(tau_x sin t_k - tau_y cos t_k) >= K z_k (the lip's preload, below)
               sqrt(2)|tau_x|, sqrt(2)|tau_y| <= pi r kappa         (the paper's box, cup.kappa set)
    suction    f_z >= -V

The tilt limit, derived from the paper's own ring-pressure model (appendix "Suction Contact
Model", assumptions 3-4): the lip presses on the object with p(theta) = p0 + p_x cos(theta) +
p_y sin(theta) per unit angle round the ring of radius r. Its resultant is
f_N = int p dtheta = 2 pi p0 = V + f_z, and its moment about the ring centre is
tau_x = int r sin(theta) p dtheta = pi r p_y, tau_y = -int r cos(theta) p dtheta = -pi r p_x. A lip
can only push: p(theta) >= 0 for every theta, and min_theta p = p0 - sqrt(p_x^2 + p_y^2), so the
lip stays on iff sqrt(p_x^2 + p_y^2) <= p0, i.e.

    ||(tau_x, tau_y)|| = pi r sqrt(p_x^2 + p_y^2) <= pi r p0 = r (V + f_z) / 2.

One circle (a second-order cone in alpha), shrinking to nothing as an axial load pulls the lip off
(f_z -> -V); where it is violated, one side of the lip lifts and the seal peels open.

Lip preload (the physical lip, cup.seal_model = "lip"). The circle assumes the lip starts evenly
pressed: true on a flat face, not on a curved one. The lip is a ring of springs of rate
K / 2 pi per radian (K = cup.lip_rate) between the bellows' end plane and the surface it rests on
(seal.py: the bridged profile). The plane settles where the springs have no net moment, i.e. it
takes the profile's mean and first harmonic, so the lip's pressure is

    p(theta) = p0 + p_x cos(theta) + p_y sin(theta) - (K / 2 pi) z(theta),

z the profile relative to that plane (zero mean, zero first harmonic, positive away from the cup:
less fold, less pressure). z has no first harmonic, so the resultant and the moment are those of
the first three terms as before (2 pi p0 = V + f_z, tau = pi r (p_y, -p_x)), and p(theta_k) >= 0 at
the seal model's K places theta_k = 2 pi k / K (from the contact frame's x axis) reads

    (V + f_z) + (2 / r) (tau_x sin(theta_k) - tau_y cos(theta_k)) >= K z_k,

K linear half-spaces in alpha that replace the circle (on a flat face, z = 0, they are the
K-gon circumscribing it: 0.2 % wider between places at K = 48). On a cylinder of radius R lying on
its side the profile is z = -(r^2 / 4 R) cos(2 theta): its flanks (z > 0) start with less
pressure, so an axial pull opens them first, at V + f_z = K r^2 / 4 R, i.e. the smallest cylinder
the lip holds under a pull grows from R_min = r^2 / (2 lip_travel) (no load, fold fraction 1/2)
to R_min V / (V + f_z); and a moment that lifts a flank peels it sooner, one that lifts the
cylinder's axis-wise sides (z < 0, extra preload) later than the circle says. The paper
instead bounds ||tau|| by a material constant, pi r kappa, relaxed to a sqrt(2) box to stay
linear; the `paper` preset keeps that box (cup.kappa set). Friction and torsion are the paper's
inscribed sqrt(3) box of the friction limit surface.

A grasp resists an external wrench w (object frame) iff -w = G alpha for some alpha in F, i.e.
iff min_{alpha in F} ||G alpha + w||^2 = 0 (the paper's QP proposition; with the ring limit it is
a second-order cone program).

Closed form. With one contact and all six basis wrenches, G is the 6x6 adjoint that maps a
wrench about the contact origin o in the contact frame R to a wrench about the object origin:
G = [[R, 0], [[o]x R, R]]. Its determinant is det(R)^2 = 1, so G is invertible and the only
alpha with G alpha = -w is alpha* = -G^-1 w = -(R^T f, R^T (tau - o x f)), minus the external
wrench expressed about the ring centre in the contact frame. Resistance is then exactly
"alpha* lies in F": no optimisation is needed, and the test vectorises over any number of grasps
and samples. `resists_qp` keeps the cone program (Clarabel) as the reference.
"""

from __future__ import annotations

import math

import clarabel
import numpy as np
import scipy.sparse as sp

from suctionbench.config import CupConfig
from suctionbench.contact.arrival import Arrival, quarter_swing_share, response_factor
from suctionbench.contact.swing_path import swing_through

SQRT2, SQRT3 = math.sqrt(2.0), math.sqrt(3.0)

CLOSED_FORM_SLACK = 1e-9
"""Relative slack on each constraint of the closed form, in units of that constraint's bound at
zero load (mu V, r mu V, the tilt bound, V), so that wrenches exactly on the boundary of F count as
resisted despite rounding."""

QP_RESIDUAL_TOL = 1e-9
"""The reference declares a wrench resisted when it finds an alpha *in F* whose residual
||D (G alpha + w)|| is at most QP_RESIDUAL_TOL + QP_RELATIVE_TOL ||D w||. D expresses the residual
in units of the tilt limit at zero load and full vacuum tau_s (r V / 2 for the ring,
min(pi r kappa, r V) for the paper's box, V = cup.vacuum_force whatever the seal holds): torques
divided by tau_s, forces multiplied by r / tau_s (a force as the torque it exerts at the cup
radius). Weighting forces less would make the residual useless: in the object
frame a tiny change of contact force at a lever |o| supplies any missing torque, so with forces
weighted by 1/V a wrench 1e-3 outside F has a true minimum residual ~1e-9 (paper preset). With D,
that residual is ~1e-3 r / |o|. After polishing (`_polish`) a resisted wrench leaves only rounding
error, ~1e-16 ||D w|| per operation (||D w|| reaches ~1e6 for the paper preset's tiny tilt limit),
hence the relative part."""

QP_RELATIVE_TOL = 1e-12
"""Relative part of the reference's resistance tolerance, see QP_RESIDUAL_TOL."""

CONE_CUTS = 8
"""Most supporting half-spaces of the tilt cone the reference's polish adds (see `resists_qp`)."""


def tilt_bound(cup: CupConfig, vacuum_force: np.ndarray | float | None = None) -> np.ndarray | float:
    """Largest tilting torque ||(tau_x, tau_y)|| at zero axial load (f_z = 0): r V / 2 for the ring
    limit; for the paper's box, pi r kappa / sqrt(2) per axis."""
    if cup.kappa is not None:
        return math.pi * cup.radius * cup.kappa / SQRT2
    v = cup.vacuum_force if vacuum_force is None else vacuum_force
    return 0.5 * cup.radius * np.asarray(v, dtype=float)


def external_wrench_at_contact(
    force: np.ndarray, com: np.ndarray, ring_centre: np.ndarray, frames: np.ndarray
) -> np.ndarray:
    """External wrench (N, 6) = (f, tau) about the ring centre, in the contact frame.

    `force` (N, 3) acts at `com` (N, 3) (e.g. gravity); `frames` (N, 3, 3) are contact frames.
    """
    torque = np.cross(com - ring_centre, force)
    return np.concatenate(
        [np.einsum("nji,nj->ni", frames, force), np.einsum("nji,nj->ni", frames, torque)], axis=1
    )


SWING_BISECTIONS = 36
"""Bisection steps of the swing's tilts: the bracket [0, pi/2] shrinks to ~2e-11 rad."""

SWING_CAP = 0.5 * math.pi
"""Largest tilt (rad) the swing is solved over: far beyond where any lip peels (the lip's tilt
past the stop reaches the ring's limit within (r V / 2 - k_b theta_max) / k_c = 0.13 rad for the
default cup)."""


class _Swing:
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
    as `resists` takes it) for a load `force` (N, 3) at `com`.

    A cup rigid in bending (`cup.bellows_swing` off) carries the load as it is; with
    `cup.swing_overshoot` off the lip carries the swing's static equilibrium (`_Swing`).

    The swing's first turning point (default). The load does not arrive slowly: it meets the lip
    as the object tips off the table (a brick's tilt built up over ~0.2 s in the simulation) and as
    the transport's acceleration rises (~0.2 s), about one swing period (0.2-0.65 s for the basic
    objects above 0.15 kg). With `arrival` (the pick's motion and the object's inertia and support,
    contact/arrival.py) the swing follows the two arrivals: from the lift-off's speed, or from rest
    at the weight's tilt as the transport's acceleration rises. Without it, the bound: whatever the
    load's history, as long as it grows from zero without reversing, an undamped spring-mass system
    swings furthest when the whole load comes at once (a dynamic amplification of 2 for a linear
    spring). From rest at phi = 0 the swing then turns where the load's work equals the cup's
    stored energy (energy conservation, `_Swing.work`):

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
    squeezed wall and the lip (`_Swing`: R rises at 0.14 N m/rad instead of the swing's 0.028):
    the energy it still carries there goes into them, the lip's moment rises steeply, and a fast
    swing peels it. A box_shoe held 26 mm off its centre of mass reaches the
    stop with ~7 mJ and, caught, needs ~36 mN m of its lip (the ring holds ~24); the simulated lip
    opened ~9 deg beyond the stopped bellows and peeled. A slow arrival is caught within the
    ring's limit.
    """
    force = np.asarray(force, dtype=float)
    if not cup.bellows_swing:
        return external_wrench_at_contact(force, com, ring_centre, frames)
    swing = _Swing(force, com, ring_centre, frames, cup)
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
        swing = _Swing(cases[0].weight, com, ring_centre, frames, cup)
        return swing_through(swing, cases[-1], np.broadcast_to(com, swing.f.shape), ring_centre, frames, cup)
    return np.stack([lip_load(loads[:, case], com, ring_centre, frames, cup, None if cases is None else cases[case])
                     for case in range(loads.shape[1])], axis=1)


def _turning_tilt(energy, phi_s: np.ndarray) -> np.ndarray:
    """Where the swing's kinetic energy `energy(phi)` (positive at phi_s, falling beyond it) runs
    out on [phi_s, SWING_CAP] (SWING_CAP if it never does)."""
    cap = np.full_like(phi_s, SWING_CAP)
    return np.where(energy(cap) > 0.0, cap, _bisect(energy, phi_s, cap))


def _lift_turn(swing: _Swing, phi_s: np.ndarray, arrival: Arrival, com: np.ndarray, ring_centre: np.ndarray,
               frames: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The swing's first turning point after the lift-off (contact/arrival.py), less the
    silicone's loss over that quarter swing; with the moment of inertia about n and the lift-off's
    time into the lift."""
    inertia = arrival.inertia_about(swing.n, swing.r, frames)
    rate, time = arrival.lift_off(swing.n, phi_s, ring_centre, com, frames)
    start = swing.work(phi_s) - 0.5 * inertia * rate * rate
    turn = _turning_tilt(lambda p: swing.work(p) - start, phi_s)
    return phi_s + quarter_swing_share(arrival.zeta) * (turn - phi_s), inertia, time


def _arrived_tilt(swing: _Swing, phi_s: np.ndarray, arrival: Arrival, com: np.ndarray, ring_centre: np.ndarray,
                  frames: np.ndarray, cup: CupConfig) -> np.ndarray:
    """The swing's first turning point for the pick's arrivals (contact/arrival.py): the lift
    leaves the table at phi_s turning at the lift-off's rate; a transport starts at the weight's
    tilt, the inertial load arriving with the transport's response factor, on top of what is left
    of the lift's swing."""
    com = np.broadcast_to(np.asarray(com, dtype=float), swing.f.shape)
    if arrival.transport_force is None:
        return _lift_turn(swing, phi_s, arrival, com, ring_centre, frames)[0]
    inertia = arrival.inertia_about(swing.n, swing.r, frames)
    still = _Swing(arrival.weight, com, ring_centre, frames, cup, axis=swing.n).static_tilt()
    rest = swing.work(still)
    step = _turning_tilt(lambda p: swing.work(p) - rest, phi_s)  # the step's turning point from phi_0
    period = 2.0 * np.pi * np.sqrt(inertia / np.maximum(swing.stiffness(phi_s), 1e-12))
    factor = response_factor(arrival.transport_time / np.maximum(period, 1e-12), arrival.zeta)
    carried = np.where(still < phi_s, phi_s + (factor - 1.0) * (step - phi_s), phi_s)
    hanging = _Swing(arrival.weight, com, ring_centre, frames, cup)
    hang = hanging.static_tilt()
    peak, hang_inertia, lifted_at = _lift_turn(hanging, hang, arrival, com, ring_centre, frames)
    omega = np.sqrt(hanging.stiffness(hang) / np.maximum(hang_inertia, 1e-15))
    ringing = (peak - hang) * np.exp(-arrival.zeta * omega * (arrival.lift_time - lifted_at))
    ringing *= np.abs(np.einsum("ni,ni->n", hanging.n, swing.n))
    return carried + np.where(hanging.tips, ringing, 0.0)


def lip_angles(count: int) -> np.ndarray:
    """Bearings theta_k = 2 pi k / count (rad, from the contact frame's x axis) of the lip places
    whose profile heights `resists` takes (the seal model's lip samples)."""
    return 2.0 * np.pi * np.arange(count) / count


def lip_rows(count: int, cup: CupConfig) -> np.ndarray:
    """(count, 6) the rows A of the lip-preload half-spaces A alpha <= V - K z_k (module doc, "Lip
    preload"): -f_z - (2 / r)(tau_x sin theta_k - tau_y cos theta_k), one per place theta_k."""
    theta = lip_angles(count)
    rows = np.zeros((count, 6))
    rows[:, 2] = -1.0
    rows[:, 3] = -(2.0 / cup.radius) * np.sin(theta)
    rows[:, 4] = (2.0 / cup.radius) * np.cos(theta)
    return rows


def resists(
    wrench_contact: np.ndarray,
    mu: np.ndarray | float,
    cup: CupConfig,
    vacuum_force: np.ndarray | float | None = None,
    lip_heights: np.ndarray | None = None,
    *,
    rim_bound: bool = False,
) -> np.ndarray:
    """Closed-form wrench resistance: does alpha* = -w lie in F? Vectorised over rows of w.

    `vacuum_force` (scalar or one per row) is the V the seal holds; default the cup's full V.
    `lip_heights` (rows, K): the lip's profile relative to its bellows plane at the K places
    `lip_angles(K)` (seal.py); with it the tilt limit is the lip-preload half-spaces (module doc),
    without it the circle of an evenly pressed lip. `rim_bound`: the profile is not measured yet
    (the seal model's first, cheap stage), so test only what every preload implies: a lip pushing
    nowhere but at its rim, ||tau|| <= r f_N (p >= 0 with resultant f_N concentrated at one point).
    """
    a = -np.asarray(wrench_contact, dtype=float)
    mu = np.asarray(mu, dtype=float)
    v = np.asarray(cup.vacuum_force if vacuum_force is None else vacuum_force, dtype=float)
    r, eps = cup.radius, CLOSED_FORM_SLACK
    f_n = a[:, 2] + v
    ok = a[:, 2] >= -v * (1.0 + eps)
    ok &= SQRT3 * np.abs(a[:, 0]) <= mu * (f_n + eps * v)
    ok &= SQRT3 * np.abs(a[:, 1]) <= mu * (f_n + eps * v)
    ok &= SQRT3 * np.abs(a[:, 5]) <= r * mu * (f_n + eps * v)
    if cup.kappa is None and rim_bound:
        ok &= np.hypot(a[:, 3], a[:, 4]) <= r * (f_n + eps * v)
    elif cup.kappa is None and lip_heights is not None:
        heights = np.asarray(lip_heights, dtype=float)
        bound = np.atleast_1d(v)[:, None] * (1.0 + eps) - cup.lip_rate * heights
        ok &= (a @ lip_rows(heights.shape[1], cup).T <= bound).all(axis=1)
    elif cup.kappa is None:
        ok &= np.hypot(a[:, 3], a[:, 4]) <= 0.5 * r * (f_n + eps * v)
    else:
        tilt = math.pi * r * cup.kappa
        ok &= SQRT2 * np.abs(a[:, 3]) <= tilt * (1.0 + eps)
        ok &= SQRT2 * np.abs(a[:, 4]) <= tilt * (1.0 + eps)
    return ok


def constraint_matrix(
    mu: float, cup: CupConfig, vacuum_force: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The linear part of F as A alpha <= b, alpha = (f_x, f_y, f_z, tau_x, tau_y, tau_z).

    Rows: +fx +fy +tz (+tx +ty) -fx -fy -tz (-tx -ty) suction, 11 rows with the paper's tilt box
    (cup.kappa set), 7 without; the ring limit is the cone of `tilt_cone`.
    """
    v = cup.vacuum_force if vacuum_force is None else float(vacuum_force)
    r, k = cup.radius, cup.kappa
    rows, bounds = [], []
    for sign in (1.0, -1.0):
        rows += [[sign * SQRT3, 0, -mu, 0, 0, 0], [0, sign * SQRT3, -mu, 0, 0, 0],
                 [0, 0, -r * mu, 0, 0, sign * SQRT3]]
        bounds += [mu * v, mu * v, r * mu * v]
        if k is not None:
            rows += [[0, 0, 0, sign * SQRT2, 0, 0], [0, 0, 0, 0, sign * SQRT2, 0]]
            bounds += [math.pi * r * k, math.pi * r * k]
    rows.append([0, 0, -1.0, 0, 0, 0])
    bounds.append(v)
    return np.array(rows, dtype=float), np.array(bounds, dtype=float)


def tilt_cone(cup: CupConfig, vacuum_force: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The ring limit as Clarabel's second-order cone: s = b - A alpha = (r (f_z + V) / 2, tau_x,
    tau_y) must satisfy s_0 >= ||(s_1, s_2)||."""
    v = cup.vacuum_force if vacuum_force is None else float(vacuum_force)
    a = np.zeros((3, 6))
    a[0, 2], a[1, 3], a[2, 4] = -0.5 * cup.radius, -1.0, -1.0
    return a, np.array([0.5 * cup.radius * v, 0.0, 0.0])


def grasp_map(ring_centre: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """The 6x6 grasp map G: contact-frame wrench about the ring centre -> object-frame wrench
    about the object origin."""
    g = np.zeros((6, 6))
    g[:3, :3] = frame
    g[3:, 3:] = frame
    g[3:, :3] = np.cross(ring_centre, frame.T).T  # [o]x R, column by column
    return g


def resists_qp(
    force: np.ndarray | None,
    com: np.ndarray | None,
    ring_centre: np.ndarray,
    frame: np.ndarray,
    mu: float,
    cup: CupConfig,
    vacuum_force: float | None = None,
    lip_heights: np.ndarray | None = None,
    wrench_contact: np.ndarray | None = None,
) -> tuple[bool, float]:
    """Reference: solve min_{alpha in F} ||D (G alpha + w)||^2 with Clarabel for one grasp.

    The external wrench w is `force` at `com`, or, given `wrench_contact` (6,) (about the ring
    centre in the contact frame, as `lip_load` gives it; `force` and `com` then None), G wrench_contact.

    With `lip_heights` (K,) the tilt limit is the lip-preload half-spaces (`lip_rows`), linear rows
    of the non-negative cone in place of the ring's second-order cone.

    Everything in the object frame (w about the object origin); D makes the residual
    dimensionless (see QP_RESIDUAL_TOL). The friction, suction and box rows are Clarabel's
    non-negative cone, the ring limit its second-order cone. Clarabel's stopping rule bounds the
    objective, i.e. the *squared* residual, so its raw solution only resolves residuals down to
    ~1e-4; the solution is therefore polished on its active set (exact KKT solves). The cone
    enters the polish as supporting half-spaces (cuts) tangent to it where the current solution
    points, added until the polished alpha lies in the cone; the cuts contain the cone, so a
    resisted wrench's exact alpha* stays feasible for them and the polish finds it. The verdict
    comes from a point of F itself (the polished alpha with its tilt scaled back onto the cone if
    a cut left it outside), so "resisted" is certified by an admissible contact wrench.
    Returns (resisted, residual).
    """
    v = cup.vacuum_force if vacuum_force is None else float(vacuum_force)
    w = (np.concatenate([force, np.cross(com, force)]) if wrench_contact is None
         else grasp_map(ring_centre, frame) @ np.asarray(wrench_contact, dtype=float))
    r, v_full = cup.radius, cup.vacuum_force  # the scale D uses the full vacuum: well defined at V = 0
    torque_scale = 0.5 * r * v_full if cup.kappa is None else min(math.pi * r * cup.kappa, r * v_full)
    scale = np.array([cup.radius / torque_scale] * 3 + [1.0 / torque_scale] * 3)
    m = scale[:, None] * grasp_map(ring_centre, frame)
    c = scale * w
    a_lin, b_lin = constraint_matrix(mu, cup, v)
    ring = cup.kappa is None and lip_heights is None
    if cup.kappa is None and lip_heights is not None:
        heights = np.asarray(lip_heights, dtype=float)
        a_lin = np.vstack([a_lin, lip_rows(len(heights), cup)])
        b_lin = np.concatenate([b_lin, v - cup.lip_rate * heights])
    a_all, b_all = a_lin, b_lin
    cones = [clarabel.NonnegativeConeT(len(b_lin))]
    if ring:
        a_cone, b_cone = tilt_cone(cup, v)
        a_all, b_all = np.vstack([a_lin, a_cone]), np.concatenate([b_lin, b_cone])
        cones.append(clarabel.SecondOrderConeT(3))
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    solver = clarabel.DefaultSolver(
        sp.triu(2.0 * m.T @ m, format="csc"), 2.0 * m.T @ c, sp.csc_matrix(a_all), b_all, cones, settings
    )
    solution = solver.solve()
    alpha = np.array(solution.x, dtype=float)
    if alpha.shape != (6,) or not np.all(np.isfinite(alpha)):  # no usable solution: polish from 0
        alpha = np.zeros(6)
    if ring:
        cuts: list[np.ndarray] = []
        for _ in range(CONE_CUTS):
            cuts.append(_cone_cut(alpha, r))
            a_cut = np.vstack([a_lin, *cuts])
            b_cut = np.concatenate([b_lin, np.full(len(cuts), 0.5 * r * v)])
            alpha = _polish(m, c, a_cut, b_cut, alpha)
            if _cone_excess(alpha, r, v, v_full) <= 1e-12:
                break
        alpha = _onto_cone(alpha, r, v)
    else:
        alpha = _polish(m, c, a_lin, b_lin, alpha)
    residual = float(np.linalg.norm(m @ alpha + c))
    return residual <= QP_RESIDUAL_TOL + QP_RELATIVE_TOL * float(np.linalg.norm(c)), residual


def _cone_cut(alpha: np.ndarray, r: float) -> np.ndarray:
    """Row u . (tau_x, tau_y) - r f_z / 2 <= r V / 2, the cone's supporting half-space in the
    direction u of alpha's tilting torque (any direction if it has none)."""
    tau = alpha[3:5]
    norm = float(np.hypot(*tau))
    u = tau / norm if norm > 0.0 else np.array([1.0, 0.0])
    return np.array([0.0, 0.0, -0.5 * r, u[0], u[1], 0.0])


def _cone_excess(alpha: np.ndarray, r: float, v: float, v_full: float) -> float:
    """How far alpha's tilting torque exceeds the ring limit (vacuum v), relative to the limit at
    zero load and full vacuum v_full."""
    return (float(np.hypot(alpha[3], alpha[4])) - 0.5 * r * (alpha[2] + v)) / (0.5 * r * v_full)


def _onto_cone(alpha: np.ndarray, r: float, v: float) -> np.ndarray:
    """alpha with its tilting torque scaled back onto the ring limit where it exceeds it."""
    limit = max(0.5 * r * (alpha[2] + v), 0.0)
    norm = float(np.hypot(alpha[3], alpha[4]))
    if norm <= limit:
        return alpha
    out = alpha.copy()
    out[3:5] *= limit / norm
    return out


def _polish(m: np.ndarray, c: np.ndarray, a: np.ndarray, b: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """Exact minimiser of ||m alpha + c||^2 s.t. a alpha <= b, from an approximate one.

    A primal-dual active-set iteration warm-started with the constraints that are (nearly) tight
    at `alpha`: minimise the residual on the active set's affine subspace (null-space method on m
    itself, never the squared-conditioned m^T m), drop the constraint with the most negative
    multiplier, else add the most violated one, until the KKT conditions hold. Six variables and
    eleven constraints: a few steps; an active set seen before ends the search with the best
    feasible point found.
    """
    norms = np.linalg.norm(a, axis=1)
    a, b = a / norms[:, None], b / norms  # unit rows: violations and multipliers comparable
    active = sorted(np.flatnonzero(b - a @ alpha <= 1e-6 * np.maximum(np.abs(b), 1e-12)).tolist())
    seen: set[tuple[int, ...]] = set()
    best, best_residual = None, np.inf
    while tuple(active) not in seen:
        seen.add(tuple(active))
        x = _least_squares_on(m, c, a[active], b[active])
        residual_vec = m @ x + c
        violation = a @ x - b
        feasible = violation.max() <= 1e-12 * max(1.0, np.abs(b).max())
        if feasible and np.linalg.norm(residual_vec) < best_residual:
            best, best_residual = x, float(np.linalg.norm(residual_vec))
        if active:
            lam = np.linalg.lstsq(a[active].T, -(m.T @ residual_vec), rcond=None)[0]
            if lam.min() < -1e-10 * max(1.0, float(np.linalg.norm(m.T @ residual_vec))):
                active.pop(int(np.argmin(lam)))
                continue
        if feasible:
            return x
        active = sorted(active + [int(np.argmax(violation))])
    return alpha if best is None else best


def _least_squares_on(m: np.ndarray, c: np.ndarray, a_eq: np.ndarray, b_eq: np.ndarray) -> np.ndarray:
    """argmin ||m x + c|| subject to a_eq x = b_eq (least-squares consistent), by null space."""
    if len(a_eq) == 0:
        return np.linalg.lstsq(m, -c, rcond=None)[0]
    x0 = np.linalg.lstsq(a_eq, b_eq, rcond=None)[0]
    _, sing, vt = np.linalg.svd(a_eq)
    rank = int((sing > 1e-12 * sing[0]).sum())
    null = vt[rank:].T
    if null.shape[1] == 0:
        return x0
    y = np.linalg.lstsq(m @ null, -(m @ x0 + c), rcond=None)[0]
    return x0 + null @ y
