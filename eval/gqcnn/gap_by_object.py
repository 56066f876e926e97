"""Where a gap between policies lies, per object, pooled over the seeds of eval/gqcnn/seeds.sh runs.

Usage: python eval/gqcnn/gap_by_object.py RUNS SET NAME [NAME ...]
Per object of SET (runs RUNS/NAME_SET_sSEED, the seeds every NAME has), each NAME's successes and
the share of its chosen grasps the labeller calls robust (rwr > 0.5, the eval's threshold), then the
objects ordered by how many more trials the first NAME carried than the last. Meant for the bounds:
`known` (analytic: grasps on the whole mesh ranked in the true state), `img` (analytic-image: the
grasps the depth image offers, ranked in the true state), `uni` (analytic-image-uniform: the same,
believing the object of uniform density) and an image policy. The first gap is what the view costs
(grasps the camera does not offer, normals it reads wrongly), the second what the mass no image
shows costs a ranker that does not know it, the third what the image policy's scoring and search
cost beyond that (negative where the network has learned a kind's mass distribution).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from paired import valid_results  # noqa: E402
from seeds import collect  # noqa: E402

ROBUST = 0.5
"""The eval's threshold on the executed grasp's rwr label (`label_positive_rate`)."""


def tally(runs: list[Path]) -> dict[str, list[int]]:
    """object -> [trials, successes, chosen grasps labelled robust], pooled over `runs`."""
    counts: dict[str, list[int]] = {}
    for run in runs:
        for result in valid_results(run).values():
            row = counts.setdefault(result["object"], [0, 0, 0])
            row[0] += 1
            row[1] += bool(result["success"])
            row[2] += (result.get("label_rwr") or 0.0) > ROBUST
    return counts


def main(runs: Path, set_name: str, names: list[str]) -> None:
    found = collect(runs)
    missing = [n for n in names if (n, set_name) not in found]
    if missing:
        raise SystemExit(f"no runs of {', '.join(missing)} on {set_name} in {runs}")
    seeds = sorted(set.intersection(*(set(found[n, set_name]) for n in names)))
    tallies = {n: tally([found[n, set_name][s] for s in seeds]) for n in names}

    def wins(name: str, obj: str) -> int:
        return tallies[name].get(obj, [0, 0, 0])[1]

    objects = sorted(set().union(*tallies.values()), key=lambda o: (wins(names[-1], o) - wins(names[0], o), o))
    print(f"{set_name}, seeds {', '.join(map(str, seeds))}: successes / trials (chosen grasps labelled robust)")
    print("| object | " + " | ".join(names) + f" | {names[0]} - {names[-1]} |")
    print("|---" * (len(names) + 2) + "|")
    total = {n: [0, 0, 0] for n in names}
    for obj in objects:
        cells = []
        for n in names:
            trials, carried, robust = tallies[n].get(obj, [0, 0, 0])
            cells.append(f"{carried}/{trials} ({robust})")
            total[n] = [a + b for a, b in zip(total[n], (trials, carried, robust), strict=True)]
        gap = wins(names[0], obj) - wins(names[-1], obj)
        print(f"| {obj} | " + " | ".join(cells) + f" | {gap:+d} |")
    cells = [f"{100 * w / t:.1f} % ({100 * r / t:.1f} %)" for t, w, r in total.values()]
    first, last = total[names[0]], total[names[-1]]
    points = 100 * (first[1] / first[0] - last[1] / last[0])
    print("| all | " + " | ".join(cells) + f" | {points:+.1f} points |")


if __name__ == "__main__":
    if len(sys.argv) < 4:
        raise SystemExit(__doc__)
    main(Path(sys.argv[1]), sys.argv[2], sys.argv[3:])
