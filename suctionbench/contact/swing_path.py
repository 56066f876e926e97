"""The swing followed in time through a planned pick: the lift, the transport and the hold.

Where the pick's motion is known when labelling (the episode's labeller: `PerturbationConfig
.transport_direction`, with its planned time and length), the swinging cup's load need not be
bounded by turning points (contact/arrival.py's closed form, which takes the lift's ringing in its
worst phase and scales a step's overshoot by the response factor of a linear swing): the same
one-body swing is integrated in time, and the lip judged at its worst instant of each phase.

The model (contact frame, which the straight lift and transport do not turn). The object is a
rigid body hinged at the lip centre, tilted by the in-plane rotation vector phi (|phi| the tilt,
phi / |phi| its axis); the cup returns R(|phi|) about that axis (`swing.Swing.returned`: bellows
and lip in series, the stop beyond theta_max); the silicone loses 2 zeta sqrt(k I) per rad/s
(zeta = cup.swing_damping_ratio, k and I the hanging swing's stiffness and moment of inertia); the
load is m (g - a(t)) at the centre of mass, a(t) the tool's min-jerk acceleration:

    lift       a = up (H / T_l^2) s''(t / T_l),                         0 <= t < T_l
    transport  a = d a_p s''((t - T_l) / T) / max s'',                  T_l <= t < T_l + T
    hold       a = 0,                                                   up to T_l + T + T_h

(a_p = 5.774 L / T^2, at most the cup's rating). Euler's equation about the lip centre for the
in-plane rate omega, the object's inertia about the lip centre I_L (parallel axes) restricted to
the cup plane, twisting held by the bellows' torsional stiffness:

    I_L omega' = (r x m (g - a))_xy - R(|phi|) phi / |phi| - c omega,   phi' = omega,

r the centre of mass turned by phi.

It starts at the lift-off (contact/arrival.py: the object leaves the table at the weight's static
tilt phi_s, turning at the pivot's rate psi', at the time t_off into the lift) and is stepped by
semi-implicit (symplectic) Euler: no drift of a lossless swing's energy, stable while omega dt < 2
(the stop's 0.14 N m/rad on a 3e-6 kg m^2 matchbox: omega = 216 rad/s, 0.43 at the 2 ms step), and
within 3 % of a tight Runge-Kutta on the stop-caught swing (tests/test_swing_path.py; implicit
Euler lost 4 % there to its numerical damping, the trapezoidal rule linearised at the step's
start overshot by 11 % where the step enters the stop).

The lip carries, at each instant, the cup's return and the loss about the tilt axis, the load's
twist, and the load less what accelerates the centre of mass (Newton: m (alpha x r + omega x
(omega x r))), all seen from the tilted object; its ring limit r (V - f_z) / 2 with f_z that
force's pull. The lip is judged (`wrench.resists`) at each phase's instant of the highest moment
over that limit (at the cup's full vacuum): the lift (to T_l) and the carry (transport and hold).

Left out: the tool's servo lag (the simulated tool runs 5-15 % past its planned peak), the axial
bounce of the bellows, a twist of the tilt axis by the object's own spin (gyroscopic terms).
"""

from __future__ import annotations

import numpy as np

from suctionbench import minjerk
from suctionbench.config import CupConfig

STEP = 0.002
"""Time step (s): 100+ per swing period of the basic objects (0.2-0.65 s), 15+ per period of the
stiffest swing on the stop (module docstring)."""

