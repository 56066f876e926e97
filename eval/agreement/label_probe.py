"""Probes behind eval/README.md, agreement "Now: the perturbed samples press where each lip lands".

Usage:
  python eval/agreement/label_probe.py samples OBJECT:SEED [OBJECT:SEED ...]
      the robust label of an agreement trial taken apart: the share of its perturbed samples that
      seal, that seal and resist every load case, and that leave the object put under the press.
  python eval/agreement/label_probe.py lip [FIELD=VALUE,...|-] OBJECT:SEED [OBJECT:SEED ...]
      the simulated trial (SimCupConfig fields overridden, e.g. lip_armature=0.05) and the second
      harmonic of its lip points' folds at the lift's start and peak: the profile the lip's springs
      feel, to compare with the labeller's lip heights (seal model, thin lip at the cup radius).
  python eval/agreement/label_probe.py conform RADIUS_MM [FIELD=VALUE,...|-]
      the cup rig (suctionbench.sim.rig) pressed on a lying cylinder (a MuJoCo primitive): the
      second harmonic of the lip points' folds at the end of the vacuum's dwell, beside the thin
      lip's profile h(t) = R - sqrt(R^2 - r^2 sin^2 t) (SimCupConfig fields overridden as for lip;
      a tuple's items separated by ';', e.g. contact_solimp=0.99;0.999;0.0005).
  python eval/agreement/label_probe.py lag OBJECT:SEED [OBJECT:SEED ...]
      the labeller's planned swing for the trial's nominal grasp, step by step, with the cup's
      vacuum lagging its leak (first order, the simulated cup's 30 ms): where the lip's moment
      passes the ring limit r N / 2 its lifted side leaks (a flat face's spring ring, no seal-gap
      allowance), the vacuum falls towards what the ejector holds against that leak, and the lip
      peels if the moment reaches the rim, r N, or the vacuum the part-present switch. Prints the
      peak moment over the ring limit, the lowest vacuum and the verdict, beside the profile's
      largest lip height (the flat-face model holds only where it is ~0).
  python eval/agreement/label_probe.py peel
      the quasi-static peel criterion with the labeller's spring ring (48 places of rate K / 48, a
      lifted place leaking its gap x arc, the ejector's vacuum): the largest tilting moment a flat
      face and lying cylinders hold with and without the lifted lip's leak.
  python eval/agreement/label_probe.py ring NORMAL_N PLACES BEARING_DEG AMPLITUDE_MM [...]
      the largest tilting moment (its torque vector at BEARING_DEG from the contact frame's x axis)
      a spring ring of PLACES places carries under the normal force NORMAL_N without lifting
      anywhere, on a lying cylinder's profile -a cos(2 theta) of second harmonic a = AMPLITUDE_MM:
      the labeller's lip (48 places, the seal model's profile) beside the simulated one (16 points).
  python eval/agreement/label_probe.py friction
      the friction a ring of lip pressure carries, exactly (tractions of at most mu p per unit
      angle at 720 places round the ring, the largest multiple of each load direction solved as a
      cone program), for an evenly pressed lip and for one tilted to the ring limit (p = p0 (1 +
      cos theta), lifted at theta = pi), beside what the paper's sqrt(3) box, the even share's
      double cone |f_t| + |tau_z| / r <= mu 2 pi min p and the hull of the ring's two pure
      strategies (all the lip sliding one way, or all twisting; `_hull_carries`, in closed form) allow. Units:
      f / (mu f_N), tau_z / (r mu f_N).
"""

from __future__ import annotations

import dataclasses
import math
import sys

import numpy as np
from lift_probe import _label_trial, _runner  # the agreement trial (this folder's scripts share it)

from suctionbench.config import CUP_DEFAULT, LabelConfig
from suctionbench.contact import robust, wrench
from suctionbench.contact import swing as swing_model
from suctionbench.contact.labeller import SuctionLabeller
from suctionbench.sim.cup import SIM_CUP_DEFAULT
from suctionbench.vacuum import equilibrium_vacuum, vacuum_force


