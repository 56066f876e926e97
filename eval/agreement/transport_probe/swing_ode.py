"""The labeller's own swing model, integrated in time through the planned lift and transport, beside
its closed form (turning points, response factor, worst-phase ringing) and the simulation.

Usage: python eval/agreement/transport_probe/swing_ode.py AGREEMENT_JSON PART PARTS OUT.json

Same trials as planned_batch.py (those that reached the transport). Per trial: the simulated peak
of the lip's moment over its ring limit in the transport (and the lift), the closed form's lift /
start / braking, and the time-resolved model's peaks in the lift and the transport.

Time-resolved model (contact frame, which the straight lift and transport do not turn): the object
a rigid body hinged at the lip centre, tilted by the in-plane rotation vector phi; the cup returns
R(|phi|) (wrench._Swing.returned) against it; the load m (g - a_tool(t)) at the centre of mass;
viscous loss 2 zeta sqrt(k I) at the hanging equilibrium. Starts at the lift-off (arrival.lift_off:
tilt phi_s, rate psi'), integrates the rest of the min-jerk lift (H, T_l), the min-jerk transport
(planned direction and time) and 1 s over the bin. The lip carries R(|phi|) in the plane; its limit
r (V - F.z) / 2 with F the load turned into the object's frame."""
import json
import math
import sys

import numpy as np

sys.path.insert(0, "eval/agreement")
from suctionbench import minjerk  # noqa: E402
from suctionbench.config import (
    LabelConfig,  # noqa: E402
    PerturbationConfig,  # noqa: E402
)
from suctionbench.contact import wrench  # noqa: E402
from suctionbench.contact.labeller import SuctionLabeller  # noqa: E402
from suctionbench.contact.robust import arrivals  # noqa: E402
from suctionbench.objects.registry import load_object  # noqa: E402
from suctionbench.sim.pick import PickRequest, PickRunner  # noqa: E402


def rot(v):
    """Rotation matrix of rotation vector v (3,)."""
    a = np.linalg.norm(v)
    if a < 1e-12:
        return np.eye(3)
    k = v / a
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(a) * kx + (1 - math.cos(a)) * kx @ kx


def integrate(lab, cup, frame, ring, plan, seal=None, dt=5e-4, hold=1.0, ringing=True):
    """Peaks of R / ring limit in lift and transport (time-resolved labeller swing)."""
    obj = lab.object
    m, g = obj.mass, np.asarray(obj.gravity, float)
    com = np.asarray(obj.com, float)
    r0 = frame.T @ (com - ring)
    ic = frame.T @ np.asarray(obj.inertia, float) @ frame
    il = ic + m * (r0 @ r0 * np.eye(3) - np.outer(r0, r0))
    motion = lab.config.perturbation
    H, Tl = motion.lift_height, motion.lift_time
    d, T = np.asarray(plan[0], float), float(plan[1])
    L = 0.0
    # the transport's length from its time: T = sqrt(5.774 L / a) where the rating limits it; the
    # probe takes L from the planned line (episode) instead, passed in plan[2]
    L = plan[2]
    swing_w = wrench._Swing(obj.gravity_force[None], com[None], ring[None], frame[None], cup)
    phi_s = swing_w.static_tilt()
    n_h = swing_w.n[0]
    weight = np.broadcast_to(obj.gravity_force, (1, 3))
    arr = arrivals(obj, motion, cup, weight, np.zeros((1, 1, 3)))[0]
    rate, t_off = arr.lift_off(swing_w.n, phi_s, ring[None], com[None], frame[None])
    if not ringing:
        rate = rate * 0.0
    phi = phi_s[0] * n_h[:2].copy()
    w = rate[0] * n_h[:2].copy()
    k_h = float(swing_w.stiffness(phi_s)[0])
    i_h = float(n_h @ il @ n_h) if swing_w.tips[0] else float(np.trace(il[:2, :2]) / 2)
    c = 2.0 * arr.zeta * math.sqrt(max(k_h, 1e-12) * i_h)
    v = cup.vacuum_force
    peaks = {"lift": 0.0, "transport": 0.0, "hold": 0.0}
    t = float(t_off[0])
    end = Tl + T + hold
    i2inv = np.linalg.inv(il[:2, :2])
    wrenches, phases = [], []
    while t < end:
        if t < Tl:
            a_w = np.array([0, 0, H / Tl**2 * minjerk.acceleration(t / Tl)])
            phase = "lift"
        elif t < Tl + T:
            a_w = d * (L / T**2) * minjerk.acceleration((t - Tl) / T)
            phase = "transport"
        else:
            a_w, phase = np.zeros(3), "hold"
        f_c = frame.T @ (m * (g - a_w))
        rm = rot(np.array([phi[0], phi[1], 0.0]))
        r = rm @ r0
        tau = np.cross(r, f_c)[:2]
        mag = math.hypot(*phi)
        ret = float(swing_w.returned(np.array([mag]))[0]) if mag > 0 else 0.0
        unit = phi / mag if mag > 1e-15 else np.zeros(2)
        alpha = i2inv @ (tau - ret * unit - c * w)
        lip_moment = ret * unit + c * w
        w = w + dt * alpha
        phi = phi + dt * w
        pull = float((rm.T @ f_c)[2])
        if seal is not None:
            w3, a3 = np.array([w[0], w[1], 0.0]), np.array([alpha[0], alpha[1], 0.0])
            acc = np.cross(a3, r) + np.cross(w3, np.cross(w3, r))
            f_obj = rm.T @ (f_c - m * acc)
            tz = float(np.cross(r0, rm.T @ f_c)[2])
            wrenches.append([*f_obj, lip_moment[0], lip_moment[1], tz])
            phases.append(phase)
        limit = 0.5 * cup.radius * max(v - pull, 1e-9)
        peaks[phase] = max(peaks[phase], ret / limit)
        t += dt
    if seal is not None:
        ok = wrench.resists(np.array(wrenches), cup.friction, cup, seal.vacuum_force[0],
                            np.repeat(seal.lip_heights[:1], len(wrenches), axis=0))
        phases = np.array(phases)
        for ph in ("lift", "transport", "hold"):
            peaks["held_" + ph] = bool(ok[phases == ph].all())
    return peaks


