"""The training labels' loads: quasi-static (what `generate` used before b834b29) against the
episode's (what the benchmark scores a pick by) on the same corpus grasps.

Usage: python eval/gqcnn/label_loads.py CORPUS_DIR
Every 75th object of the corpus (20 objects), 100 uniform surface grasps each, those facing up to
80 deg in its most probable stable pose, both labels at seed 0; positives at rwr > 0.2 (the
training threshold), shares weighted by grasps.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from suctionbench.config import CUP_DEFAULT, STANDARD_GRAVITY, LabelConfig
from suctionbench.contact import SuctionLabeller
from suctionbench.geometry.sampling import sample_surface_grasps
from suctionbench.objects.build import ObjectRecord

THRESHOLD = 0.2
"""Training label threshold (Dex-Net 3.0)."""


def main(corpus: Path) -> None:
    configs = (LabelConfig(cup=CUP_DEFAULT), LabelConfig.for_episode(CUP_DEFAULT))
    rows = []
    for directory in sorted((corpus / "train").iterdir())[::75][:20]:
        record = ObjectRecord.load(directory)
        mesh = record.mesh()
        points, approaches = sample_surface_grasps(mesh, 100, np.random.default_rng(0))
        rotation = np.asarray(record.stable_poses[0]["transform"])[:3, :3]
        up = rotation.T @ np.array([0.0, 0.0, 1.0])
        facing = -(approaches @ up) >= np.cos(np.radians(80))
        points, approaches = points[facing], approaches[facing]
        labellers = [SuctionLabeller(mesh, config, mass=record.mass, com=np.asarray(record.com),
                                     gravity=-STANDARD_GRAVITY * up) for config in configs]
        positive = [lab.label(points, approaches, 0, metrics=("rwr",)).rwr > THRESHOLD for lab in labellers]
        rows.append((len(points), positive[0].mean(), positive[1].mean(), (positive[0] != positive[1]).mean()))
        print(f"{directory.name:28s} mass {record.mass:.3f} kg, {len(points):3d} grasps: quasi-static positive "
              f"{rows[-1][1]:.2f}, episode positive {rows[-1][2]:.2f}, labels differ {rows[-1][3]:.2f}", flush=True)
    table = np.array(rows, dtype=float)
    quasi, episode, differ = (table[:, 1:] * table[:, :1]).sum(axis=0) / table[:, 0].sum()
    print(f"weighted by grasps: quasi-static positive {quasi:.3f}, episode positive {episode:.3f}, "
          f"labels differ {differ:.3f}")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
