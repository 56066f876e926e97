"""Tests of the suction-ring wrench-resistance model (suctionbench/contact/wrench.py).

Notation (module docstring of wrench.py): contact frame R (columns x, y, z = v, z into the
object), ring centre o. The contact applies alpha = (f_x, f_y, f_z, tau_x, tau_y, tau_z) (contact
frame, about o) on top of the vacuum pull V, with lip normal force f_N = f_z + V. F is

    sqrt(3)|f_x| <= mu f_N,  sqrt(3)|f_y| <= mu f_N,  sqrt(3)|tau_z| <= r mu f_N,  f_z >= -V,
    ||(tau_x, tau_y)|| <= r f_N / 2                       (ring pressure: default cup)
    sqrt(2)|tau_x| <= pi r kappa,  sqrt(2)|tau_y| <= pi r kappa      (the paper's box: paper preset)

An external force f acting at the centre of mass c has, about o and in the contact frame, the
wrench w_c = (R^T f, R^T ((c - o) x f)) (= `external_wrench_at_contact`). The grasp resists iff
alpha* = -w_c lies in F (`resists`), or, equivalently, iff min_{alpha in F} ||G alpha + w|| = 0
with w = (f, c x f) about the object origin (`resists_qp`, a cone program for the ring limit).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

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
    """Tilt bound at zero axial load: ||(tau_x, tau_y)|| <= r V / 2 for the ring (p(theta) >= 0
    with 2 pi p0 = V and ||tau|| = pi r sqrt(p_x^2 + p_y^2) <= pi r p0); for the paper's box the
    largest |tau_x| (= largest |tau_y|), pi r kappa / sqrt(2)."""
    if cup.kappa is None:
        return cup.radius * cup.vacuum_force / 2.0
    return math.pi * cup.radius * cup.kappa / SQRT2


def faces(cup: CupConfig) -> list[str]:
    """The faces of F in the row order of `constraint_matrix`, the ring's tilt cone last."""
    if cup.kappa is None:
        return ["+fx", "+fy", "+tz", "-fx", "-fy", "-tz", "suction", "tilt"]
    return ["+fx", "+fy", "+tz", "+tx", "+ty", "-fx", "-fy", "-tz", "-tx", "-ty", "suction"]


def slacks(alpha: np.ndarray, mu: float, cup: CupConfig) -> np.ndarray:
    """b - A alpha for the linear rows, then (ring only) the cone slack r f_N / 2 - ||tau_t||."""
    a_mat, b_vec = constraint_matrix(mu, cup)
    out = b_vec - a_mat @ alpha
    if cup.kappa is None:
        out = np.append(out, cup.radius * (alpha[2] + cup.vacuum_force) / 2 - math.hypot(alpha[3], alpha[4]))
    return out


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
            force=force,
            com=com,
            centres=centres,
            frames=frames,
            mu=mu,
            w_c=w_c,
            closed=closed,
            qp=qp_ok,
            qp_res=qp_res,
        )
    return _CACHE[cup.name]


def relative_margins(alpha: np.ndarray, mu: np.ndarray, cup: CupConfig) -> np.ndarray:
    """(n, faces) slacks of F in the order of `faces`, forces in units of V and torques in units
    of their bound at zero load."""
    v, r = cup.vacuum_force, cup.radius
    f_n = alpha[:, 2] + v
    t = tilt_limit(cup)
    cols = []
    for sign in (1.0, -1.0):
        cols += [
            (mu * f_n - sign * SQRT3 * alpha[:, 0]) / v,
            (mu * f_n - sign * SQRT3 * alpha[:, 1]) / v,
            (r * mu * f_n - sign * SQRT3 * alpha[:, 5]) / (r * v),
        ]
        if cup.kappa is not None:
            cols += [(t - sign * alpha[:, 3]) / t, (t - sign * alpha[:, 4]) / t]
    cols.append(f_n / v)
    if cup.kappa is None:
        cols.append((r * f_n / 2 - np.hypot(alpha[:, 3], alpha[:, 4])) / t)
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
    # Faces in the order of `faces(cup)`. The suction face is never violated alone (f_N < 0 also
    # violates mu f_N >= sqrt(3)|f_x| and, for the ring, r f_N / 2 >= ||tau_t||), so require only
    # that it is violated. For the paper preset (V = 250 N, r mu V / sqrt(3) >> tilt limit) the
    # tau_z faces can only bind together with the tilt faces, as torques are sampled on the tilt
    # scale.
    names = faces(cup)
    torsion = [names.index("+tz"), names.index("-tz")]
    suction = names.index("suction")
    must_be_sole = [i for i in range(len(names)) if i != suction and (cup.kappa is None or i not in torsion)]
    assert (only[:, must_be_sole].sum(axis=0) >= 20).all(), only.sum(axis=0)
    assert violated[:, suction].sum() >= 20
    assert violated[:, torsion].any(axis=1).sum() >= 20


