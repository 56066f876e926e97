"""Probe: the tool's tilt from vertical, angular rate/acceleration and linear acceleration in the transport."""
import math, sys
import numpy as np
from suctionbench.objects.registry import load_object
from suctionbench.sim.pick import PickRequest, PickRunner

for trial in sys.argv[1:]:
    key, seed = trial.rsplit(":", 1)
    runner = PickRunner(PickRequest(key, policy="random-surface", record=load_object(key)))
    runner.request.seed = int(seed)
    runner.reset()
    ep = runner.episode
    rows = {"lift": [], "transport": []}
    def rec(data, ctl):
        if ep.motion in rows:
            site = ep.tip; tb = ep.tool
            R = data.xmat[tb].reshape(3, 3)
            rows[ep.motion].append((data.time, data.site_xpos[site].copy(), R[:, 2].copy(), ctl.bellows_tilt(data)))
    ep.recorder, ep.record_every = rec, 1
    res = runner.run_after_reset()
    print(trial, res["failure"] if isinstance(res, dict) else res)
    dt = ep.model.opt.timestep
    for m, st in rows.items():
        if len(st) < 5: continue
        t = np.array([s[0] for s in st]); x = np.array([s[1] for s in st]); z = np.array([s[2] for s in st]); b = np.array([s[3] for s in st])
        tilt = np.degrees(np.arccos(np.clip(np.abs(z[:, 2]), -1, 1)))
        # angular rate of the axis
        dz = np.diff(z, axis=0) / dt
        w = np.linalg.norm(dz, axis=1)
        al = np.linalg.norm(np.diff(dz, axis=0), axis=1) / dt
        acc = np.linalg.norm(x[2:] - 2 * x[1:-1] + x[:-2], axis=1) / dt**2
        print(f" {m}: dur {t[-1]-t[0]:.2f}s axis tilt max {tilt.max():.1f} deg, axis rate max {math.degrees(w.max()):.0f} deg/s,"
              f" axis ang acc max {math.degrees(al.max()):.0f} deg/s2, lin acc max {acc.max():.2f}, bellows tilt max {math.degrees(b.max()) if b.max()<3 else b.max():.1f}")
        for i in range(0, len(t), max(1, len(t)//12)):
            print(f"   t {t[i]-t[0]:.3f} tilt {tilt[i]:.1f} bellows {math.degrees(b[i]) if b.max()<3 else b[i]:.1f}")
