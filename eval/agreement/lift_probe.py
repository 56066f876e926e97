"""The lift's swing in both models, for agreement trials the labeller rejects and the simulation
carries (eval/README.md, agreement "Now: the simulated vacuum pulls along the axis").

Usage:
  python eval/agreement/lift_probe.py swing OBJECT:SEED [OBJECT:SEED ...]
      the labeller's nominal lip wrench at the lift's and the carry's worst instants (moment over
      the ring limit r (V + f_z) / 2, shear and twist over the friction limits), its swing from the
      lift-off (static tilt, rate, time; tilt every 40 ms), and the simulated tilts every 40 ms of
      the lift (bellows, and the object against the bellows' end: the lip's own tilt).
  python eval/agreement/lift_probe.py relabel OUT.json [--no-sqrt3]
      relabel (the labeller only, no simulation) the trials of agreement.json that seal in the
      labeller and carry or score rwr >= 0.1; --no-sqrt3 drops the paper's sqrt(3) from the
      friction box (the most permissive box).
  python eval/agreement/lift_probe.py bridge [AGREEMENT.json]
      for the executed trials the simulation sealed and the labeller did not (default: the
      agreement.json before the leak test measured the real surface, agreement_before_surface.json),
      how far the object's convex parts (the collision geometry the simulated lip rests on) lie
      above its real surface under the lip: rays along the approach through 48 places of the lip
      circle round the grasp point, `mj_ray` on the parts and trimesh on the posed mesh; the
      largest and smallest offset (mm) and the places where a part is met and no surface is.
  python eval/agreement/lift_probe.py centred SET [COUNT]
      the COUNT (default 10) heaviest objects of SET with the robust label (the pick's loads at the
      rated acceleration, as a dataset labels it) of their centred grasp: straight down at the
      sealable point nearest above the centre of mass (tests/test_sim.py's `centred_grasp`, which
      the heaviest-object test uses), and that point's distance from it.
"""

from __future__ import annotations

import json
import math
import sys

import numpy as np

from suctionbench.config import CUP_DEFAULT as CUP
from suctionbench.contact import swing as swing_model
from suctionbench.contact import swing_path, wrench
from suctionbench.evaluation.agreement import NOT_EXECUTED
from suctionbench.objects.registry import load_object
from suctionbench.policies.analytic import random_surface_grasp
from suctionbench.sim.cup import SIM_CUP_DEFAULT, SimCupConfig
from suctionbench.sim.pick import PickRequest, PickRunner

AGREEMENT = "eval/agreement/agreement.json"


def _runner(key: str, seed: int, sim_cup: SimCupConfig = SIM_CUP_DEFAULT) -> PickRunner:
    """The agreement trial's runner (a random surface grasp, its seed), reset: the object placed."""
    runner = PickRunner(PickRequest(key, policy="random-surface", record=load_object(key), sim_cup=sim_cup))
    runner.request.seed = seed
    runner.reset()
    return runner


def _label_trial(key: str, seed: int):
    """The agreement trial's grasp labelled as the episode labels it (no simulation): its runner,
    the posed mesh and centre of mass, the grasp and its labels."""
    runner = _runner(key, seed)
    mesh, com = runner.posed_object(runner.object_pose())
    grasp = random_surface_grasp(mesh, seed)
    return runner, mesh, com, grasp, runner.label_grasp(grasp.point, grasp.approach, mesh, com)


