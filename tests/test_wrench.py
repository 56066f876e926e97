"""Tests of the suction-ring wrench-resistance model (suctionbench/contact/wrench.py).

Notation (module docstring of wrench.py): contact frame R (columns x, y, z = v, z into the
object), ring centre o. The contact applies alpha = (f_x, f_y, f_z, tau_x, tau_y, tau_z) (contact
frame, about o) on top of the vacuum pull V, with lip normal force f_N = f_z + V. F is

    sqrt(3)|f_x| <= mu f_N,  sqrt(3)|f_y| <= mu f_N,  sqrt(3)|tau_z| <= r mu f_N,
    sqrt(2)|tau_x| <= pi r kappa,  sqrt(2)|tau_y| <= pi r kappa,  f_z >= -V.

An external force f acting at the centre of mass c has, about o and in the contact frame, the
wrench w_c = (R^T f, R^T ((c - o) x f)) (= `external_wrench_at_contact`). The grasp resists iff
alpha* = -w_c lies in F (`resists`), or, equivalently, iff min_{alpha in F} ||G alpha + w|| = 0
with w = (f, c x f) about the object origin (`resists_qp`).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from suctionbench.config import CUP_DEFAULT, CUP_PAPER, CupConfig
from suctionbench.contact.wrench import (
    constraint_matrix,
    external_wrench_at_contact,
    grasp_map,
    resists,
    resists_qp,
)

SQRT2, SQRT3 = math.sqrt(2.0), math.sqrt(3.0)
PRESETS = [pytest.param(CUP_DEFAULT, id="default"), pytest.param(CUP_PAPER, id="paper")]
EPS = 1e-3  # relative step just inside / just outside a face of F


def tilt_limit(cup: CupConfig) -> float:
    """Largest |tau_x| (= largest |tau_y|) in F: sqrt(2)|tau_x| <= pi r kappa."""
    return math.pi * cup.radius * cup.kappa / SQRT2


def qp(force, com, centre, frame, mu, cup) -> tuple[bool, float]:
    """`resists_qp`, with Clarabel's non-convergence warnings silenced (its verdict is what we test)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        ok, residual = resists_qp(force, com, centre, frame, float(mu), cup)
    return bool(ok), residual


def random_frames(rng: np.random.Generator, n: int) -> np.ndarray:
    return Rotation.random(n, random_state=rng).as_matrix()


def unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def force_and_com(alpha: np.ndarray, frame: np.ndarray, centre: np.ndarray, along: float = 0.02):
    """A (force, com) pair whose contact-frame wrench about `centre` is w_c = -alpha.

    The object-frame force is f = R w_c[:3] = -R alpha[:3] and the torque about o must be
    t = -R alpha[3:]. A single force gives (c - o) x f = t only if t . f = 0; then
    d = (f x t) / |f|^2 works, since (f x t) x f = t |f|^2 - f (t . f) = t |f|^2; any multiple of
    f may be added to d (`along`, metres along the force line) without changing the torque.
    """
    force = -frame @ alpha[:3]
    torque = -frame @ alpha[3:]
    fsq = float(force @ force)
    assert fsq > 0.0
    assert abs(force @ torque) <= 1e-12 * math.sqrt(fsq) * (np.linalg.norm(torque) + 1e-300)
    d = np.cross(force, torque) / fsq + along * force / math.sqrt(fsq)
    return force, centre + d


def contact_wrench(force, com, centre, frame) -> np.ndarray:
    return external_wrench_at_contact(force[None], com[None], centre[None], frame[None])[0]


# --------------------------------------------------------------------------------------------
# 1. Closed form vs. QP reference on random cases
# --------------------------------------------------------------------------------------------

N_RANDOM = 10_000
RANDOM_SEED = {"default": 20240601, "paper": 20240602}


