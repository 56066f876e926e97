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
    centre in the contact frame, as `swing.lip_load` gives it; `force` and `com` then None), G wrench_contact.

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
