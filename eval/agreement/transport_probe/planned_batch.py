import json, math, sys
import numpy as np
sys.path.insert(0, "eval/agreement")
from lip_peak import simulated
from suctionbench.config import LabelConfig, PerturbationConfig
from suctionbench.contact.labeller import SuctionLabeller
from suctionbench.objects.registry import load_object
from suctionbench.sim.pick import PickRequest, PickRunner
d = json.load(open(sys.argv[1]))
trials = [(x["object"], x["seed"]) for x in d["per_trial"] if x["failure"] in (None, "seal_lost_transport", "seal_lost_hold") and x["label_rwr"] is not None]
part, parts = int(sys.argv[2]), int(sys.argv[3])
rows = []
for key, seed in trials[part::parts]:
    runner = PickRunner(PickRequest(key, policy="random-surface", record=load_object(key)))
    runner.request.seed = int(seed); runner.reset(); pose = runner.object_pose()
    episode, cupst = runner.episode, runner.episode.cup
    k = cupst.sim.lip_point_stiffness(cupst.cup)
    from suctionbench.contact import wrench
    theta = wrench.lip_angles(len(cupst.lip_qpos))
    peak = [0.0]
    def rec(data, c):
        if episode.motion == "transport":
            fold = data.qpos[c.lip_qpos]; push = -k * fold
            m = cupst.cup.radius * math.hypot((push * np.sin(theta)).sum(), (push * np.cos(theta)).sum())
            peak[0] = max(peak[0], m / max(0.5 * cupst.cup.radius * push.sum(), 1e-9))
    episode.recorder, episode.record_every = rec, 1
    result = runner.run_after_reset()
    grasp = np.asarray(result["grasp_world"], dtype=float)
    point, approach = grasp[None, :3], grasp[None, 3:]
    plan = episode.planned_transport(point[0], approach[0])
    mesh, com = runner.posed_object(pose)
    cup = runner.request.cup
    pc = PerturbationConfig.for_episode(cup, transport_direction=tuple(plan[0]), transport_time=plan[1], transport_time_max=None)
    lab = SuctionLabeller(mesh, LabelConfig(cup=cup, perturbation=pc), mass=runner.record.mass, com=com)
    frames, seal = lab.frames(point, approach), lab.seal(point, approach)
    ratios = []
    for w in lab.nominal_lip_loads(frames, seal):
        limit = 0.5 * cup.radius * (seal.vacuum_force[0] - w[0, 2])
        ratios.append(math.hypot(w[0, 3], w[0, 4]) / limit)
    rows.append(dict(object=key, seed=seed, success=result["success"], failure=result["failure"], rwr=result["label_rwr"],
                     T=plan[1], sim_transport=peak[0], lab=ratios, mass=runner.record.mass))
json.dump(rows, open(f"/work/probe/pb_{part}.json", "w"))