def _lip_recorder(episode, peak):
    """A recorder keeping, per motion, the simulated lip's peak moment over its ring limit."""
    cup_state = episode.cup
    k = cup_state.sim.lip_point_stiffness(cup_state.cup)
    theta = wrench.lip_angles(len(cup_state.lip_qpos))
    radius = cup_state.cup.radius

    def rec(data, ctl):
        if episode.motion in peak:
            push = -k * data.qpos[ctl.lip_qpos]
            moment = radius * math.hypot((push * np.sin(theta)).sum(), (push * np.cos(theta)).sum())
            peak[episode.motion] = max(peak[episode.motion], moment / max(0.5 * radius * push.sum(), 1e-9))
    return rec


def main():
    from suctionbench.sim import episode as episode_module
    original = episode_module.PickEpisode._carry_time
    carried = []

    def carry_time(self, waypoints, length):
        duration = original(self, waypoints, length)
        carried.append((duration, length))
        return duration
    episode_module.PickEpisode._carry_time = carry_time
    executed = "--executed" in sys.argv
    with open(sys.argv[1]) as f:
        d = json.load(f)
    trials = [(x["object"], x["seed"]) for x in d["per_trial"]
              if x["failure"] in (None, "seal_lost_transport", "seal_lost_hold") and x["label_rwr"] is not None]
    part, parts = int(sys.argv[2]), int(sys.argv[3])
    rows = []
    for key, seed in trials[part::parts]:
        runner = PickRunner(PickRequest(key, policy="random-surface", record=load_object(key)))
        runner.request.seed = int(seed)
        runner.reset()
        pose = runner.object_pose()
        episode = runner.episode
        peak = {"lift": 0.0, "transport": 0.0, "hold": 0.0}
        rec = _lip_recorder(episode, peak)
        episode.recorder, episode.record_every = rec, 1
        carried.clear()
        result = runner.run_after_reset()
        ran = list(carried)
        grasp = np.asarray(result["grasp_world"], dtype=float)
        point, approach = grasp[None, :3], grasp[None, 3:]
        plan = episode.planned_transport(point[0], approach[0])
        length = float(np.linalg.norm(episode._above_bin() - episode._lift_end(point[0])))
        planned_time = plan[1]
        if executed and len(ran) >= 2:  # the label's plan, then the episode's own carry
            plan = (plan[0], ran[-1][0])
            length = ran[-1][1]
        mesh, com = runner.posed_object(pose)
        cup = runner.request.cup
        pc = PerturbationConfig.for_episode(cup, transport_direction=tuple(plan[0]), transport_time=plan[1],
                                            transport_time_max=None)
        lab = SuctionLabeller(mesh, LabelConfig(cup=cup, perturbation=pc), mass=runner.record.mass, com=com)
        frames, seal = lab.frames(point, approach), lab.seal(point, approach)
        closed = []
        for wr in lab.nominal_lip_loads(frames, seal):
            limit = 0.5 * cup.radius * (seal.vacuum_force[0] - wr[0, 2])
            closed.append(math.hypot(wr[0, 3], wr[0, 4]) / limit)
        closed_ok = [bool(wrench.resists(wr, cup.friction, cup, seal.vacuum_force, seal.lip_heights)[0])
                     for wr in lab.nominal_lip_loads(frames, seal)]
        ode = integrate(lab, cup, frames[0], seal.ring_centre[0], (plan[0], plan[1], length), seal)
        ode_quiet = integrate(lab, cup, frames[0], seal.ring_centre[0], (plan[0], plan[1], length), ringing=False)
        rows.append(dict(object=key, seed=seed, success=result["success"], failure=result["failure"],
                         rwr=result["label_rwr"], T=plan[1], T_planned=planned_time, sim=peak, closed=closed,
                         closed_ok=closed_ok, ode=ode, ode_quiet=ode_quiet, mass=runner.record.mass))
        print(key, seed, result["success"], {k_: round(v_, 2) for k_, v_ in peak.items()},
              [round(x, 2) for x in closed], {k_: round(v_, 2) for k_, v_ in ode.items()}, flush=True)
    with open(sys.argv[4], "w") as out:
        json.dump(rows, out)


if __name__ == "__main__":
    main()
