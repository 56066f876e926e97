"""How a pick's loads reach the swinging cup: the lift-off and the transport's acceleration.

The bellows lets a held object swing (`swing.Swing`), and a swing overshoots its equilibrium by
as much as the load's arrival lets it. Taking every load as applied at once from rest (the step:
twice the static tilt for a linear spring) bounds every history, but the pick's motion is known
(`PerturbationConfig`: lift height and time, transport time, the cup's rated acceleration), and
with it the two arrivals:

Lift-off. A lifted object does not drop into its swing: it tips. The cup rises at the grasp while
the object's far support edge stays on the table, so the object turns about that edge (the pivot)
by the kinematics of the lift, psi = asin(h / L_p), L_p the horizontal lever from the grasp to the
pivot. The table carries what the cup does not until the cup's return balances the load's moment,
i.e. until the tilt reaches the swing's static equilibrium phi_s: there the object leaves the table
(quasi-statically; the pivot's reaction has fallen to zero), turning at the pivot's rate
psi' = v / (L_p cos phi_s), v the tool's lift speed at that moment. The tool has then risen
h_off = m g / k_a + L_p sin phi_s: the vacuum had compressed the bellows against the table-borne
object to V / k_a, and it carries the weight at (V - m g) / k_a. Min-jerk lift of height H over
time T: h(t) = H s(t / T), s = 10 u^3 - 15 u^4 + 6 u^5, v = (H / T) 30 u^2 (1 - u)^2. The swing
then starts at phi_s with kinetic energy I psi'_n^2 / 2, I the object's moment of inertia about
the tilt axis n through the lip centre and psi'_n the pivot's rate about n; it turns where that
energy is stored (`lift_turning_tilt`), less the silicone's loss over the first quarter swing.

Transport. The object starts the transport hanging at rest at its static tilt under gravity alone
(phi_0, about the transport load's axis) and the inertial load m a(t) arrives with the min-jerk
acceleration profile a(t) = a_max s''(t / T) / max s'', T the transport time. A linear oscillator of
natural period T_n driven so peaks at DAF(T / T_n) times its static response, `response_factor`
(1 for a slow motion, 2 for a step, less than 1 when the swing is too slow to follow); the labeller
scales the step's overshoot of the swung (non-linear) cup by DAF - 1, which for a linear cup is
exact: phi_p = phi_s + (DAF - 1) (phi_u - phi_s). T_n = 2 pi sqrt(I / k), k the swing's stiffness
at phi_s: the cup's return rate plus the pendulum's, d/dphi (R - A cos phi + B sin phi).

The lift's swing is still ringing when the transport starts: its overshoot, left by the silicone's
loss exp(-zeta omega (T_lift - t_off)) over the rest of the lift (omega the hanging swing's natural
frequency, t_off the lift-off's time), and turned onto the transport's tilt axis, adds to the
transport's peak (in the worst phase: the transport's start is not timed to the swing).

Left out: the lift's own acceleration profile (the lift case takes its peak,
PerturbationConfig.lift_acceleration, as a static load from the start), a pivot that slides instead
of turning, and a transport whose load turns the tilt axis (the swing keeps the axis of the full
load's moment).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from suctionbench import minjerk

SUPPORT_TOLERANCE = 1e-3
"""Hull vertices within this height (m) of the lowest, along the labelled pose's gravity, are on the
table: the object's support, whose extreme in the direction of the centre of mass is the pivot."""

DAF_RATIOS = np.geomspace(0.02, 50.0, 300)
"""Grid of motion time over natural period the transport's response factor is tabulated on (beyond
50 the response is static within 0.1 %)."""

RESIDUAL_PERIODS = 1.5
"""The response is followed this many natural periods past the motion's end (the free swing after
it: the hold over the bin), where the peak may still come."""


def min_jerk_at(height: np.ndarray, total: float, duration: float) -> tuple[np.ndarray, np.ndarray]:
    """Tool speed (m/s) of a min-jerk move of `total` metres over `duration` s once it has covered
    `height` (clipped to [0, total]; 0 at both ends), and the time (s) into the move when it has."""
    u = minjerk.progress(np.asarray(height, dtype=float) / total)
    return (total / duration) * minjerk.speed(u), duration * u


