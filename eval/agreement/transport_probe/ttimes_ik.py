import sys, math
import numpy as np
from suctionbench.objects.registry import load_object
from suctionbench.sim.pick import PickRequest, PickRunner
from suctionbench.sim import episode as E
runner = PickRunner(PickRequest("basic/box_brick", policy="random-surface", record=load_object("basic/box_brick")))
runner.request.seed = 0; runner.reset()
ep = runner.episode
rng = np.random.default_rng(0)
bx, by = ep.scene.config.bin_centre
above = np.array([bx, by, ep.config.transport_height])
cx, cy = ep.scene.config.workspace_centre
out = []
for i in range(int(sys.argv[1])):
    tilt = math.radians(float(sys.argv[2])) * math.sqrt(rng.random()); az = 2 * math.pi * rng.random()
    approach = np.array([math.sin(tilt) * math.cos(az), math.sin(tilt) * math.sin(az), -math.cos(tilt)])
    start = np.array([cx + rng.uniform(-0.1, 0.1), cy + rng.uniform(-0.1, 0.1), rng.uniform(0.15, 0.3)])
    try:
        q = ep._ik(start, approach, ep._ready_configuration())
        path = ep._line(start, above, approach, q, step=E.CARRY_STEP)
    except Exception as exc:
        continue
    L = float(np.linalg.norm(above - start))
    out.append((ep._carry_time(path, L), L, math.degrees(tilt)))
t = np.array(out)
print(len(t), "T pct 0/10/50/90/99/100", np.round(np.percentile(t[:, 0], [0, 10, 50, 90, 99, 100]), 3), "L", t[:, 1].min(), t[:, 1].max())
for lo, hi in [(0, 15), (15, 30), (30, 45)]:
    m = (t[:, 2] >= lo) & (t[:, 2] < hi)
    if m.any(): print(lo, hi, m.sum(), np.round(np.percentile(t[m, 0], [0, 50, 90, 100]), 3))