def random_cases(cup: CupConfig, n: int, seed: int):
    """Random grasps, scaled per preset so that every face of F is active in some cases.

    Force magnitude |f| is log-uniform in [0.01 V, 3.2 V], so the suction and friction faces bind
    for the larger forces. The torque about o is set through the offset of the COM perpendicular
    to the force line: |(c - o) x f| = d_perp |f| with d_perp = tau / |f|, tau log-uniform in
    [0.01, 10] times the tilt limit (the tightest torque bound for both presets; capped at
    10 cm), plus up to +-5 cm along the force line (which changes no torque). Ring centres lie
    in a 10 cm cube, frames are uniform random rotations, mu uniform in [0.1, 1].
    """
    rng = np.random.default_rng(seed)
    v = cup.vacuum_force
    frames = random_frames(rng, n)
    centres = rng.uniform(-0.05, 0.05, (n, 3))
    direction = unit(rng.normal(size=(n, 3)))
    magnitude = v * 10.0 ** rng.uniform(-2.0, 0.5, n)
    perp = unit(np.cross(direction, rng.normal(size=(n, 3))))
    d_perp = np.minimum(tilt_limit(cup) * 10.0 ** rng.uniform(-2.0, 1.0, n) / magnitude, 0.1)
    com = centres + d_perp[:, None] * perp + rng.uniform(-0.05, 0.05, n)[:, None] * direction
    force = direction * magnitude[:, None]
    mu = rng.uniform(0.1, 1.0, n)
    return force, com, centres, frames, mu


_CACHE: dict[str, dict] = {}


def random_results(cup: CupConfig) -> dict:
    """Closed-form and QP verdicts on the random cases of `cup` (computed once per preset)."""
    if cup.name not in _CACHE:
        force, com, centres, frames, mu = random_cases(cup, N_RANDOM, RANDOM_SEED[cup.name])
        w_c = external_wrench_at_contact(force, com, centres, frames)
        closed = resists(w_c, mu, cup)
        qp_ok = np.empty(N_RANDOM, dtype=bool)
        qp_res = np.empty(N_RANDOM)
        for i in range(N_RANDOM):
            qp_ok[i], qp_res[i] = qp(force[i], com[i], centres[i], frames[i], mu[i], cup)
        _CACHE[cup.name] = dict(
            force=force, com=com, centres=centres, frames=frames, mu=mu, w_c=w_c,
            closed=closed, qp=qp_ok, qp_res=qp_res,
        )
    return _CACHE[cup.name]


def relative_margins(alpha: np.ndarray, mu: np.ndarray, cup: CupConfig) -> np.ndarray:
    """(n, 11) slacks b - A alpha of F, forces in units of V and torques in units of the bound."""
    v, r = cup.vacuum_force, cup.radius
    f_n = alpha[:, 2] + v
    t = tilt_limit(cup)
    cols = []
    for sign in (1.0, -1.0):
        cols += [
            (mu * f_n - sign * SQRT3 * alpha[:, 0]) / v,
            (mu * f_n - sign * SQRT3 * alpha[:, 1]) / v,
            (r * mu * f_n - sign * SQRT3 * alpha[:, 5]) / (r * v),
            (t - sign * alpha[:, 3]) / t,
            (t - sign * alpha[:, 4]) / t,
        ]
    cols.append(f_n / v)
    return np.stack(cols, axis=1)