def swing(key: str, seed: int) -> None:
    """Print both models' lift for one trial (module docstring)."""
    spied: dict = {"wrench": None, "tilts": [], "on": False}
    through, turned = swing_model.swing_through, swing_path._axis_turned

    def spy_through(swing_, arrival, *args, **kwargs):
        nominal = len(args[2]) == 1  # the nominal label: one grasp, no perturbation samples
        if nominal:
            phi_s = swing_.static_tilt()
            rate, t_off = arrival.lift_off(swing_.n, phi_s, args[1], args[0], args[2])
            spied["start"] = (math.degrees(phi_s[0]), math.degrees(rate[0]), float(t_off[0]))
        spied["on"] = nominal
        out = through(swing_, arrival, *args, **kwargs)
        spied["on"] = False
        if nominal:
            spied["wrench"] = out[0]
        return out

    def spy_turned(phi):
        if spied["on"] and len(phi) == 1:
            spied["tilts"].append(math.degrees(float(np.hypot(*phi[0]))))
        return turned(phi)

    swing_model.swing_through, swing_path._axis_turned = spy_through, spy_turned
    try:
        runner = _runner(key, seed)
        episode, sim = runner.episode, []

        def record(data, cup) -> None:
            if episode.motion != "lift":
                return
            rel = data.site_xmat[episode.tip].reshape(3, 3).T @ data.xmat[episode.object].reshape(3, 3)
            sim.append((cup.bellows_tilt(data), rel))

        episode.recorder, episode.record_every = record, 1
        result = runner.run_after_reset()
    finally:
        swing_model.swing_through, swing_path._axis_turned = through, turned
    print(f"{key} seed {seed}: simulated {'success' if result['success'] else result['failure']}, "
          f"label rwr {result['label_rwr']}")
    if spied["wrench"] is not None:
        for phase, w in zip(swing_path.PHASES, spied["wrench"], strict=True):
            a = -w
            f_n = a[2] + CUP.vacuum_force
            print(f"  labeller {phase}: moment / ring limit {np.hypot(a[3], a[4]) / (CUP.radius * f_n / 2):.2f}, "
                  f"shear / mu f_N {np.hypot(a[0], a[1]) / (CUP.friction * f_n):.2f}, "
                  f"twist / r mu f_N {abs(a[5]) / (CUP.radius * CUP.friction * f_n):.2f}")
        s = spied["start"]
        print(f"  labeller lift-off: static tilt {s[0]:.1f} deg, rate {s[1]:.0f} deg/s, {s[2]:.3f} s into the lift; "
              f"tilt every 40 ms: {np.round(spied['tilts'][::20][:25], 1).tolist()}")
    if sim:
        first = sim[0][1]
        lip = [math.degrees(math.acos(np.clip((np.trace(rel @ first.T) - 1.0) / 2.0, -1.0, 1.0))) for _, rel in sim]
        print(f"  simulated bellows tilt every 40 ms: {np.round(np.degrees([b for b, _ in sim[::20]]), 1).tolist()}")
        print(f"  simulated lip tilt every 40 ms:     {np.round(lip[::20], 1).tolist()}")


def relabel(out: str, no_sqrt3: bool) -> None:
    """Relabel the candidate trials (module docstring) and write old and new rwr per trial."""
    if no_sqrt3:
        wrench.SQRT3 = 1.0
    with open(AGREEMENT) as f:
        trials = json.load(f)["per_trial"]
    rows = []
    for t in trials:
        if not (t["valid"] and t["failure"] not in NOT_EXECUTED and t["label_seal"]
                and (t["success"] or t["label_rwr"] >= 0.1)):
            continue
        labels = _label_trial(t["object"], int(t["seed"]))[-1]
        rows.append({"object": t["object"], "seed": t["seed"], "success": t["success"],
                     "rwr": t["label_rwr"], "relabelled": labels["label_rwr"]})
    moved = [r for r in rows if abs(r["rwr"] - r["relabelled"]) > 1e-9]
    hits = sum(r["success"] and r["rwr"] <= 0.5 < r["relabelled"] for r in rows)
    false = sum(not r["success"] and r["rwr"] <= 0.5 < r["relabelled"] for r in rows)
    print(f"{len(rows)} trials relabelled, {len(moved)} moved; misses turned hits {hits}, new false positives {false}")
    with open(out, "w") as f:
        json.dump(rows, f, indent=1)


