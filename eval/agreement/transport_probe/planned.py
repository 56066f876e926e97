import math, sys
import numpy as np
sys.path.insert(0, "eval/agreement")
from lip_peak import simulated
from suctionbench.config import LabelConfig, PerturbationConfig
from suctionbench.contact.labeller import SuctionLabeller
from suctionbench.objects.registry import load_object
from suctionbench.sim.pick import PickRequest, PickRunner
for trial in sys.argv[1:]:
    key, seed = trial.rsplit(":", 1)
    runner = PickRunner(PickRequest(key, policy="random-surface", record=load_object(key)))
    runner.request.seed = int(seed); runner.reset(); pose = runner.object_pose()
    result, peaks = simulated(runner)
    grasp = np.asarray(result["grasp_world"], dtype=float)
    point, approach = grasp[None, :3], grasp[None, 3:]
    plan = runner.episode.planned_transport(point[0], approach[0])
    mesh, com = runner.posed_object(pose)
    cup = runner.request.cup
    pc = PerturbationConfig.for_episode(cup, transport_direction=tuple(plan[0]), transport_time=plan[1], transport_time_max=None)
    lab = SuctionLabeller(mesh, LabelConfig(cup=cup, perturbation=pc), mass=runner.record.mass, com=com)
    frames, seal = lab.frames(point, approach), lab.seal(point, approach)
    out = []
    for w in lab.nominal_lip_loads(frames, seal):
        limit = 0.5 * cup.radius * (seal.vacuum_force[0] - w[0, 2])
        out.append(f"{math.hypot(w[0, 3], w[0, 4]) / limit:.2f}")
    print(f"{trial}: sim {'success' if result['success'] else result['failure']}, rwr {result['label_rwr']}, T {plan[1]:.2f} dir {np.round(plan[0],2)}, mass {runner.record.mass:.3f}")
    for m, t in peaks.items(): print(f"   sim {m}: {t}")
    print("   labelled lift / start / braking:", out)
