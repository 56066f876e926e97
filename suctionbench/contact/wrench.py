"""Wrench resistance under the suction-ring contact model (Dex-Net 3.0, "Wrench Space Analysis"
and the appendix "Suction Contact Model").

Contact frame: origin at the centre of the contact ring, z = v (into the object), x and y in the
cup plane. The contact applies to the object the wrench alpha = (f_x, f_y, f_z, tau_x, tau_y,
tau_z) in that frame, on top of a constant vacuum pull V toward the cup; the lip's normal force
is f_N = f_z + V. The admissible set F is the paper's, linear in alpha:

    friction   sqrt(3)|f_x| <= mu f_N,  sqrt(3)|f_y| <= mu f_N,  sqrt(3)|tau_z| <= r mu f_N
    material   sqrt(2)|tau_x| <= pi r kappa,  sqrt(2)|tau_y| <= pi r kappa
    suction    f_z >= -V

A grasp resists an external wrench w (object frame) iff -w = G alpha for some alpha in F, i.e.
iff min_{alpha in F} ||G alpha + w||^2 = 0 (the paper's QP proposition).

Closed form. With one contact and all six basis wrenches, G is the 6x6 adjoint that maps a
wrench about the contact origin o in the contact frame R to a wrench about the object origin:
G = [[R, 0], [[o]x R, R]]. Its determinant is det(R)^2 = 1, so G is invertible and the only
alpha with G alpha = -w is alpha* = -G^-1 w = -(R^T f, R^T (tau - o x f)), minus the external
wrench expressed about the ring centre in the contact frame. Resistance is then exactly
"alpha* satisfies the eleven inequalities above": no optimisation is needed, and the test
vectorises over any number of grasps and samples. `resists_qp` keeps the QP as the reference.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import qpsolvers
import scipy.sparse as sp

from suctionbench.config import CupConfig

SQRT2, SQRT3 = math.sqrt(2.0), math.sqrt(3.0)

CLOSED_FORM_SLACK = 1e-9
"""Relative slack on each constraint of the closed form, in units of that constraint's bound at
zero load (mu V, r mu V, pi r kappa, V), so that wrenches exactly on the boundary of F count as
resisted despite rounding."""

QP_RESIDUAL_TOL = 1e-9
"""The QP reference declares a wrench resisted when the residual ||D (G alpha + w)|| is at most
QP_RESIDUAL_TOL + QP_RELATIVE_TOL ||D w||. D expresses the residual in units of the tilt limit
tau_s = min(pi r kappa, r V): torques divided by tau_s, forces multiplied by r / tau_s (a force as
the torque it exerts at the cup radius). Weighting forces less would make the residual useless:
in the object frame a tiny change of contact force at a lever |o| supplies any missing torque, so
with forces weighted by 1/V a wrench 1e-3 outside F has a true minimum residual ~1e-9 (paper
preset). With D, that residual is ~1e-3 r / |o|. After polishing (`_polish`) a resisted wrench
leaves only rounding error, ~1e-16 ||D w|| per operation (||D w|| reaches ~1e6 for the paper
preset's tiny tilt limit), hence the relative part."""

QP_RELATIVE_TOL = 1e-12
"""Relative part of the QP's resistance tolerance, see QP_RESIDUAL_TOL."""


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


def resists(wrench_contact: np.ndarray, mu: np.ndarray | float, cup: CupConfig) -> np.ndarray:
    """Closed-form wrench resistance: does alpha* = -w lie in F? Vectorised over rows of w."""
    a = -np.asarray(wrench_contact, dtype=float)
    mu = np.asarray(mu, dtype=float)
    v, r = cup.vacuum_force, cup.radius
    tilt = math.pi * r * cup.kappa
    eps = CLOSED_FORM_SLACK
    f_n = a[:, 2] + v
    ok = a[:, 2] >= -v * (1.0 + eps)
    ok &= SQRT3 * np.abs(a[:, 0]) <= mu * (f_n + eps * v)
    ok &= SQRT3 * np.abs(a[:, 1]) <= mu * (f_n + eps * v)
    ok &= SQRT3 * np.abs(a[:, 5]) <= r * mu * (f_n + eps * v)
    ok &= SQRT2 * np.abs(a[:, 3]) <= tilt * (1.0 + eps)
    ok &= SQRT2 * np.abs(a[:, 4]) <= tilt * (1.0 + eps)
    return ok


def constraint_matrix(mu: float, cup: CupConfig) -> tuple[np.ndarray, np.ndarray]:
    """The set F as A alpha <= b (11 rows), alpha = (f_x, f_y, f_z, tau_x, tau_y, tau_z)."""
    v, r, k = cup.vacuum_force, cup.radius, cup.kappa
    rows, bounds = [], []
    for sign in (1.0, -1.0):
        rows += [
            [sign * SQRT3, 0, -mu, 0, 0, 0],
            [0, sign * SQRT3, -mu, 0, 0, 0],
            [0, 0, -r * mu, 0, 0, sign * SQRT3],
            [0, 0, 0, sign * SQRT2, 0, 0],
            [0, 0, 0, 0, sign * SQRT2, 0],
        ]
        bounds += [mu * v, mu * v, r * mu * v, math.pi * r * k, math.pi * r * k]
    rows.append([0, 0, -1.0, 0, 0, 0])
    bounds.append(v)
    return np.array(rows, dtype=float), np.array(bounds, dtype=float)


def grasp_map(ring_centre: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """The 6x6 grasp map G: contact-frame wrench about the ring centre -> object-frame wrench
    about the object origin."""
    g = np.zeros((6, 6))
    g[:3, :3] = frame
    g[3:, 3:] = frame
    g[3:, :3] = np.cross(ring_centre, frame.T).T  # [o]x R, column by column
    return g


def resists_qp(
    force: np.ndarray,
    com: np.ndarray,
    ring_centre: np.ndarray,
    frame: np.ndarray,
    mu: float,
    cup: CupConfig,
) -> tuple[bool, float]:
    """Reference: solve min_{alpha in F} ||D (G alpha + w)||^2 with Clarabel for one grasp.

    Everything in the object frame (w about the object origin); D makes the residual
    dimensionless (see QP_RESIDUAL_TOL). Clarabel's stopping rule bounds the objective, i.e. the *squared* residual, so
    its raw solution only resolves residuals down to ~1e-4; the solution is therefore polished on
    its active set (exact KKT solves), which makes the residual exact. Returns (resisted, residual).
    """
    w = np.concatenate([force, np.cross(com, force)])
    torque_scale = min(math.pi * cup.radius * cup.kappa, cup.radius * cup.vacuum_force)
    scale = np.array([cup.radius / torque_scale] * 3 + [1.0 / torque_scale] * 3)
    m = scale[:, None] * grasp_map(ring_centre, frame)
    c = scale * w
    a_ineq, b_ineq = constraint_matrix(mu, cup)
    with warnings.catch_warnings():  # non-"Solved" statuses are expected here; the polish fixes them
        warnings.simplefilter("ignore", UserWarning)
        alpha = qpsolvers.solve_qp(
            sp.csc_matrix(2.0 * m.T @ m), 2.0 * m.T @ c, sp.csc_matrix(a_ineq), b_ineq, solver="clarabel"
        )
    if alpha is None:  # no solution reported: start the active-set polish from alpha = 0
        alpha = np.zeros(6)
    alpha = _polish(m, c, a_ineq, b_ineq, alpha)
    residual = float(np.linalg.norm(m @ alpha + c))
    return residual <= QP_RESIDUAL_TOL + QP_RELATIVE_TOL * float(np.linalg.norm(c)), residual


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