@pytest.mark.parametrize("cup", PRESETS)
def test_random_cases_cover_both_outcomes_and_every_face(cup):
    # The distribution must exercise both verdicts (20-80 % resisted) and every constraint type:
    # each face of F must be the *only* violated one in some cases, otherwise a bug in that single
    # inequality could hide behind another violated one.
    data = random_results(cup)
    share = data["closed"].mean()
    print(f"{cup.name}: resisted share {share:.3f}")
    assert 0.2 <= share <= 0.8
    margins = relative_margins(-data["w_c"], data["mu"], cup)
    violated = margins < 0
    only = violated & (violated.sum(axis=1) == 1)[:, None]
    # faces: +fx +fy +tz +tx +ty -fx -fy -tz -tx -ty suction. The suction face alone can never be
    # the only violated one (f_N < 0 also violates mu f_N >= sqrt(3)|f_x|), so check it at all.
    # For the paper preset (V = 250 N, r mu V / sqrt(3) >> tilt limit) the tau_z faces can only
    # bind together with the tilt faces, as torques are sampled on the tilt scale.
    must_be_sole = [0, 1, 3, 4, 5, 6, 8, 9] + ([2, 7] if cup.name == "default" else [])
    assert (only[:, must_be_sole].sum(axis=0) >= 20).all(), only.sum(axis=0)
    assert violated[:, 10].sum() >= 20
    assert violated[:, [2, 7]].any(axis=1).sum() >= 20


@pytest.mark.parametrize("cup", PRESETS)
def test_closed_form_is_the_linear_feasibility_test(cup):
    # Independent of the QP: G is invertible, so -w = G alpha has the single solution
    # alpha* = -G^-1 w = -w_c; resistance is exactly A alpha* <= b with (A, b) = constraint_matrix.
    data = random_results(cup)
    w = np.concatenate([data["force"], np.cross(data["com"], data["force"])], axis=1)
    for i in range(0, N_RANDOM, 97):  # G alpha* = -w (a sample of the cases is plenty)
        g = grasp_map(data["centres"][i], data["frames"][i])
        np.testing.assert_allclose(g @ (-data["w_c"][i]), -w[i], rtol=0, atol=1e-12 * (1 + abs(w[i]).max()))
    feasible = np.empty(N_RANDOM, dtype=bool)
    for i in range(N_RANDOM):
        a, b = constraint_matrix(data["mu"][i], cup)
        scale = np.abs(b) + 1e-300
        feasible[i] = np.all((a @ -data["w_c"][i] - b) / scale <= 1e-9)
    # the closed form uses a 1e-9 relative slack too; anything nearer the boundary than ~1e-9 may
    # differ, and at this sample size none is that near
    assert np.array_equal(feasible, data["closed"])


@pytest.mark.parametrize("cup", PRESETS)
def test_qp_never_resists_what_the_closed_form_rejects(cup):
    # If the QP's minimiser has residual <= 1e-8 there is an alpha in F with G alpha ~= -w, so
    # alpha* = -w_c lies within ~1e-8 (scaled) of F. Away from that sliver of the boundary a QP
    # "resisted" must therefore be a closed-form "resisted" too (no false positives of the QP).
    data = random_results(cup)
    false_pos = np.nonzero(data["qp"] & ~data["closed"])[0]
    for i in false_pos[:10]:
        print(cup.name, i, data["qp_res"][i], -data["w_c"][i])
    assert len(false_pos) <= N_RANDOM // 1000


@pytest.mark.xfail(
    strict=True,
    reason=(
        "BUG in resists_qp: on clearly resisted wrenches (alpha* deep inside F) Clarabel with "
        "CLARABEL_SETTINGS often stops with InsufficientProgress/AlmostSolved/MaxIterations (qpsolvers "
        "then returns None -> reported as not resisted, residual inf) or 'Solved' with a residual "
        "1e-8..1e-6 > QP_RESIDUAL_TOL; the squared-residual objective cannot resolve residuals below "
        "~sqrt(eps) ||D w||. Disagreement ~0.24 % (default) and ~1.3 % (paper), all QP false negatives."
    ),
)
@pytest.mark.parametrize("cup", PRESETS)
def test_closed_form_agrees_with_qp_on_random_cases(cup):
    # Both decide the same question (is -w in G F?), so they must agree except within ~1e-8 of the
    # boundary of F, which random continuous samples essentially never hit: allow <= 0.1 %.
    data = random_results(cup)
    disagree = np.nonzero(data["qp"] != data["closed"])[0]
    if len(disagree):
        margins = relative_margins(-data["w_c"][disagree], data["mu"][disagree], cup)
        print(f"{cup.name}: {len(disagree)} disagreements of {N_RANDOM}")
        for j, i in enumerate(disagree[:20]):
            print(
                f"  case {i}: closed={data['closed'][i]} qp={data['qp'][i]} "
                f"residual={data['qp_res'][i]:.3g} min relative margin={margins[j].min():.3g} "
                f"|w_c|={np.linalg.norm(data['w_c'][i]):.3g}"
            )
    assert len(disagree) <= N_RANDOM // 1000


