"""The lip's peak moment in the lift and the transport, simulated and labelled, for agreement trials.

Usage: python eval/agreement/lip_peak.py OBJECT:SEED [OBJECT:SEED ...]
(e.g. basic/box_brick:351; the trials of eval/agreement/agreement.json, random-surface grasps).

Simulation: the moment the lip's point springs carry about the lip centre, over the ring-pressure
limit r F / 2 of the force F they carry (their sum), at its peak in each motion; with the points
unfolded there (lifted to their free length), the bellows' tilt, the leak area and the cup's
vacuum at that step. Labeller: the nominal grasp's lip moment at the swing's turning point over its
ring limit r (V + f_z) / 2, per load case (the lift, then transports at the labeller's nominal
azimuths 0, 90, 180, 270 deg at the rated acceleration), the nominal weight without perturbation.
"""

from __future__ import annotations

import math
import sys

import numpy as np

from suctionbench.config import LabelConfig
from suctionbench.contact import wrench
from suctionbench.contact.labeller import SuctionLabeller
from suctionbench.objects.registry import load_object
from suctionbench.sim.pick import PickRequest, PickRunner


def simulated(runner: PickRunner) -> tuple[dict, dict[str, str]]:
    """Run the trial, recording the lip's moment every step of the lift and the transport."""
    episode = runner.episode
    cup_state, cup = episode.cup, episode.cup.cup
    k = cup_state.sim.lip_point_stiffness(cup)
    theta = wrench.lip_angles(len(cup_state.lip_qpos))  # the lip points' bearings (sim/cup.py lays them so)
    rows: dict[str, list] = {"lift": [], "transport": []}

    def record(data, controller) -> None:
        if episode.motion not in rows:
            return
        fold = data.qpos[controller.lip_qpos]
        push = -k * fold
        moment = cup.radius * math.hypot((push * np.sin(theta)).sum(), (push * np.cos(theta)).sum())
        tilt = math.degrees(controller.bellows_tilt(data))
        rows[episode.motion].append((moment / (0.5 * cup.radius * push.sum()), moment, int((fold > -1e-5).sum()),
                                      tilt, controller.leak_area, controller.vacuum(data)))

    episode.recorder, episode.record_every = record, 1
    result = runner.run_after_reset()
    out = {}
    for motion, steps in rows.items():
        if steps:
            ratio, moment, free, tilt, leak, vacuum = max(steps)
            out[motion] = (f"{ratio:.2f} ({1e3 * moment:.1f} mN m, {free} points unfolded, bellows {tilt:.1f} deg, "
                           f"leak {1e6 * leak:.2f} mm^2, vacuum {vacuum:.3f})")
    return result, out


def labelled(runner: PickRunner, pose: np.ndarray, result: dict) -> list[str]:
    """The labeller's lip moment over its limit at each load case's turning point (nominal grasp in
    the object's settled `pose`, where it was planned)."""
    mesh, com = runner.posed_object(pose)
    record = runner.record
    labeller = SuctionLabeller(mesh, LabelConfig.for_episode(runner.request.cup), mass=record.mass, com=com)
    grasp = np.asarray(result["grasp_world"], dtype=float)
    point, approach = grasp[None, :3], grasp[None, 3:]
    frames, seal = labeller.frames(point, approach), labeller.seal(point, approach)
    cup = labeller.config.cup
    out = []
    for w in labeller.nominal_lip_loads(frames, seal):
        limit = 0.5 * cup.radius * (seal.vacuum_force[0] - w[0, 2])
        out.append(f"{math.hypot(w[0, 3], w[0, 4]) / limit:.2f}")
    return out


def main(trials: list[str]) -> None:
    for trial in trials:
        key, seed = trial.rsplit(":", 1)
        runner = PickRunner(PickRequest(key, policy="random-surface", record=load_object(key)))
        runner.request.seed = int(seed)
        runner.reset()
        pose = runner.object_pose()
        result, peaks = simulated(runner)
        print(f"{key} seed {seed}: simulated {'success' if result['success'] else result['failure']}, "
              f"label rwr {result['label_rwr']}")
        for motion, text in peaks.items():
            print(f"  simulated {motion}: peak lip moment / ring limit {text}")
        if result["seal_time"] is not None:
            print("  labelled (lift, transport at 0/90/180/270 deg): " + ", ".join(labelled(runner, pose, result)))


if __name__ == "__main__":
    main(sys.argv[1:])
