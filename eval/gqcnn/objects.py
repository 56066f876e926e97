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

import numpy as np


def main(out: Path) -> None:
    runs = []
    for path in out.glob("*d*_n*.json"):
        match = re.fullmatch(r"(init_)?d(\d+)_n(\d+)(?:_s(\d+))?", path.stem)
        if match is None:
            continue
        init, d, n, seed = match.groups()
        history = json.loads((out / path.stem / "model.json").read_text())["history"]
        runs.append((int(d), int(n), json.loads(path.read_text()), history, int(seed or 0), bool(init)))
    runs.sort(key=lambda r: (r[5], r[0], r[1], r[4]))
    print("| start | datapoints | objects | seed | datapoints / object | held-out accuracy by epoch | AP | "
          "fit accuracy | fit - held-out |")
    print("|---|---|---|---|---|---|---|---|---|")
    for _, n, run, history, seed, init in runs:
        epochs = " / ".join(f"{h['val_accuracy']:.4f}" for h in history)
        start = "fine-tuned" if init else "scratch"
        print(f"| {start} | {run['num_train']:,} | {n:,} | {seed} | {run['num_train'] / n:,.0f} | {epochs} | "
              f"{run['val_ap']:.4f} | {run['fit_accuracy']:.4f} | {run['fit_accuracy'] - run['val_accuracy']:+.4f} |")
    print()
    for init, d in sorted({(r[5], r[0]) for r in runs}):
        group = [r for r in runs if r[0] == d and r[5] == init]
        if len({r[1] for r in group}) < 2:
            continue
        x = np.log2([r[1] for r in group])
        y = np.array([r[2]["val_accuracy"] for r in group])
        slope = np.polyfit(x, y, 1)[0]
        arms = ", ".join(f"{r[1]} (seed {r[4]}): {r[2]['val_accuracy']:.4f}" for r in group)
        start = "fine-tuned, " if init else ""
        print(f"{start}D = {d:,}: held-out accuracy {slope * 100:+.2f} points per doubling of the objects ({arms})")


if __name__ == "__main__":
    if len(sys.argv) != 2 or not Path(sys.argv[1]).is_dir():
        sys.exit("usage: python eval/gqcnn/objects.py OUT_DIR (the directory eval/gqcnn/objects.sh wrote)")
    main(Path(sys.argv[1]))