@pytest.mark.parametrize("cup", PRESETS)
def test_closed_form_is_the_linear_feasibility_test(cup):
    # Independent of the QP: G is invertible, so -w = G alpha has the single solution
    # alpha* = -G^-1 w = -w_c; resistance is exactly "every slack of F at alpha* is >= 0": the
    # linear rows (A, b) = constraint_matrix and, for the ring, the cone r f_N / 2 >= ||tau_t||.
    data = random_results(cup)
    w = np.concatenate([data["force"], np.cross(data["com"], data["force"])], axis=1)
    for i in range(0, N_RANDOM, 97):  # G alpha* = -w (a sample of the cases is plenty)
        g = grasp_map(data["centres"][i], data["frames"][i])
        np.testing.assert_allclose(g @ (-data["w_c"][i]), -w[i], rtol=0, atol=1e-12 * (1 + abs(w[i]).max()))
    feasible = np.empty(N_RANDOM, dtype=bool)
    for i in range(N_RANDOM):
        bound = np.abs(slacks(np.zeros(6), data["mu"][i], cup))  # every bound at zero load, > 0
        feasible[i] = np.all(slacks(-data["w_c"][i], data["mu"][i], cup) / bound >= -1e-9)
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
# Single labelled cases (boundary faces, physical facts), run through every path
# --------------------------------------------------------------------------------------------


@dataclass
class Case:
    """One external load with its expected verdict and expected contact-frame wrench."""

    label: str
    force: np.ndarray
    com: np.ndarray
    centre: np.ndarray
    frame: np.ndarray
    mu: float
    w_c: np.ndarray  # expected external_wrench_at_contact(force, com, centre, frame)
    expected: bool


def check_closed_form(case: Case, cup: CupConfig) -> None:
    """The closed form on the intended w_c and on the one recomputed from (force, com)."""
    w_c = contact_wrench(case.force, case.com, case.centre, case.frame)
    scale = np.abs(case.w_c).max()
    np.testing.assert_allclose(w_c, case.w_c, rtol=0, atol=1e-12 * scale, err_msg=case.label)
    assert resists(case.w_c[None], case.mu, cup)[0] == case.expected, case.label
    assert resists(w_c[None], case.mu, cup)[0] == case.expected, case.label


# --------------------------------------------------------------------------------------------
# 2. Boundary cases: alpha* on, just inside and just outside each face of F
# --------------------------------------------------------------------------------------------

BOUNDARY_SCALES = {"on": 1.0, "inside": 1.0 - EPS, "outside": 1.0 + EPS}
BOUNDARY_MU = 0.5
BOUNDARY_PARAMS = [pytest.param(c, f, id=f"{c.name}{f}") for c in (CUP_DEFAULT, CUP_PAPER) for f in faces(c)]


