import math, sys
import numpy as np
from suctionbench.contact import wrench
from suctionbench.objects.registry import load_object
from suctionbench.sim.pick import PickRequest, PickRunner

for trial in sys.argv[1:]:
    key, seed = trial.rsplit(":", 1)
    runner = PickRunner(PickRequest(key, policy="random-surface", record=load_object(key)))
    runner.request.seed = int(seed)
    runner.reset()
    ep = runner.episode
    cs, cup = ep.cup, ep.cup.cup
    k = cs.sim.lip_point_stiffness(cup)
    theta = wrench.lip_angles(len(cs.lip_qpos))
    rows = []
    def rec(data, ctl):
        if ep.motion in ("lift", "transport"):
            R = data.xmat[ep.tool].reshape(3, 3)
            fold = data.qpos[ctl.lip_qpos]; push = -k * fold
            m = cup.radius * math.hypot((push * np.sin(theta)).sum(), (push * np.cos(theta)).sum())
            ratio = m / max(0.5 * cup.radius * push.sum(), 1e-9)
            tv = data.qpos[ctl._tilt_qpos]
            rows.append((ep.motion, data.time, R[:, 2].copy(), np.degrees(tv).copy(), ratio, ctl.leak_area * 1e6, ctl.vacuum(data), data.xpos[ep.tool].copy()))
    ep.recorder, ep.record_every = rec, 1
    res = runner.run_after_reset()
    print(trial, res["failure"], res.get("grasp_world"))
    t0 = rows[0][1]
    n = len(rows)
    idx = sorted(set(list(range(0, n, max(1, n // 30))) + [n - 1]))
    for i in idx:
        m, t, z, tv, ratio, leak, vac, x = rows[i]
        print(f" {m:9s} t {t - t0:.3f} axis ({z[0]:+.2f},{z[1]:+.2f},{z[2]:+.2f}) tilt ({tv[0]:+5.1f},{tv[1]:+5.1f}) ratio {ratio:.2f} leak {leak:5.1f} vac {vac:.2f} x ({x[0]:+.3f},{x[1]:+.3f},{x[2]:+.3f})")