def quarter_swing_share(zeta: float) -> float:
    """Share of an undamped swing's amplitude left at the first peak of a damped one started at
    equilibrium with speed v0: x(t) = (v0 / w_d) exp(-zeta w t) sin(w_d t) peaks where
    tan(w_d t) = sqrt(1 - zeta^2) / zeta, at exp(-zeta / sqrt(1 - zeta^2) atan(sqrt(1 - zeta^2) / zeta))
    of v0 / w (0.927 at zeta = 0.05)."""
    root = math.sqrt(1.0 - zeta * zeta)
    return math.exp(-zeta / root * math.atan2(root, zeta))


@functools.lru_cache(maxsize=8)
def _response_table(zeta: float) -> np.ndarray:
    """Peak response (in units of the static response to the peak acceleration) of
    x'' + 2 zeta w x' + w^2 x = w^2 a(t) / a_max, w = 2 pi / T_n, a the min-jerk acceleration over
    T = ratio T_n (then 0 for RESIDUAL_PERIODS more periods), from rest, for each ratio of
    DAF_RATIOS. Time in natural periods; semi-implicit Euler, each ratio with its own step: 200 per
    period and per motion, the same number of steps for all (vectorised)."""
    w = 2.0 * math.pi
    span = DAF_RATIOS + RESIDUAL_PERIODS
    dt = np.minimum(1.0, DAF_RATIOS) / 200.0
    steps = int(np.ceil((span / dt).max()))
    dt = span / steps
    x, v, peak = np.zeros_like(dt), np.zeros_like(dt), np.zeros_like(dt)
    for k in range(steps):
        u = np.minimum(k * dt / DAF_RATIOS, 1.0)
        drive = minjerk.acceleration(u) / minjerk.PEAK_ACCELERATION  # 0 from u = 1 on
        v += dt * (w * w * (drive - x) - 2.0 * zeta * w * v)
        x += dt * v
        np.maximum(peak, x, out=peak)
    return peak


def response_factor(ratio: np.ndarray, zeta: float) -> np.ndarray:
    """DAF: the peak swing under the transport's min-jerk acceleration over the static swing at its
    peak, for motion time / natural period `ratio` (interpolated in log ratio; beyond the table,
    its end values: ~1 for slow motions, ~0 for a swing too slow to follow)."""
    table = _response_table(round(float(zeta), 12))
    return np.interp(np.log(np.maximum(ratio, 1e-12)), np.log(DAF_RATIOS), table)


def table_support(hull: np.ndarray, gravity: np.ndarray) -> np.ndarray:
    """The hull vertices (H, 3) within SUPPORT_TOLERANCE of the lowest along `gravity` (3,): what the
    object stands on; only the corners of their outline seen along gravity (the pivot, an extreme
    point in a horizontal direction, is one of them: a rounded bar's hundreds of bottom vertices
    become a few dozen)."""
    down = np.asarray(gravity, dtype=float) / max(float(np.linalg.norm(gravity)), 1e-12)
    depth = hull @ down
    support = hull[depth >= depth.max() - SUPPORT_TOLERANCE]
    if len(support) < 4:
        return support
    across = np.linalg.svd(np.eye(3) - np.outer(down, down))[0][:, :2]  # a basis of the horizontal
    try:
        return support[ConvexHull(support @ across).vertices]
    except QhullError:  # collinear (a cylinder on its side): every point is an extreme candidate
        return support