def boundary_alpha(face: str, scale: float, mu: float, cup: CupConfig) -> np.ndarray:
    """alpha with the constrained component of `face` at `scale` times its bound, others inside.

    Torque and force are kept orthogonal (f . tau = 0) for every scale, so that a single force at
    a COM produces the wrench (see `force_and_com`): the scaled component's partner in the dot
    product f . tau (f_x <-> tau_x, ...) is set to zero and one free component absorbs the rest.
    Pure-torque faces (tau_x, tau_y, tau_z) thus come from a force plus an offset.
    """
    v, r, t = cup.vacuum_force, cup.radius, tilt_limit(cup)
    ring = cup.kappa is None
    if face == "suction":
        # f_z = -V s: f_N = V (1 - s), so the friction-bounded f_x, f_y, tau_z must vanish, and
        # with the ring limit r f_N / 2 the tilts too; the paper's box leaves the tilts free
        # (f . tau = f_z tau_z = 0). The force is a pure pull along the axis.
        return np.array([0.0, 0.0, -v * scale, 0.0 if ring else 0.3 * t, 0.0 if ring else -0.2 * t, 0.0])
    fz = 0.5 * v  # f_N = 1.5 V
    f_lim = mu * (fz + v) / SQRT3
    if face == "tilt":
        # ||tau_t|| = s r f_N / 2 at a bearing of 35 degrees; tau_z absorbs f . tau = 0 (it stays
        # under half its torsion bound: |f_t| |tau_t| / f_z <= 0.36 f_lim 0.75 r V / (0.5 V)).
        psi = math.radians(35.0)
        tau = scale * r * (fz + v) / 2 * np.array([math.cos(psi), math.sin(psi)])
        fx, fy = 0.3 * f_lim, -0.2 * f_lim
        return np.array([fx, fy, fz, tau[0], tau[1], -(fx * tau[0] + fy * tau[1]) / fz])
    sign = 1.0 if face[0] == "+" else -1.0
    comp = face[1:]
    if comp == "tz":
        # tau_z = +-r mu f_N / sqrt(3) s; f . tau = f_z tau_z must not depend on s, so f_z = 0
        # (f_N = V) and tau_x absorbs f_x tau_x + f_y tau_y = 0.
        fx, fy, ty = 0.5 * mu * v / SQRT3, -0.2 * mu * v / SQRT3, 0.2 * t
        return np.array([fx, fy, 0.0, -fy * ty / fx, ty, sign * scale * r * mu * v / SQRT3])
    alpha = np.array([0.3 * f_lim, -0.2 * f_lim, fz, 0.2 * t, -0.3 * t, 0.0])
    index = {"fx": 0, "fy": 1, "tx": 3, "ty": 4}[comp]
    partner = {0: 3, 1: 4, 3: 0, 4: 1}[index]
    alpha[index] = sign * scale * (f_lim if index < 3 else t)
    alpha[partner] = 0.0
    # tau_z absorbs the orthogonality: f_z tau_z = -(f_x tau_x + f_y tau_y)
    alpha[5] = -(alpha[0] * alpha[3] + alpha[1] * alpha[4]) / fz
    return alpha


def boundary_cases(cup: CupConfig, face: str) -> list[Case]:
    rng = np.random.default_rng(100 + faces(cup).index(face))
    frame = random_frames(rng, 1)[0]
    centre = rng.uniform(-0.05, 0.05, 3)
    cases = []
    for where, s in BOUNDARY_SCALES.items():
        alpha = boundary_alpha(face, s, BOUNDARY_MU, cup)
        force, com = force_and_com(alpha, frame, centre)
        label = f"{cup.name} {face} {where}"
        cases.append(Case(label, force, com, centre, frame, BOUNDARY_MU, -alpha, where != "outside"))
    return cases


@pytest.mark.parametrize("cup, face", BOUNDARY_PARAMS)
def test_boundary_face_construction(cup, face):
    # The construction itself: with the slacks of F (`slacks`: b - A alpha of constraint_matrix,
    # then the ring's cone slack r f_N / 2 - ||tau_t||), row `face` has slack (1 - s) times its
    # bound (the scaled component enters that row linearly and alone, so the bound is the slack
    # with the component zeroed), every other row is well inside (> 10 % of its bound). On the
    # suction face f_N = V (1 - s) also scales the six friction rows (f_x = f_y = tau_z = 0
    # there) and the ring's cone (tau_t = 0), so they share the suction row's slack (1 - s).
    names = faces(cup)
    if face == "suction":
        tight = [i for i, n in enumerate(names) if n[1:] in ("fx", "fy", "tz") or n in ("suction", "tilt")]
    else:
        tight = [names.index(face)]
    reference = np.abs(slacks(np.zeros(6), BOUNDARY_MU, cup))  # every bound at zero load, > 0
    for s in BOUNDARY_SCALES.values():
        alpha = boundary_alpha(face, s, BOUNDARY_MU, cup)
        zeroed = boundary_alpha(face, 0.0, BOUNDARY_MU, cup)
        slack = slacks(alpha, BOUNDARY_MU, cup)
        bound = slacks(zeroed, BOUNDARY_MU, cup)[tight]
        assert (bound > 0).all()
        np.testing.assert_allclose(slack[tight], (1 - s) * bound, rtol=0, atol=1e-12 * bound.max())
        others = np.delete(slack / reference, tight)
        assert (others > 0.1).all(), (s, slack / reference)