PHASES = ("lift", "carry")
"""The phases whose worst instants the lip is judged at: the lift, then the transport and the hold."""


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise a x b of (N, 3) arrays (np.cross's axis handling costs more than the product on the
    short rows the step loop works on)."""
    return np.column_stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1], a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                            a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]])


def _rotate(phi: np.ndarray, v: np.ndarray) -> np.ndarray:
    """v (N, 3) turned by the in-plane rotation vectors phi (N, 2): Rodrigues,
    v cos a + (n x v) sin a + n (n . v)(1 - cos a), written out for an axis n = (n_x, n_y, 0)."""
    angle = np.hypot(phi[:, 0], phi[:, 1])
    safe = np.maximum(angle, 1e-15)
    nx, ny = phi[:, 0] / safe, phi[:, 1] / safe
    c, s = np.cos(angle), np.sin(angle)
    dot = (nx * v[:, 0] + ny * v[:, 1]) * (1.0 - c)
    return np.column_stack([c * v[:, 0] + s * ny * v[:, 2] + nx * dot, c * v[:, 1] - s * nx * v[:, 2] + ny * dot,
                            c * v[:, 2] + s * (nx * v[:, 1] - ny * v[:, 0])])


def _axis_turned(phi: np.ndarray) -> np.ndarray:
    """(N, 3) the unit z axis turned by the in-plane rotation vectors phi (N, 2): (n_y sin a,
    -n_x sin a, cos a)."""
    angle = np.hypot(phi[:, 0], phi[:, 1])
    scale = np.sin(angle) / np.maximum(angle, 1e-15)
    return np.column_stack([phi[:, 1] * scale, -phi[:, 0] * scale, np.cos(angle)])


def _damping(swing, phi_s: np.ndarray, about_lip: np.ndarray, zeta: float) -> np.ndarray:
    """(N,) the silicone's loss c = 2 zeta sqrt(k I) (N m s/rad) of the hanging swing: k its
    stiffness at the weight's static tilt (`Swing.stiffness`), I the moment of inertia about its
    axis through the lip centre (a load with no tilting moment: the mean of the in-plane ones)."""
    axis = swing.n
    along = np.einsum("ni,nij,nj->n", axis, about_lip, axis)
    inertia = np.where(swing.tips, along, 0.5 * (about_lip[:, 0, 0] + about_lip[:, 1, 1]))
    return 2.0 * zeta * np.sqrt(np.maximum(swing.stiffness(phi_s), 0.0) * inertia)


def _lip_wrench(phi: np.ndarray, omega: np.ndarray, alpha: np.ndarray, arm: np.ndarray, arm0: np.ndarray,
                load: np.ndarray, lip: np.ndarray, mass: float) -> np.ndarray:
    """(M, 6) the lip's wrench seen from the tilted object (module docstring): the load less what
    accelerates the centre of mass (m (alpha x r + omega x (omega x r))), the moment `lip` the cup
    returns, and the load's twist about the approach."""
    spin = np.zeros_like(arm)
    spin[:, :2] = omega
    turn = np.zeros_like(arm)
    turn[:, :2] = alpha
    centre = _cross(turn, arm) + _cross(spin, _cross(spin, arm))
    seen = _rotate(-phi, load)  # seen from the object: turned back by the tilt
    force = seen - mass * _rotate(-phi, centre)
    return np.column_stack([force, lip, _cross(arm0, seen)[:, 2]])