def bridge(path: str) -> None:
    """Print the parts' offset above the real surface under the lip (module docstring)."""
    import mujoco

    from suctionbench.sim.cup import SURFACE_GROUP

    with open(path) as f:
        trials = json.load(f)["per_trial"]
    group = np.zeros(6, np.uint8)
    group[SURFACE_GROUP] = 1
    theta = wrench.lip_angles(48)
    for t in trials:
        if not t["valid"] or t["failure"] in NOT_EXECUTED or t["failure"] == "no_seal" or t["label_seal"]:
            continue
        runner, mesh, _, grasp, _ = _label_trial(t["object"], int(t["seed"]))
        model, data = runner.episode.model, runner.episode.data
        mujoco.mj_forward(model, data)
        a = np.asarray(grasp.approach, float) / np.linalg.norm(grasp.approach)
        x = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
        x /= np.linalg.norm(x)
        ring = np.cos(theta)[:, None] * x + np.sin(theta)[:, None] * np.cross(a, x)
        origins = grasp.point - 0.03 * a + CUP.radius * ring
        real = np.full(len(theta), np.nan)
        hits, index, _ = mesh.ray.intersects_location(origins, np.tile(a, (len(theta), 1)), multiple_hits=False)
        real[index] = (hits - origins[index]) @ a
        parts, geom = np.full(len(theta), np.nan), np.zeros(1, np.int32)
        for k, origin in enumerate(origins):
            distance = mujoco.mj_ray(model, data, origin, a, group, 0, -1, geom)
            if geom[0] >= 0 and model.geom_bodyid[geom[0]] == runner.episode.object:
                parts[k] = distance
        offset = 1e3 * (real - parts)
        print(f"{t['object']:30s} {t['seed']:4d} simulated {str(t['failure'] or 'success'):20s} labeller "
              f"{t['label_seal_failure']:18s} parts above the surface: max {np.nanmax(offset):+.2f} min "
              f"{np.nanmin(offset):+.2f} mm, no surface at {int((np.isnan(real) & ~np.isnan(parts)).sum())} places")


def centred(name: str, count: int) -> None:
    """Print the heaviest objects' centred-grasp labels (module docstring)."""
    sys.path.insert(0, "tests")
    from test_sim import centred_grasp  # the heaviest-object test's grasp

    from suctionbench.objects.registry import list_objects

    for record in sorted(list_objects(name), key=lambda r: -r.mass)[:count]:
        grasp, rwr = centred_grasp(record)
        if grasp is None:
            print(f"{record.key:30s} {record.mass:.3f} kg: no sealable point")
            continue
        pose = record.most_probable_pose()
        com = pose[:3, :3] @ np.asarray(record.com) + pose[:3, 3]
        point = pose[:3, :3] @ np.asarray(grasp[:3]) + pose[:3, 3]
        print(f"{record.key:30s} {record.mass:.3f} kg: centred grasp {1e3 * np.hypot(*(point[:2] - com[:2])):.1f} mm "
              f"from the centre of mass, rwr {rwr:.2f}")


if __name__ == "__main__":
    if len(sys.argv) >= 3 and sys.argv[1] == "swing":
        for arg in sys.argv[2:]:
            name, seed_text = arg.rsplit(":", 1)
            swing(name, int(seed_text))
    elif len(sys.argv) in (3, 4) and sys.argv[1] == "centred":
        centred(sys.argv[2], int(sys.argv[3]) if len(sys.argv) == 4 else 10)
    elif len(sys.argv) in (2, 3) and sys.argv[1] == "bridge":
        bridge(sys.argv[2] if len(sys.argv) == 3 else "eval/agreement/agreement_before_surface.json")
    elif len(sys.argv) >= 3 and sys.argv[1] == "relabel":
        relabel(sys.argv[2], "--no-sqrt3" in sys.argv[3:])
    else:
        sys.exit(__doc__)