@pytest.mark.parametrize("cup, face", BOUNDARY_PARAMS)
def test_boundary_faces_closed_form(cup, face):
    # On the face and 1e-3 inside: alpha* = -w_c in F -> resisted. 1e-3 outside: only this face
    # (and, for suction, the friction rows and the ring's cone that f_N < 0 breaks) is violated
    # -> not resisted. The closed form's 1e-9 slack absorbs the rounding of the (force, com)
    # round trip on the face.
    for case in boundary_cases(cup, face):
        check_closed_form(case, cup)


# --------------------------------------------------------------------------------------------
# 3. Physical facts of the model
# --------------------------------------------------------------------------------------------


def frame_and_centre(seed: int = 7):
    rng = np.random.default_rng(seed)
    return random_frames(rng, 1)[0], rng.uniform(-0.05, 0.05, 3)


def pull_cases(cup: CupConfig) -> list[Case]:
    # A force F along +z (the approach v, pulling the object away from the cup) acting on the
    # axis has w_c = (0, 0, F, 0, 0, 0), so alpha* = (0, 0, -F, 0, 0, 0): the suction face
    # f_z >= -V gives F <= V; the friction rows need only 0 <= mu (V - F). Pushing the object into
    # the cup (F < 0) only loads the lip: any magnitude is resisted.
    frame, centre = frame_and_centre()
    v, mu, z = cup.vacuum_force, cup.friction, frame[:, 2]
    com = centre + 0.03 * z
    cases = []
    for s in (0.5, 1 - EPS, 1 + EPS, 2.0, -1.0, -100.0):
        w_c = np.array([0.0, 0.0, s * v, 0.0, 0.0, 0.0])
        cases.append(Case(f"{cup.name} pull {s}V", s * v * z, com, centre, frame, mu, w_c, s <= 1))
    return cases


def tangential_cases(cup: CupConfig) -> list[Case]:
    # Zero normal load: f_N = V. A tangential force F along the contact x or y axis through the
    # ring centre (or with the COM offset along the force line: still no torque) needs
    # sqrt(3) F <= mu V. The sqrt(3) box is inscribed in the friction cone: along the diagonal,
    # |f_x| = |f_y| = F / sqrt(2), so there the limit is sqrt(3/2) F <= mu V instead.
    frame, centre = frame_and_centre()
    v = cup.vacuum_force
    cases = []
    for mu in (0.2, 0.5, 1.0):
        limit = mu * v / SQRT3
        for axis in (0, 1):
            for sign in (1.0, -1.0):
                direction = sign * frame[:, axis]
                for offset in (0.0, 0.04):
                    for s in (1 - EPS, 1 + EPS):
                        w_c = np.zeros(6)
                        w_c[axis] = sign * s * limit
                        cases.append(
                            Case(
                                f"{cup.name} tangential mu={mu} axis={axis} sign={sign} {s}",
                                s * limit * direction,
                                centre + offset * direction,
                                centre,
                                frame,
                                mu,
                                w_c,
                                s < 1,
                            )
                        )
        diagonal = (frame[:, 0] + frame[:, 1]) / SQRT2
        diag_limit = mu * v / math.sqrt(1.5)
        for s in (1.2 * limit / diag_limit, 1 - EPS, 1 + EPS):
            w_c = np.array([1.0, 1.0, 0, 0, 0, 0]) * s * diag_limit / SQRT2
            force, label = s * diag_limit * diagonal, f"{cup.name} diagonal mu={mu} {s}"
            cases.append(Case(label, force, centre, centre, frame, mu, w_c, s < 1))
    return cases


def torsion_cases(cup: CupConfig) -> list[Case]:
    # A pure torque is no single force, so the torsion about z comes from a small tangential force
    # F e_x at an offset d e_y: (d e_y) x (F e_x) = -d F e_z, zero normal load (f_N = V), torsion
    # limit r mu V / sqrt(3). F is a tenth of its own friction limit, so only the torsion face binds.
    frame, centre = frame_and_centre()
    v, r, mu = cup.vacuum_force, cup.radius, cup.friction
    f = 0.1 * mu * v / SQRT3
    limit = r * mu * v / SQRT3
    cases = []
    for sign in (1.0, -1.0):
        for s in (1 - EPS, 1 + EPS):
            tau = sign * s * limit
            cases.append(
                Case(
                    f"{cup.name} torsion sign={sign} {s}",
                    f * frame[:, 0],
                    centre + (-tau / f) * frame[:, 1],
                    centre,
                    frame,
                    mu,
                    np.array([f, 0, 0, 0, 0, tau]),
                    s < 1,
                )
            )
    return cases