def samples(key: str, seed: int) -> None:
    """Print the robust label's samples taken apart (module docstring)."""
    seen: dict = {}
    evaluate, stays = robust.evaluate_samples, robust.stays_put

    def spy_evaluate(seal, grasps, cases):
        ok, landed = evaluate(seal, grasps, cases)
        seen["seal"] = seal.evaluate(grasps.points, grasps.frames).seal
        seen["resists"] = ok
        return ok, landed

    def spy_stays(*args, **kwargs):
        seen["stays"] = stays(*args, **kwargs)
        return seen["stays"]

    robust.evaluate_samples, robust.stays_put = spy_evaluate, spy_stays
    try:
        labels = _label_trial(key, seed)[-1]
    finally:
        robust.evaluate_samples, robust.stays_put = evaluate, stays
    put = seen.get("stays")
    print(f"{key} seed {seed}: seal {labels['label_seal']} ({labels['label_seal_failure']}), nominal "
          f"{labels['label_wr']}, rwr {labels['label_rwr']}; samples: seal {seen['seal'].mean():.2f}, seal and "
          f"resist {seen['resists'].mean():.2f}, stay put {'-' if put is None else f'{put.mean():.2f}'}")


def _sim_cup(overrides: str):
    """SIM_CUP_DEFAULT with FIELD=VALUE overrides ("-": none; a tuple's items separated by ';')."""
    fields = {} if overrides == "-" else dict(kv.split("=") for kv in overrides.split(","))

    def value(text: str):
        if ";" in text:
            return tuple(float(x) for x in text.split(";"))
        return int(text) if text.isdigit() else float(text)

    return dataclasses.replace(SIM_CUP_DEFAULT, **{k: value(v) for k, v in fields.items()})


def _harmonics(folds: np.ndarray) -> tuple[np.ndarray, complex]:
    """Folds at evenly spaced places round the lip taken apart: (mean, cos, sin) coefficients (the
    bellows' plane) and the second harmonic (complex amplitude, m) of what is left."""
    theta = wrench.lip_angles(len(folds))
    basis = np.column_stack([np.ones_like(theta), np.cos(theta), np.sin(theta)])
    first = np.linalg.lstsq(basis, folds, rcond=None)[0]
    return first, 2.0 * np.mean((folds - basis @ first) * np.exp(2j * theta))


def conform(radius_mm: float, overrides: str) -> None:
    """Print the rig's lip folds on a lying cylinder against the thin lip (module docstring)."""
    sys.path.insert(0, "tests")
    from test_cup_physics import lying_cylinder  # the physics tests' cylinder

    from suctionbench.sim.rig import CupRig

    radius = 1e-3 * radius_mm
    t = np.linspace(0.0, 2.0 * math.pi, 3600, endpoint=False)
    thin = abs(2.0 * np.mean((radius - np.sqrt(radius**2 - (CUP_DEFAULT.radius * np.sin(t)) ** 2)) * np.exp(2j * t)))
    rig = CupRig(lying_cylinder(radius), sim=_sim_cup(overrides))
    run, after = rig._run, []

    def recording(*args, **kwargs):  # settle, move, approach, dwell, ...: keep the folds after each
        out = run(*args, **kwargs)
        after.append(-rig.data.qpos[rig.cup.lip_qpos].copy())
        return out

    rig._run = recording
    result = rig.grasp([0.0, 0.0, 2.0 * radius])
    second = abs(_harmonics(after[3])[1])
    print(f"lying cylinder R {radius_mm} mm ({overrides}): folds' second harmonic {1e3 * second:.3f} mm, the thin "
          f"lip's {1e3 * thin:.3f} mm ({second / thin:.3f}); sealed {result.sealed}, lifted {result.lifted}")


