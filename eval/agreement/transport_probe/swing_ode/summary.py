"""Transport verdicts of the time-resolved swing and the closed form against the simulation, from
swing_ode.py's runs (git show 2b5bc1a:eval/agreement/transport_probe/swing_ode.py; run this from the
repository root)."""
import json

import numpy as np

rows = []
for part in (0, 1):
    with open(f"eval/agreement/transport_probe/swing_ode/ode_{part}.json") as f:
        rows += json.load(f)
carried = np.array([r["success"] for r in rows])
verdicts = {
    "time-resolved": np.array([r["ode"]["held_transport"] and r["ode"]["held_hold"] for r in rows]),
    "closed form": np.array([all(r["closed_ok"][1:]) for r in rows]),
}
for name, held in verdicts.items():
    counts = {"carried & held": carried & held, "carried & rejected": carried & ~held,
              "lost & held": ~carried & held, "lost & rejected": ~carried & ~held}
    print(f"{name:14s}", ", ".join(f"{label} {int(mask.sum())}" for label, mask in counts.items()))