# --------------------------------------------------------------------------------------------
# 2. Boundary cases: alpha* on, just inside and just outside each of the 11 faces of F
# --------------------------------------------------------------------------------------------

FACES = ["+fx", "+fy", "+tz", "+tx", "+ty", "-fx", "-fy", "-tz", "-tx", "-ty", "suction"]
"""In the row order of `constraint_matrix`."""


def boundary_alpha(face: str, scale: float, mu: float, cup: CupConfig) -> np.ndarray:
    """alpha with the constrained component of `face` at `scale` times its bound, others inside.

    Torque and force are kept orthogonal (f . tau = 0), for every scale, so that a single force at
    a COM produces the wrench (see `force_and_com`): the scaled component's partner in the dot
    product f . tau (f_x <-> tau_x, ...) is set to zero and one free component absorbs the rest.
    """
    v, r, t = cup.vacuum_force, cup.radius, tilt_limit(cup)
    if face == "suction":
        # f_z = -V s: f_N = V (1 - s), so the friction-bounded f_x, f_y, tau_z must vanish; the
        # tilts are free (f . tau = f_z tau_z = 0).
        return np.array([0.0, 0.0, -v * scale, 0.3 * t, -0.2 * t, 0.0])
    sign = 1.0 if face[0] == "+" else -1.0
    comp = face[1:]
    if comp == "tz":
        # tau_z = +-r mu f_N / sqrt(3) s; f . tau = f_z tau_z must not depend on s, so f_z = 0
        # (f_N = V) and tau_x absorbs f_x tau_x + f_y tau_y = 0.
        fx, fy, ty = 0.5 * mu * v / SQRT3, -0.2 * mu * v / SQRT3, 0.2 * t
        return np.array([fx, fy, 0.0, -fy * ty / fx, ty, sign * scale * r * mu * v / SQRT3])
    fz = 0.5 * v  # f_N = 1.5 V
    f_lim = mu * (fz + v) / SQRT3
    alpha = np.array([0.3 * f_lim, -0.2 * f_lim, fz, 0.2 * t, -0.3 * t, 0.0])
    index = {"fx": 0, "fy": 1, "tx": 3, "ty": 4}[comp]
    partner = {0: 3, 1: 4, 3: 0, 4: 1}[index]
    alpha[index] = sign * scale * (f_lim if index < 3 else t)
    alpha[partner] = 0.0
    # tau_z absorbs the orthogonality: f_z tau_z = -(f_x tau_x + f_y tau_y)
    alpha[5] = -(alpha[0] * alpha[3] + alpha[1] * alpha[4]) / fz
    return alpha


BOUNDARY_SCALES = {"on": 1.0, "inside": 1.0 - EPS, "outside": 1.0 + EPS}