def lip(overrides: str, key: str, seed: int) -> None:
    """Print the simulated lip's fold harmonics (module docstring)."""
    runner = _runner(key, seed, _sim_cup(overrides))
    episode = runner.episode
    cup_state, cup = episode.cup, episode.cup.cup
    k = cup_state.sim.lip_point_stiffness(cup)
    theta = wrench.lip_angles(len(cup_state.lip_qpos))
    steps: list = []

    def record(data, controller) -> None:
        if episode.motion == "lift":
            push = -k * data.qpos[controller.lip_qpos]
            moment = cup.radius * math.hypot((push * np.sin(theta)).sum(), (push * np.cos(theta)).sum())
            steps.append((moment / (0.5 * cup.radius * push.sum()), moment, -data.qpos[controller.lip_qpos].copy(),
                          controller.leak_area, controller.vacuum(data)))

    episode.recorder, episode.record_every = record, 1
    result = runner.run_after_reset()
    print(f"{key} seed {seed} ({overrides}): simulated {'success' if result['success'] else result['failure']}")
    if len(steps) > 5:
        axis = 0.5 * np.angle(_harmonics(steps[5][2])[1])  # the profile's most folded (axis-wise) bearing
        for name, step in (("lift start", steps[5]), ("lift peak", max(steps, key=lambda s: s[0]))):
            first, harmonic = _harmonics(step[2])
            bearing = math.degrees(math.atan2(-first[1], first[2]) - axis) % 360.0  # tau = pi r (p_y, -p_x)
            print(f"  {name}: moment {1e3 * step[1]:.1f} mN m ({step[0]:.2f} of the flat ring limit) at "
                  f"{bearing:.0f} deg from the axis-wise side, folds' second harmonic {1e3 * abs(harmonic):.2f} mm, "
                  f"points at free length {int((step[2] < 1e-5).sum())}, leak {1e6 * step[3]:.2f} mm^2, "
                  f"vacuum {step[4]:.3f}")


def _flat_lifted_leak(ratio: float, normal: float, cup) -> float:
    """Leak area (m^2) of a flat face's spring ring (rate K round it) carrying the normal force
    `normal` with a tilting moment `ratio` x r x normal, beyond the ring limit (ratio > 1/2): the
    compression c0 + c1 cos(theta) lifts where it is negative; with rho = c1 / c0 and the contact's
    half-angle a = acos(-1 / rho), ratio = (2 sin a + rho (a + sin a cos a)) / (2 (a + rho sin a)),
    normal = (K c0 / pi)(a + rho sin a), and the lifted arc's area is 2 r c0 (rho sin a - (pi - a))."""
    def shape(rho: float) -> tuple[float, float]:
        a = math.acos(-1.0 / rho)
        return (2 * math.sin(a) + rho * (a + math.sin(a) * math.cos(a))) / (2 * (a + rho * math.sin(a))), a

    low, high = 1.0, 1e6
    for _ in range(100):
        mid = math.sqrt(low * high)
        low, high = (mid, high) if shape(mid)[0] < ratio else (low, mid)
    rho = 0.5 * (low + high)
    a = shape(rho)[1]
    c0 = math.pi * normal / (cup.lip_rate * (a + rho * math.sin(a)))
    return 2.0 * cup.radius * c0 * (rho * math.sin(a) - (math.pi - a))