def swing_through(swing, arrival, com: np.ndarray, ring_centre: np.ndarray, frames: np.ndarray,
                  cup: CupConfig, trace=None) -> np.ndarray:
    """(N, 2, 6) the wrench the lip carries (contact frame, as `wrench.resists` takes it) at the
    worst instant of the lift and of the carry (module docstring), for the swing of the object's
    weight alone `swing` (`swing.Swing`: its static tilt and axis start the lift-off) and the
    planned motion `arrival` (`Arrival` with `planned` set: its transport force gives the
    direction, its transport_time, transport_peak and hold_time the timing). `trace`, if given, is
    called at every step with (t, the lip's wrench (N, 6) as returned for the worst instants,
    which rows swing (N,)): the whole history, for probes."""
    count = len(frames)
    if count == 0:
        return np.zeros((0, len(PHASES), 6))
    mass = arrival.mass
    gravity = np.einsum("nji,nj->ni", frames, arrival.weight) / mass  # g in the contact frame
    up = -gravity / np.maximum(np.linalg.norm(gravity, axis=1), 1e-12)[:, None]
    push = np.einsum("nji,nj->ni", frames, -arrival.transport_force)  # -(-m a): along the tool's acceleration
    ahead = push / np.maximum(np.linalg.norm(push, axis=1), 1e-12)[:, None]
    arm0 = np.einsum("nji,nj->ni", frames, com - ring_centre)
    own = np.einsum("nji,jk,nkl->nil", frames, arrival.inertia, frames)
    about_lip = own + mass * (np.einsum("ni,ni->n", arm0, arm0)[:, None, None] * np.eye(3)
                              - np.einsum("ni,nj->nij", arm0, arm0))
    plane = about_lip[:, :2, :2]
    det = plane[:, 0, 0] * plane[:, 1, 1] - plane[:, 0, 1] * plane[:, 1, 0]
    inverse = np.stack([np.stack([plane[:, 1, 1], -plane[:, 0, 1]], axis=1),
                        np.stack([-plane[:, 1, 0], plane[:, 0, 0]], axis=1)], axis=1) / det[:, None, None]
    phi_s = swing.static_tilt()
    rate, t_off = arrival.lift_off(swing.n, phi_s, ring_centre, com, frames)
    phi = phi_s[:, None] * swing.n[:, :2]
    omega = rate[:, None] * swing.n[:, :2]
    loss = _damping(swing, phi_s, about_lip, arrival.zeta)

    lift_time, lift_rate = arrival.lift_time, arrival.lift_height / arrival.lift_time**2
    duration = np.broadcast_to(np.asarray(arrival.transport_time, dtype=float), (count,))
    peak = arrival.transport_peak / minjerk.PEAK_ACCELERATION
    end = lift_time + duration + arrival.hold_time
    best = np.full((count, len(PHASES)), -np.inf)
    out = np.zeros((count, len(PHASES), 6))
    limit_scale = 0.5 * cup.radius
    vacuum = cup.vacuum_force
    t = float(np.min(t_off))
    while t < float(end.max()):
        active = (t >= t_off) & (t < end)
        if t < lift_time:
            accel = up * (lift_rate * minjerk.acceleration(t / lift_time))
            phase = PHASES.index("lift")
        else:
            u = np.clip((t - lift_time) / duration, 0.0, 1.0)
            accel = ahead * (peak * minjerk.acceleration(u))[:, None]
            phase = PHASES.index("carry")
        load = mass * (gravity - accel)
        arm = _rotate(phi, arm0)
        along = _axis_turned(phi)  # the object's approach axis, turned by the tilt
        moment = _cross(arm, load)[:, :2]
        tilt = np.hypot(phi[:, 0], phi[:, 1])
        axis = phi / np.maximum(tilt, 1e-15)[:, None]
        returned = swing.returned(tilt)
        alpha = np.einsum("nij,nj->ni", inverse, moment - returned[:, None] * axis - loss[:, None] * omega)
        alpha = np.where(active[:, None], alpha, 0.0)
        omega = omega + STEP * alpha
        lip = returned[:, None] * axis + loss[:, None] * omega
        # The instant is chosen by the load's pull along the object's axis; the lip's full wrench
        # (less what accelerates the centre of mass) is formed only where a row has a new worst.
        pull = np.einsum("ni,ni->n", load, along)
        ratio = np.hypot(lip[:, 0], lip[:, 1]) / (limit_scale * np.maximum(vacuum - pull, 1e-9))
        if trace is not None:
            trace(t, _lip_wrench(phi, omega, alpha, arm, arm0, load, lip, mass), active)
        worse = np.flatnonzero(active & (ratio > best[:, phase]))
        if len(worse):
            best[worse, phase] = ratio[worse]
            out[worse, phase] = _lip_wrench(phi[worse], omega[worse], alpha[worse], arm[worse], arm0[worse],
                                            load[worse], lip[worse], mass)
        phi = phi + STEP * np.where(active[:, None], omega, 0.0)  # held at the lift-off's tilt until then
        t += STEP
    never = ~np.isfinite(best)  # a phase the swing never reached (no lift left after the lift-off)
    out[never] = 0.0
    return out