@pytest.mark.parametrize("cup", PRESETS)
@pytest.mark.parametrize("face", range(11), ids=FACES)
def test_boundary_faces(cup, face):
    # On and just inside the face: alpha* in F -> resisted. Just outside (relative 1e-3) only
    # this face is violated -> not resisted. Checked (a) on the contact-frame wrench w_c = -alpha
    # directly, (b) on the wrench recomputed from a (force, com) pair, and (c) with the QP.
    mu = 0.5
    rng = np.random.default_rng(100 + face)
    frame = random_frames(rng, 1)[0]
    centre = rng.uniform(-0.05, 0.05, 3)
    a_mat, b_vec = constraint_matrix(mu, cup)
    row_scale = np.abs(b_vec)
    for where, s in BOUNDARY_SCALES.items():
        alpha = boundary_alpha(FACES[face], s, mu, cup)
        # the construction: only row `face` is at/over its bound, all others strictly inside
        slack = (b_vec - a_mat @ alpha) / row_scale
        others = np.delete(slack, face)
        if where == "outside" and FACES[face] == "suction":
            # f_N = -EPS V < 0 also breaks the three friction pairs; the tilts stay inside
            assert slack[face] < 0 and (slack[[3, 4, 8, 9]] > 0.1).all()
        else:
            assert (others > 0.1).all(), (where, slack)
            # the scaled component enters row `face` linearly and alone, so its slack is
            # (1 - s) times the bound at this alpha (the slack with that component zeroed)
            bound = (b_vec - a_mat @ boundary_alpha(FACES[face], 0.0, mu, cup))[face]
            assert bound > 0
            assert (b_vec - a_mat @ alpha)[face] == pytest.approx((1 - s) * bound, abs=1e-12 * bound)
        expected = where != "outside"

        # (a) closed form on the contact-frame wrench itself
        assert resists(-alpha[None], mu, cup)[0] == expected, (where, alpha)

        # (b) and (c): through a single force at a COM
        force, com = force_and_com(alpha, frame, centre)
        w_c = contact_wrench(force, com, centre, frame)
        np.testing.assert_allclose(w_c, -alpha, rtol=0, atol=1e-12 * np.abs(alpha).max())
        assert resists(w_c[None], mu, cup)[0] == expected, (where, w_c)
        ok, residual = qp(force, com, centre, frame, mu, cup)
        assert ok == expected, (where, residual)


# --------------------------------------------------------------------------------------------
# 3. Physical facts of the model
# --------------------------------------------------------------------------------------------

FRAME_SEED = 7


def frame_and_centre(seed: int = FRAME_SEED):
    rng = np.random.default_rng(seed)
    return random_frames(rng, 1)[0], rng.uniform(-0.05, 0.05, 3)


def both_verdicts(force, com, centre, frame, mu, cup) -> tuple[bool, bool]:
    closed = bool(resists(contact_wrench(force, com, centre, frame)[None], mu, cup)[0])
    return closed, qp(force, com, centre, frame, mu, cup)[0]


@pytest.mark.parametrize("cup", PRESETS)
def test_pull_along_approach_limited_by_vacuum(cup):
    # A force F along +z (the approach v, pulling the object away from the cup) acting on the
    # axis has w_c = (0, 0, F, 0, 0, 0), so alpha* = (0, 0, -F, 0, 0, 0): the suction face
    # f_z >= -V gives F <= V, and the friction rows need only 0 <= mu (V - F).
    frame, centre = frame_and_centre()
    v, mu = cup.vacuum_force, cup.friction
    approach = frame[:, 2]
    com = centre + 0.03 * approach
    assert both_verdicts((1 - EPS) * v * approach, com, centre, frame, mu, cup) == (True, True)
    assert both_verdicts((1 + EPS) * v * approach, com, centre, frame, mu, cup) == (False, False)
    # pushing the object into the cup only loads the lip: any magnitude is resisted
    assert both_verdicts(-100 * v * approach, com, centre, frame, mu, cup) == (True, True)