def lag(key: str, seed: int) -> None:
    """Print the planned swing with the vacuum lagging its leak (module docstring)."""
    cup, tau = CUP_DEFAULT, SIM_CUP_DEFAULT.vacuum_time_constant
    history: list = []
    through = swing_model.swing_through

    def spy(swing_, arrival, *args, **kwargs):
        if len(args[2]) == 1:  # the nominal grasp: one row
            kwargs["trace"] = lambda t, w, active: history.append(
                (t, float(np.hypot(w[0, 3], w[0, 4])), float(w[0, 2]), bool(active[0])))
        return through(swing_, arrival, *args, **kwargs)

    swing_model.swing_through = spy
    try:
        runner, mesh, com, grasp, labels = _label_trial(key, seed)
    finally:
        swing_model.swing_through = through
    labeller = SuctionLabeller(mesh, LabelConfig.for_episode(cup), mass=runner.record.mass, com=com)
    seal = labeller.seal(grasp.point[None], grasp.approach[None])  # the lip's profile: label_grasp keeps none
    heights = 0.0 if seal.lip_heights is None else float(np.abs(seal.lip_heights).max())
    p, lowest, peak, verdict, last = 1.0, 1.0, 0.0, "held", None
    for t, moment, pull, active in history:
        if not active:
            continue
        dt = 0.0 if last is None else t - last
        last = t
        normal = p * cup.vacuum_force - pull  # f_N = V + f_z, f_z = -w_z (the load's pull)
        ratio = moment / (cup.radius * max(normal, 1e-12))
        peak = max(peak, 2.0 * ratio)
        if normal <= 0.0 or ratio >= 1.0:
            verdict = f"peeled at {t:.3f} s (moment at the rim)"
            break
        leak = _flat_lifted_leak(ratio, normal, cup) if ratio > 0.5 else 0.0
        target = float(equilibrium_vacuum(leak, cup)) / cup.vacuum_pressure
        p += (target - p) * (1.0 - math.exp(-dt / tau))
        lowest = min(lowest, p)
        if p < cup.vacuum_switch_fraction:
            verdict = f"peeled at {t:.3f} s (vacuum at the switch)"
            break
    print(f"{key} seed {seed}: label rwr {labels['label_rwr']}, nominal {labels['label_wr']}; largest lip height "
          f"{1e3 * heights:.2f} mm; planned swing's peak moment {peak:.2f} of the ring limit, lowest vacuum "
          f"{lowest:.3f}: {verdict}")


PLACES = 48


def _lip_gaps(normal: float, torque: np.ndarray, heights: np.ndarray, cup, places: int = PLACES) -> np.ndarray:
    """Each place's compression (m, negative: lifted) of the spring ring carrying the normal force
    and the tilting torque (tau_x, tau_y), on a profile `heights`: Newton on the convex potential
    sum (K / 2n) max(c, 0)^2 - u . w, c = u . b - z, whose gradient is the force balance."""
    theta = wrench.lip_angles(places)
    basis = np.column_stack([np.ones(places), np.cos(theta), np.sin(theta)])
    rate, r = cup.lip_rate / places, cup.radius
    target = np.array([normal, -torque[1] / r, torque[0] / r])
    u = np.array([normal / cup.lip_rate, -2 * torque[1] / (cup.lip_rate * r), 2 * torque[0] / (cup.lip_rate * r)])

    def potential(v):
        return 0.5 * rate * np.sum(np.maximum(basis @ v - heights, 0.0) ** 2) - v @ target

    for _ in range(200):
        c = basis @ u - heights
        grad = basis.T @ (rate * np.maximum(c, 0.0)) - target
        if np.abs(grad).max() < 1e-10:
            break
        on = c > 0.0
        step = np.linalg.solve(rate * basis[on].T @ basis[on] + 1e-9 * np.eye(3), -grad)
        t = 1.0
        while potential(u + t * step) > potential(u) + 1e-4 * t * (grad @ step) and t > 1e-10:
            t *= 0.5
        u = u + t * step
    return basis @ u - heights


def _largest(holds, high: float) -> float:
    """The largest value in [0, high] for which `holds(value)`, by 40 bisections (holds(0) true)."""
    low = 0.0
    for _ in range(40):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if holds(mid) else (low, mid)
    return low


def _holds(pull: float, torque: np.ndarray, heights: np.ndarray, cup, leaking: bool) -> bool:
    """Whether the lip holds: without `leaking`, no place lifts (p >= 0); with it, the largest
    equilibrium of lip and vacuum (monotone iteration down from the full vacuum) keeps the vacuum
    above the part-present switch."""
    v = cup.vacuum_force
    arc = 2.0 * math.pi * cup.radius / len(heights)
    for _ in range(300):
        normal = v - pull
        if np.hypot(*torque) >= cup.radius * normal * 0.999:
            return False
        c = _lip_gaps(normal, torque, heights, cup, len(heights))
        if not leaking:
            return bool(c.min() >= -1e-12)
        new = float(vacuum_force(arc * np.maximum(-c, 0.0).sum(), cup))
        if abs(new - v) < 1e-10:
            break
        v = new
    return v >= cup.vacuum_switch_fraction * cup.vacuum_force


