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

import numpy as np
import qpsolvers
import scipy.sparse as sp

from suctionbench.config import CupConfig

SQRT2, SQRT3 = math.sqrt(2.0), math.sqrt(3.0)

CLOSED_FORM_SLACK = 1e-9
"""Relative slack on each constraint of the closed form (in units of V for forces, r V for
torques), so that wrenches exactly on the boundary of F count as resisted despite rounding."""

QP_RESIDUAL_TOL = 1e-8
"""The QP reference declares a wrench resisted when the residual ||D (G alpha + w)||, with forces
scaled by 1/V and torques by 1/(r V), is at most this. With `CLARABEL_SETTINGS` the residual of a
resisted wrench comes out ~1e-12, so the two paths can only disagree for wrenches within ~1e-8
(relative) of the boundary of F."""

CLARABEL_SETTINGS = {"tol_gap_abs": 1e-14, "tol_gap_rel": 1e-14, "tol_feas": 1e-12, "tol_ktratio": 1e-10}
"""Clarabel's default gap tolerance (1e-8) bounds the objective, the *squared* residual, so it
stops at residuals ~1e-6 and misclassifies wrenches just inside the boundary; these settings
cost nothing measurable (0.2 ms per QP either way)."""


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
    ef, et = CLOSED_FORM_SLACK * v, CLOSED_FORM_SLACK * r * v
    f_n = a[:, 2] + v
    ok = a[:, 2] >= -v - ef
    ok &= SQRT3 * np.abs(a[:, 0]) <= mu * f_n + ef
    ok &= SQRT3 * np.abs(a[:, 1]) <= mu * f_n + ef
    ok &= SQRT3 * np.abs(a[:, 5]) <= r * mu * f_n + et
    torque_limit = math.pi * r * cup.kappa + et
    ok &= SQRT2 * np.abs(a[:, 3]) <= torque_limit
    ok &= SQRT2 * np.abs(a[:, 4]) <= torque_limit
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
    dimensionless. Returns (resisted, residual).
    """
    w = np.concatenate([force, np.cross(com, force)])
    g = grasp_map(ring_centre, frame)
    scale = np.array([1.0 / cup.vacuum_force] * 3 + [1.0 / (cup.radius * cup.vacuum_force)] * 3)
    dg = scale[:, None] * g
    dw = scale * w
    a_ineq, b_ineq = constraint_matrix(mu, cup)
    p = sp.csc_matrix(2.0 * dg.T @ dg)
    q = 2.0 * dg.T @ dw
    alpha = qpsolvers.solve_qp(
        p, q, sp.csc_matrix(a_ineq), b_ineq, solver="clarabel", **CLARABEL_SETTINGS
    )
    if alpha is None:  # solver failure: report as not resisted, with an infinite residual
        return False, math.inf
    residual = float(np.linalg.norm(dg @ alpha + dw))
    return residual <= QP_RESIDUAL_TOL, residual
