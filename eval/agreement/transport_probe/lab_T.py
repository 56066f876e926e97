import math, sys, dataclasses
import numpy as np
sys.path.insert(0, "eval/agreement")
from lip_peak import labelled
from suctionbench.config import LabelConfig, PerturbationConfig
from suctionbench.objects.registry import load_object
from suctionbench.sim.pick import PickRequest, PickRunner
import suctionbench.config as C
for trial in sys.argv[1:]:
    key, seed = trial.rsplit(":", 1)
    runner = PickRunner(PickRequest(key, policy="random-surface", record=load_object(key)))
    runner.request.seed = int(seed); runner.reset(); pose = runner.object_pose()
    res = runner.run_after_reset()
    print(trial, res["failure"], res["peak_acceleration"] if "peak_acceleration" in res else "", res.get("label_rwr"))
    orig = C.PerturbationConfig.for_episode.__func__
    for T in (0.5, 0.6, 0.7, 0.8, 0.9, 1.1):
        def fe(cls, cup, T=T):
            return dataclasses.replace(orig(cls, cup), transport_time=T)
        C.PerturbationConfig.for_episode = classmethod(fe)
        print("  T", T, labelled(runner, pose, res))
    C.PerturbationConfig.for_episode = classmethod(orig)