def peel() -> None:
    """Print the largest moment held with and without the lifted lip's leak (module docstring)."""
    cup, pull = CUP_DEFAULT, 0.6
    theta = wrench.lip_angles(PLACES)
    limit = 0.5e3 * cup.radius * (cup.vacuum_force - pull)
    print(f"pull {pull} N, flat ring limit r (V - pull) / 2 = {limit:.2f} mN m")
    for radius in (math.inf, 0.05, 0.03, 0.022):
        heights = -(cup.radius**2 / (4.0 * radius)) * np.cos(2.0 * theta)
        for bearing in (0.0, 90.0):
            direction = np.array([math.cos(math.radians(bearing)), math.sin(math.radians(bearing))])
            found = [_largest(lambda m, d=direction, z=heights, leak=leaking: _holds(pull, m * d, z, cup, leak),
                              cup.radius * (cup.vacuum_force - pull)) for leaking in (False, True)]
            print(f"  cylinder R {radius * 1e3:.0f} mm, torque at {bearing:.0f} deg: {found[0] * 1e3:.2f} mN m "
                  f"without the lifted lip's leak, {found[1] * 1e3:.2f} with it ({found[1] / found[0]:.4f}x)")


def ring(normal: float, places: int, bearing: float, amplitudes: list[float]) -> None:
    """Print the spring ring's lift-free moment on lying cylinders' profiles (module docstring)."""
    cup = CUP_DEFAULT
    theta = wrench.lip_angles(places)
    direction = np.array([math.cos(math.radians(bearing)), math.sin(math.radians(bearing))])
    for amplitude in amplitudes:
        heights = -1e-3 * amplitude * np.cos(2.0 * theta)
        held = _largest(lambda m, z=heights: _lip_gaps(normal, m * direction, z, cup, places).min() >= -1e-12,
                        cup.radius * normal)
        print(f"{places} places, normal force {normal} N, torque at {bearing} deg, profile {amplitude} mm: "
              f"{held * 1e3:.2f} mN m")


def _ring(pressure: np.ndarray) -> tuple[np.ndarray, float]:
    """The ring's tangents e_k (K, 2) at its places (`wrench.lip_angles`) and each place's arc (rad)."""
    theta = wrench.lip_angles(len(pressure))
    return np.stack([-np.sin(theta), np.cos(theta)], axis=1), 2.0 * np.pi / len(pressure)


def _ring_carries(pressure: np.ndarray, load: np.ndarray) -> float:
    """Largest s such that the ring (radius 1, pressure per unit angle `pressure` at equally spaced
    places, friction coefficient 1) carries s * load = (f_x, f_y, tau_z): tractions t_k with
    |t_k| <= p_k dtheta, sum t_k = s (f_x, f_y), sum e_k . t_k = s tau_z (e_k the ring's tangent)."""
    import clarabel
    import scipy.sparse as sp

    tangent, arc = _ring(pressure)
    places = len(pressure)
    n = 1 + 2 * places  # s, then (t_x, t_y) per place
    equal = np.zeros((3, n))
    equal[:, 0] = -load
    equal[0, 1::2], equal[1, 2::2] = 1.0, 1.0
    equal[2, 1::2], equal[2, 2::2] = tangent[:, 0], tangent[:, 1]
    cones = np.zeros((3 * places, n))
    cones[3 * np.arange(places) + 1, 1 + 2 * np.arange(places)] = -1.0
    cones[3 * np.arange(places) + 2, 2 + 2 * np.arange(places)] = -1.0
    bound = np.zeros(3 * places)
    bound[0::3] = pressure * arc
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    cost = np.zeros(n)
    cost[0] = -1.0
    solver = clarabel.DefaultSolver(sp.csc_matrix((n, n)), cost, sp.csc_matrix(np.vstack([equal, cones])),
                                    np.concatenate([np.zeros(3), bound]),
                                    [clarabel.ZeroConeT(3)] + [clarabel.SecondOrderConeT(3)] * places, settings)
    return float(solver.solve().x[0])


