"""Print the object-diversity learning curve (Markdown) from the runs eval/gqcnn/objects.sh writes.

Usage: python eval/gqcnn/objects.py OUT_DIR
One row per arm (D datapoints from N training objects, seed S): held-out accuracy after every
epoch (50,000 validation datapoints of the 300 unseen objects, the same in every arm of a seed),
the last epoch's AP and fit accuracy (training datapoints scored without augmentation). Then, per
datapoint count with two or more object counts, the held-out accuracy's least-squares slope per
doubling of the number of objects (over every arm and seed of that count). Arms that fine-tuned a
trained model (INIT=MODEL, named init_...) are marked "fine-tuned" and get slopes of their own.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path
from typing import NamedTuple

import numpy as np


class Arm(NamedTuple):
    """One finished arm: D datapoints from N objects, its train --json line and per-epoch history."""

    fine_tuned: bool
    datapoints: int
    objects: int
    seed: int
    run: dict
    history: list[dict]


def main(out: Path) -> None:
    arms = []
    for path in out.glob("*d*_n*.json"):
        match = re.fullmatch(r"(init_)?d(\d+)_n(\d+)(?:_s(\d+))?", path.stem)
        if match is None:
            continue
        init, d, n, seed = match.groups()
        history = json.loads((out / path.stem / "model.json").read_text())["history"]
        arms.append(Arm(bool(init), int(d), int(n), int(seed or 0), json.loads(path.read_text()), history))
    arms.sort(key=lambda a: (a.fine_tuned, a.datapoints, a.objects, a.seed))
    print("| start | datapoints | objects | seed | datapoints / object | held-out accuracy by epoch | AP | "
          "fit accuracy | fit - held-out |")
    print("|---|---|---|---|---|---|---|---|---|")
    for a in arms:
        epochs = " / ".join(f"{h['val_accuracy']:.4f}" for h in a.history)
        run = a.run
        print(f"| {'fine-tuned' if a.fine_tuned else 'scratch'} | {run['num_train']:,} | {a.objects:,} | {a.seed} | "
              f"{run['num_train'] / a.objects:,.0f} | {epochs} | {run['val_ap']:.4f} | {run['fit_accuracy']:.4f} | "
              f"{run['fit_accuracy'] - run['val_accuracy']:+.4f} |")
    print()
    for fine_tuned, d in sorted({(a.fine_tuned, a.datapoints) for a in arms}):
        group = [a for a in arms if (a.fine_tuned, a.datapoints) == (fine_tuned, d)]
        if len({a.objects for a in group}) < 2:
            continue
        x = np.log2([a.objects for a in group])
        y = np.array([a.run["val_accuracy"] for a in group])
        slope = np.polyfit(x, y, 1)[0]
        listed = ", ".join(f"{a.objects} (seed {a.seed}): {a.run['val_accuracy']:.4f}" for a in group)
        start = "fine-tuned, " if fine_tuned else ""
        print(f"{start}D = {d:,}: held-out accuracy {slope * 100:+.2f} points per doubling of the objects ({listed})")

if __name__ == "__main__":
    if len(sys.argv) != 2 or not Path(sys.argv[1]).is_dir():
        sys.exit("usage: python eval/gqcnn/objects.py OUT_DIR (the directory eval/gqcnn/objects.sh wrote)")
    main(Path(sys.argv[1]))