@pytest.mark.parametrize("cup", PRESETS)
@pytest.mark.parametrize("mu", [0.2, 0.5, 1.0])
def test_tangential_force_limited_by_friction(cup, mu):
    # Zero normal load: f_N = V. A tangential force F along the contact x or y axis, through the
    # ring centre (no torque), needs sqrt(3) F <= mu V. (The sqrt(3) box inscribes the friction
    # cone; along a diagonal, |f_x| = |f_y| = F / sqrt(2) and the limit is sqrt(3/2) F <= mu V.)
    frame, centre = frame_and_centre()
    v = cup.vacuum_force
    limit = mu * v / SQRT3
    for axis in (0, 1):
        for sign in (1.0, -1.0):
            direction = sign * frame[:, axis]
            for com in (centre, centre + 0.04 * direction):  # offsets along the force: no torque
                assert both_verdicts((1 - EPS) * limit * direction, com, centre, frame, mu, cup) == (True, True)
                assert both_verdicts((1 + EPS) * limit * direction, com, centre, frame, mu, cup) == (False, False)
    diagonal = (frame[:, 0] + frame[:, 1]) / SQRT2
    assert both_verdicts(1.2 * limit * diagonal, centre, centre, frame, mu, cup) == (True, True)
    diag_limit = mu * v / math.sqrt(1.5)
    assert both_verdicts((1 - EPS) * diag_limit * diagonal, centre, centre, frame, mu, cup) == (True, True)
    assert both_verdicts((1 + EPS) * diag_limit * diagonal, centre, centre, frame, mu, cup) == (False, False)


@pytest.mark.parametrize("cup", PRESETS)
def test_torsion_limited_by_friction_and_normal_force(cup):
    # A torque tau about the contact z axis is resisted iff sqrt(3)|tau| <= r mu (f_z + V), with
    # f_z = -(external normal force) the contact's normal force. Closed form on contact-frame
    # wrenches w_c = (0, 0, -f_z, 0, 0, tau) for several normal loads: pulling (f_z < 0) shrinks
    # the torsion capacity to zero at f_z = -V, pushing (f_z > 0) grows it linearly.
    v, r, mu = cup.vacuum_force, cup.radius, cup.friction
    for f_z in (-0.9 * v, -0.5 * v, 0.0, v, 3 * v):
        limit = r * mu * (f_z + v) / SQRT3
        for sign in (1.0, -1.0):
            for s, expected in ((1 - EPS, True), (1 + EPS, False)):
                w_c = np.array([[0.0, 0.0, -f_z, 0.0, 0.0, sign * s * limit]])
                assert resists(w_c, mu, cup)[0] == expected, (f_z, sign, s)
    # A pure torque is no single force, so for the QP (and the force/com path) the torsion
    # comes from a small tangential force F along x at an offset d along y:
    # (d e_y) x (F e_x) = -d F e_z. F is a tenth of its own friction limit; at f_z = 0 the
    # torsion limit is r mu V / sqrt(3).
    frame, centre = frame_and_centre()
    f = 0.1 * mu * v / SQRT3
    limit = r * mu * v / SQRT3
    for sign in (1.0, -1.0):
        for s, expected in ((1 - EPS, True), (1 + EPS, False)):
            tau = sign * s * limit
            force, com = f * frame[:, 0], centre + (-tau / f) * frame[:, 1]
            w_c = contact_wrench(force, com, centre, frame)
            np.testing.assert_allclose(w_c, [f, 0, 0, 0, 0, tau], atol=1e-12 * v)
            assert both_verdicts(force, com, centre, frame, mu, cup) == (expected, expected), (sign, s)