@dataclass(frozen=True)
class Arrival:
    """What `swing.lip_load` needs to follow the arrival of one load case, per row (one row per
    load): the lift (`transport_force` None) or a transport (`transport_force` the inertial part
    m a of each load, the rest being the weight `weight`)."""

    weight: np.ndarray
    """(N, 3) the object's weight m g (N) in the object frame: its direction is "down"."""

    transport_force: np.ndarray | None
    """(N, 3) the transport's inertial force (N) in the object frame; None for the lift."""

    inertia: np.ndarray
    """(3, 3) the object's inertia tensor about its centre of mass (kg m^2), object frame."""

    mass: float
    """The object's mass (kg)."""

    support: np.ndarray
    """(H, 3) the hull vertices (m, object frame) the object stands on in its labelled pose
    (`table_support`); a perturbed sample's tilt does not stand it on one corner."""

    lift_height: float
    """Height (m) of the min-jerk lift."""

    lift_time: float
    """Duration (s) of the min-jerk lift."""

    transport_time: float | np.ndarray
    """Duration (s) of the min-jerk transport: one for all rows, or (N,) one per row."""

    axial_stiffness: float
    """The bellows' axial rate k_a (N/m)."""

    zeta: float
    """Damping ratio of the swing (the silicone's loss factor / 2)."""

    planned: bool = False
    """The pick's motion is known (the transport's direction, time and length: PerturbationConfig
    .transport_direction): the swing is followed in time through the lift, the transport and the
    hold (contact/swing_path.py), and each load case stands for one phase's worst instant
    (swing_path.PHASES), the transport case's force -m a giving the transport's direction. False:
    the closed form's turning points, one per load case."""

    transport_peak: float = 0.0
    """Peak acceleration (m/s^2) of the planned transport (`planned`): 5.774 L / T^2."""

    hold_time: float = 0.0
    """How long (s) the planned pick holds the object over the bin after the transport (`planned`)."""

    def take(self, rows: np.ndarray | slice) -> Arrival:
        """The rows `rows` only."""
        transport = None if self.transport_force is None else self.transport_force[rows]
        duration = self.transport_time if np.ndim(self.transport_time) == 0 else self.transport_time[rows]
        return dataclasses.replace(self, weight=self.weight[rows], transport_force=transport, transport_time=duration)

    def inertia_along(self, n: np.ndarray, frames: np.ndarray) -> np.ndarray:
        """(N, 3) I_c n: the inertia about the centre of mass turned into each contact frame
        (`frames` (N, 3, 3), columns in the mesh frame), applied to the axis n (contact frame)."""
        return np.einsum("nji,jk,nkl,nl->ni", frames, self.inertia, frames, n)

    def inertia_about(self, n: np.ndarray, arm: np.ndarray, frames: np.ndarray) -> np.ndarray:
        """(N,) moment of inertia about the tilt axis n (contact frame) through the lip centre:
        n' I_c n (`inertia_along`) + m |n x r|^2, r the lip centre to the centre of mass (contact
        frame; parallel axes)."""
        lever = np.cross(n, arm)
        return np.einsum("ni,ni->n", n, self.inertia_along(n, frames)) + self.mass * np.einsum("ni,ni->n", lever,
                                                                                                 lever)

    def lift_off(self, n: np.ndarray, phi_s: np.ndarray, ring_centre: np.ndarray, com: np.ndarray,
                 frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(N,) the swing's rate about n (rad/s) as the object leaves the table at the tilt phi_s,
        and (N,) the time (s) into the lift when it does (module docstring, "Lift-off")."""
        weight = np.linalg.norm(self.weight, axis=1)
        down = self.weight / np.maximum(weight, 1e-12)[:, None]
        offset = com - ring_centre
        offset = offset - np.einsum("ni,ni->n", offset, down)[:, None] * down
        reach = np.linalg.norm(offset, axis=1)
        towards = offset / np.maximum(reach, 1e-12)[:, None]
        ahead = (towards @ self.support.T).max(axis=1) - np.einsum("ni,ni->n", ring_centre, towards)
        lever = np.maximum(ahead, 1e-3)  # a grasp above its pivot: the object lifts off at once
        risen = weight / self.axial_stiffness + lever * np.sin(phi_s)
        speed, time = min_jerk_at(risen, self.lift_height, self.lift_time)
        pivot_axis = np.einsum("nji,nj->ni", frames, np.cross(down, towards))
        along_n = np.abs(np.einsum("ni,ni->n", pivot_axis, n))
        rate = np.where(reach > 1e-9, speed / (lever * np.cos(phi_s)) * along_n, 0.0)
        return rate, time