def tilt_bearings(cup: CupConfig) -> list[float]:
    """Bearings (deg) of the tilting torque probed: the ring limit is a circle, so any bearing
    (the diagonal included, where the paper's box reaches sqrt(2) further); the box is probed
    along its axes."""
    return [0.0, 45.0, 90.0, 200.0, 315.0] if cup.kappa is None else [0.0, 90.0, 180.0, 270.0]


def tilt_bound_at(cup: CupConfig, f_z: float) -> float:
    """Largest ||(tau_x, tau_y)|| along the probed bearings at contact normal force f_z: the ring
    pressure p(theta) = p0 + p_x cos + p_y sin >= 0 with 2 pi p0 = V + f_z gives
    ||tau|| <= pi r p0 = r (V + f_z) / 2; the paper's box does not depend on f_z."""
    if cup.kappa is None:
        return cup.radius * (cup.vacuum_force + f_z) / 2.0
    return tilt_limit(cup)


def tilt_cases(cup: CupConfig) -> list[Case]:
    # An external normal force N = -f_z (along +z) at an in-plane offset d = (d_x, d_y) gives the
    # tilting torque d x (N e_z) = N (d_y, -d_x, 0): for a target tau_t, d_y = tau_x / N and
    # d_x = -tau_y / N. Probed at 1e-3 inside and outside the bound, for pulls (f_z < 0) and
    # pushes (f_z > 0) alike.
    frame, centre = frame_and_centre()
    v, mu = cup.vacuum_force, cup.friction
    cases = []
    for f_z in (-0.9 * v, -0.5 * v, v, 10 * v):
        n_ext = -f_z
        for bearing in tilt_bearings(cup):
            u = np.array([math.cos(math.radians(bearing)), math.sin(math.radians(bearing))])
            for s in (1 - EPS, 1 + EPS):
                tau = s * tilt_bound_at(cup, f_z) * u
                w_c = np.array([0.0, 0.0, n_ext, tau[0], tau[1], 0.0])
                com = centre + (tau[0] / n_ext) * frame[:, 1] - (tau[1] / n_ext) * frame[:, 0]
                label = f"{cup.name} tilt f_z={f_z / v}V bearing={bearing} {s}"
                cases.append(Case(label, n_ext * frame[:, 2], com, centre, frame, mu, w_c, s < 1))
    return cases


@pytest.mark.parametrize("cup", PRESETS)
def test_pull_along_approach_limited_by_vacuum(cup):
    for case in pull_cases(cup):
        check_closed_form(case, cup)


@pytest.mark.parametrize("cup", PRESETS)
def test_tangential_force_limited_by_friction(cup):
    for case in tangential_cases(cup):
        check_closed_form(case, cup)


@pytest.mark.parametrize("cup", PRESETS)
def test_torsion_limited_by_friction_and_normal_force(cup):
    # sqrt(3)|tau_z| <= r mu (f_z + V), f_z the contact's normal force (= -external normal
    # force): pulling (f_z < 0) shrinks the torsion capacity to zero at f_z = -V, pushing grows it
    # linearly. A normal load plus a torsion is no single force (f . tau != 0), so the normal-load
    # dependence is checked on contact-frame wrenches w_c = (0, 0, -f_z, 0, 0, tau).
    v, r, mu = cup.vacuum_force, cup.radius, cup.friction
    for f_z in (-0.9 * v, -0.5 * v, 0.0, v, 3 * v):
        limit = r * mu * (f_z + v) / SQRT3
        for sign in (1.0, -1.0):
            for s, expected in ((1 - EPS, True), (1 + EPS, False)):
                w_c = np.array([[0.0, 0.0, -f_z, 0.0, 0.0, sign * s * limit]])
                assert resists(w_c, mu, cup)[0] == expected, (f_z, sign, s)
    for case in torsion_cases(cup):  # and through a force at a COM, at zero normal load
        check_closed_form(case, cup)