@pytest.mark.parametrize("cup", PRESETS)
def test_tilting_torque_bound_independent_of_normal_force(cup):
    # The material rows sqrt(2)|tau_x|, sqrt(2)|tau_y| <= pi r kappa contain no f_z: the tilt
    # capacity pi r kappa / sqrt(2) is the same for any admissible normal load. (Default cup:
    # kappa = V / (2 pi), so the bound is r V / (2 sqrt(2)) = 23.4 mN m.)
    v, mu, t = cup.vacuum_force, cup.friction, tilt_limit(cup)
    if cup is CUP_DEFAULT:
        assert t == pytest.approx(cup.radius * v / (2 * SQRT2), rel=1e-12)
    for f_z in (-0.9 * v, -0.5 * v, 0.0, v, 10 * v):
        for axis in (3, 4):
            for sign in (1.0, -1.0):
                for s, expected in ((1 - EPS, True), (1 + EPS, False)):
                    w_c = np.zeros((1, 6))
                    w_c[0, 2], w_c[0, axis] = -f_z, sign * s * t
                    assert resists(w_c, mu, cup)[0] == expected, (f_z, axis, sign, s)
    # Through a force: an external normal force N = -f_z (along +z) at an offset d in the cup
    # plane gives tilting torques (d e_y) x (N e_z) = d N e_x and (d e_x) x (N e_z) = -d N e_y.
    frame, centre = frame_and_centre()
    for f_z in (-0.9 * v, -0.5 * v, v, 10 * v):
        n_ext = -f_z
        for axis, (offset_axis, torque_sign) in {3: (1, 1.0), 4: (0, -1.0)}.items():
            for sign in (1.0, -1.0):
                for s, expected in ((1 - EPS, True), (1 + EPS, False)):
                    tau = sign * s * t
                    d = tau / (torque_sign * n_ext)
                    force, com = n_ext * frame[:, 2], centre + d * frame[:, offset_axis]
                    w_c = contact_wrench(force, com, centre, frame)
                    target = np.zeros(6)
                    target[2], target[axis] = n_ext, tau
                    np.testing.assert_allclose(w_c, target, rtol=0, atol=1e-12 * abs(n_ext))
                    assert both_verdicts(force, com, centre, frame, mu, cup) == (expected, expected), (
                        f_z, axis, sign, s,
                    )


# --------------------------------------------------------------------------------------------
# 4. The grasp map
# --------------------------------------------------------------------------------------------


def test_grasp_map_is_the_invertible_adjoint():
    # G = [[R, 0], [[o]x R, R]] is block lower-triangular with diagonal blocks R, so
    # det G = det(R)^2 = 1 and G^-1 = [[R^T, 0], [-R^T [o]x, R^T]]. G^-1 w, w = (f, c x f) about
    # the object origin, is the same wrench about o in the contact frame:
    # (R^T f, R^T (c x f - o x f)) = (R^T f, R^T ((c - o) x f)) = external_wrench_at_contact (same
    # sign: alpha* = -G^-1 w is the contact's answer, the minus belongs to alpha*, not to w_c).
    rng = np.random.default_rng(4)
    n = 200
    frames = random_frames(rng, n)
    centres = rng.uniform(-0.1, 0.1, (n, 3))
    force = rng.normal(size=(n, 3)) * 5.0
    com = rng.uniform(-0.1, 0.1, (n, 3))
    w_c = external_wrench_at_contact(force, com, centres, frames)
    for i in range(n):
        r_mat, o = frames[i], centres[i]
        g = grasp_map(o, r_mat)
        assert np.linalg.det(g) == pytest.approx(1.0, abs=1e-12)
        ox = np.array([[0, -o[2], o[1]], [o[2], 0, -o[0]], [-o[1], o[0], 0]])
        expected = np.block([[r_mat, np.zeros((3, 3))], [ox @ r_mat, r_mat]])
        np.testing.assert_allclose(g, expected, rtol=0, atol=1e-15)
        g_inv = np.block([[r_mat.T, np.zeros((3, 3))], [-r_mat.T @ ox, r_mat.T]])
        np.testing.assert_allclose(g_inv @ g, np.eye(6), rtol=0, atol=1e-14)
        w = np.concatenate([force[i], np.cross(com[i], force[i])])
        np.testing.assert_allclose(np.linalg.solve(g, w), w_c[i], rtol=0, atol=1e-12)
        np.testing.assert_allclose(g_inv @ w, w_c[i], rtol=0, atol=1e-12)
        # column j of G: the j-th contact-frame basis wrench about the object origin, e.g. a unit
        # force along the contact z axis applied at o has torque o x z about the origin
        np.testing.assert_allclose(g[:, 2], np.concatenate([r_mat[:, 2], np.cross(o, r_mat[:, 2])]))
        np.testing.assert_allclose(g[:, 5], np.concatenate([np.zeros(3), r_mat[:, 2]]))
