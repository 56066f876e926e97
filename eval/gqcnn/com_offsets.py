"""How far each kind of a corpus's objects has its centre of mass from its shape's: where a mass
distribution no depth image shows can decide a label at all.

Usage: python eval/gqcnn/com_offsets.py CORPUS [EVERY]
Every EVERY-th object of CORPUS (`objects generate` output, or any source `resolve_objects` reads;
EVERY 1 by default), grouped by the kind its name ends in (train_NNNNN_KIND): the distance from the
record's centre of mass to the shape's volume centroid (`policies.analytic.uniform_density_com`, what
`analytic-image-uniform` believes), its median and the shares beyond 2 and 5 mm; for the household
kind, the generators whose median is beyond 1 mm.
"""

from __future__ import annotations

import sys
from collections import defaultdict

import numpy as np

from suctionbench.objects.registry import resolve_objects
from suctionbench.policies.analytic import uniform_density_com


def main(corpus: str, every: int = 1) -> None:
    offsets: dict[str, list[tuple[float, str]]] = defaultdict(list)
    for record in resolve_objects(corpus)[::every]:
        offset = float(np.linalg.norm(np.asarray(record.com) - uniform_density_com(record.mesh()))) * 1000
        offsets[record.name.rsplit("_", 1)[-1]].append((offset, record.generator))
    print(f"{corpus}, every {every}th object: centre of mass from the shape's (mm)")
    print("| kind | objects | median | beyond 2 mm | beyond 5 mm |")
    print("|---|---|---|---|---|")
    for kind, rows in sorted(offsets.items()):
        mm = np.array([o for o, _ in rows])
        beyond = [f"{100 * np.mean(mm > limit):.0f} %" for limit in (2, 5)]
        print(f"| {kind} | {len(mm)} | {np.median(mm):.2f} | {beyond[0]} | {beyond[1]} |")
    by_generator: dict[str, list[float]] = defaultdict(list)
    for offset, generator in offsets.get("household", []):
        by_generator[generator].append(offset)
    wide = {g: round(float(np.median(v)), 1) for g, v in sorted(by_generator.items()) if np.median(v) > 1}
    print(f"household generators with a median beyond 1 mm: {wide}")


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3):
        raise SystemExit(__doc__)
    main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) == 3 else 1)