def test_ring_tilt_limit_is_a_circle_shrinking_with_the_pull():
    # Default cup (ring pressure): ||(tau_x, tau_y)|| <= r (V + f_z) / 2 at every bearing. At zero
    # load that is r V / 2 = 7.5 mm x 7.964 N / 2 = 29.9 mN m; a 0.2 kg object hanging from the cup
    # (f_z = -1.96 N) leaves 22.5 mN m; at f_z = -V nothing. Along the diagonal the paper's box
    # would allow sqrt(2) more: the ring does not.
    cup = CUP_DEFAULT
    v, mu, r = cup.vacuum_force, cup.friction, cup.radius
    assert tilt_bound_at(cup, 0.0) == pytest.approx(0.02986, abs=1e-5)
    assert tilt_bound_at(cup, -0.2 * 9.80665) == pytest.approx(0.02251, abs=1e-5)
    for f_z in (-0.999 * v, -0.9 * v, -0.5 * v, 0.0, v, 10 * v):
        for bearing in range(0, 360, 15):
            u = np.array([math.cos(math.radians(bearing)), math.sin(math.radians(bearing))])
            for s, expected in ((1 - EPS, True), (1 + EPS, False)):
                tau = s * r * (v + f_z) / 2 * u
                w_c = np.array([[0.0, 0.0, -f_z, tau[0], tau[1], 0.0]])
                assert resists(w_c, mu, cup)[0] == expected, (f_z, bearing, s)
    # the bound scales with the vacuum the seal actually holds (a leaking seal holds less)
    w_c = np.array([[0.0, 0.0, 0.0, 0.9 * r * v / 2, 0.0, 0.0]])
    assert resists(w_c, mu, cup, vacuum_force=v)[0]
    assert not resists(w_c, mu, cup, vacuum_force=0.8 * v)[0]
    for case in tilt_cases(cup):
        check_closed_form(case, cup)


def test_paper_box_tilt_bound_independent_of_normal_force():
    # The paper's material rows sqrt(2)|tau_x|, sqrt(2)|tau_y| <= pi r kappa contain no f_z: the
    # tilt capacity pi r kappa / sqrt(2) = 83 uN m (kappa = 0.005) is the same for every
    # admissible normal load, including zero (a pure tilting torque, checked on w_c directly).
    cup = CUP_PAPER
    v, mu, t = cup.vacuum_force, cup.friction, tilt_limit(cup)
    assert t == pytest.approx(math.pi * 0.0075 * 0.005 / SQRT2, rel=1e-12)
    for f_z in (-0.9 * v, -0.5 * v, 0.0, v, 10 * v):
        for axis in (3, 4):
            for sign in (1.0, -1.0):
                for s, expected in ((1 - EPS, True), (1 + EPS, False)):
                    w_c = np.zeros((1, 6))
                    w_c[0, 2], w_c[0, axis] = -f_z, sign * s * t
                    assert resists(w_c, mu, cup)[0] == expected, (f_z, axis, sign, s)
    for case in tilt_cases(cup):
        check_closed_form(case, cup)


# --------------------------------------------------------------------------------------------
# The QP reference on the same single cases
# --------------------------------------------------------------------------------------------


def all_single_cases(cup: CupConfig) -> list[Case]:
    cases = [c for face in faces(cup) for c in boundary_cases(cup, face)]
    cases += pull_cases(cup) + tangential_cases(cup) + torsion_cases(cup) + tilt_cases(cup)
    return cases


@pytest.mark.parametrize("cup", PRESETS)
def test_qp_rejects_every_case_outside_F(cup):
    # Just outside F (1e-3 relative beyond one face) the distance from -w to G F is positive, so
    # min ||D (G alpha + w)|| > QP_RESIDUAL_TOL: the QP must say "not resisted". The smallest such
    # distance here is the paper preset's tilt face: 1e-3 x 8.3e-5 N m / (r V) = 4.4e-8 > 1e-8.
    # The ring's cone enters the reference as a second-order cone (Clarabel) plus tangent cuts in
    # its polish, and the verdict comes from a point of F, so this also checks the cone handling.
    wrong = []
    for case in all_single_cases(cup):
        if not case.expected:
            ok, residual = qp(case.force, case.com, case.centre, case.frame, case.mu, cup)
            if ok:
                wrong.append((case.label, residual))
    assert not wrong, wrong


@pytest.mark.parametrize("cup", PRESETS)
def test_qp_resists_every_case_on_or_inside_F(cup):
    # On the face or 1e-3 inside, alpha* = -w_c lies in F and G alpha* = -w exactly, so the QP's
    # minimum residual is 0 and it must say "resisted".
    wrong = []
    for case in all_single_cases(cup):
        if case.expected:
            ok, residual = qp(case.force, case.com, case.centre, case.frame, case.mu, cup)
            if not ok:
                wrong.append((case.label, residual))
    for label, residual in wrong:
        print(f"QP rejects {label}: residual {residual:.3g}")
    assert not wrong, f"{len(wrong)} wrongly rejected"


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
