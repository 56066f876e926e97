"""How many contacts the simulated cup's vacuum probe has with the object as the lift starts, and
how much of their normals lies along the cup's axis, for the agreement trials the labeller calls
robust or the simulation carries (eval/README.md, "Now: the planned transport").

Usage: python eval/agreement/vacuum_probe_contacts.py PART PARTS OUT.json   (run two parts side by
side on 2 cores, ~2 min), then python eval/agreement/vacuum_probe_contacts.py --summary OUT0 OUT1 ...
"""

from __future__ import annotations

import json
import sys

import numpy as np

from suctionbench.evaluation.agreement import NOT_EXECUTED
from suctionbench.objects.registry import load_object
from suctionbench.sim.pick import PickRequest, PickRunner


def _recorder(episode, info):
    """Records, at the lift's first step, the probe's contact count and mean |normal . axis|."""
    model = episode.model

    def record(data, cup) -> None:
        if episode.motion != "lift" or info:
            return
        axis = data.xmat[cup.bellow].reshape(3, 3)[:, 2]
        shares = []
        for i in range(data.ncon):
            contact = data.contact[i]
            names = (model.geom(contact.geom1).name, model.geom(contact.geom2).name)
            if any(name.endswith("vacuum_probe") for name in names):
                shares.append(abs(float(contact.frame[:3] @ axis)))
        info["contacts"], info["axial"] = len(shares), float(np.mean(shares)) if shares else 0.0
    return record


def main(part: int, parts: int, out: str) -> None:
    with open("eval/agreement/agreement.json") as f:
        trials = [x for x in json.load(f)["per_trial"] if x["valid"] and x["failure"] not in NOT_EXECUTED
                  and x["label_rwr"] is not None and (x["label_rwr"] > 0.5 or x["success"])]
    rows = []
    for trial in trials[part::parts]:
        runner = PickRunner(PickRequest(trial["object"], policy="random-surface", record=load_object(trial["object"])))
        runner.request.seed = int(trial["seed"])
        runner.reset()
        info: dict = {}
        runner.episode.recorder, runner.episode.record_every = _recorder(runner.episode, info), 1
        result = runner.run_after_reset()
        rows.append({"object": trial["object"], "seed": trial["seed"], "rwr": trial["label_rwr"],
                     "success": result["success"], "failure": result["failure"], **info})
    with open(out, "w") as f:
        json.dump(rows, f)


def summary(paths: list[str]) -> None:
    rows = []
    for path in paths:
        with open(path) as f:
            rows += [r for r in json.load(f) if "contacts" in r]
    for several, name in ((False, "one probe contact"), (True, "several")):
        chosen = [r for r in rows if (r["contacts"] > 1) == several]
        robust = [r for r in chosen if r["rwr"] > 0.5]
        print(f"{name}: {len(chosen)} trials, {len(robust)} labelled robust, {sum(not r['success'] for r in robust)} "
              f"of those lost; mean axial share {np.mean([r['axial'] for r in chosen]):.3f}")


if __name__ == "__main__":
    if sys.argv[1] == "--summary":
        summary(sys.argv[2:])
    else:
        main(int(sys.argv[1]), int(sys.argv[2]), sys.argv[3])