def _hull_carries(pressure: np.ndarray, load: np.ndarray) -> float:
    """Largest s such that s * load lies in the hull of the ring's two pure strategies (module
    docstring, friction; eval/README.md's closed form): all the pressure sliding one way u,
    (F u, c . u), or twisting one way, +-(c, F), with F = sum p dtheta = f_N and c = sum p_k e_k
    dtheta (only p's first harmonic, the tilt, enters). A load (f, tau) is in the hull iff
    ||f - l c|| + |l| F <= F with the mixture's twisting share l = (tau - c . f / F) F / (F^2 - |c|^2);
    l is linear in the load, so the largest multiple is F / (||f - l c|| + |l| F) at s = 1."""
    tangent, arc = _ring(pressure)
    total = float(pressure.sum() * arc)
    c = (pressure[:, None] * tangent).sum(axis=0) * arc
    share = (load[2] - c @ load[:2] / total) * total / (total**2 - c @ c)
    return total / (float(np.linalg.norm(load[:2] - share * c)) + abs(share) * total)


def friction() -> None:
    """Print the exact ring friction beside the box and the double cone (module docstring)."""
    theta = wrench.lip_angles(720)
    profiles = {"evenly pressed": np.full(len(theta), 1.0 / (2.0 * np.pi)),
                "tilted to the ring limit": (1.0 + np.cos(theta)) / (2.0 * np.pi)}
    loads = {"shear along x (the tilt's plane)": (1, 0, 0), "shear along y": (0, 1, 0), "twist": (0, 0, 1),
             "box corner (1, 1, 1)": (1, 1, 1), "box corner (1, 1, -1)": (1, 1, -1),
             "shear x and twist (1, 0, 1)": (1, 0, 1)}
    print("load (normalised)                  | profile                  | ring carries | box allows | double cone"
          " | strategies' hull")
    for name, pressure in profiles.items():
        even = 2.0 * np.pi * pressure.min()
        for label, load in loads.items():
            v = np.array(load, dtype=float) / np.linalg.norm(load)
            exact = _ring_carries(pressure, v)
            box = (1.0 / math.sqrt(3.0)) / np.abs(v).max()
            cone = even / (np.hypot(v[0], v[1]) + abs(v[2]))
            hull = _hull_carries(pressure, v)
            print(f"{label:34s} | {name:24s} | {exact:12.3f} | {box:10.3f} | {cone:11.3f} | {hull:16.3f}")


if __name__ == "__main__":
    if len(sys.argv) >= 3 and sys.argv[1] == "samples":
        for arg in sys.argv[2:]:
            name, text = arg.rsplit(":", 1)
            samples(name, int(text))
    elif len(sys.argv) >= 4 and sys.argv[1] == "lip":
        for arg in sys.argv[3:]:
            name, text = arg.rsplit(":", 1)
            lip(sys.argv[2], name, int(text))
    elif len(sys.argv) in (3, 4) and sys.argv[1] == "conform":
        conform(float(sys.argv[2]), sys.argv[3] if len(sys.argv) == 4 else "-")
    elif len(sys.argv) >= 3 and sys.argv[1] == "lag":
        for arg in sys.argv[2:]:
            name, text = arg.rsplit(":", 1)
            lag(name, int(text))
    elif len(sys.argv) == 2 and sys.argv[1] == "peel":
        peel()
    elif len(sys.argv) == 2 and sys.argv[1] == "friction":
        friction()
    elif len(sys.argv) >= 6 and sys.argv[1] == "ring":
        ring(float(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]), [float(a) for a in sys.argv[5:]])
    else:
        sys.exit(__doc__)
