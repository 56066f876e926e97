"""Per object, what a run's policy chose: successes, the analytic label of the executed grasps and
the ways they failed, read from the run's episode logs (each /result message).

Usage: python eval/gqcnn/chosen_labels.py RUN [RUN ...]   (each an `eval --out` directory)

Why: a run's summary gives one `label_positive_rate` per set (rwr > 0.5, the eval's threshold). To
see whether a policy loses an object because it picks grasps the labeller rejects (a learning or
perception miss) or because the simulated cup drops what the labeller passes (a labeller miss),
the per-object counts at the dataset's own label threshold (rwr > 0.2) are needed beside the
successes. Columns: trials, successes, median rwr of the chosen grasps, chosen grasps with rwr >
0.2 and > 0.5, successes among the > 0.2 ones, the commonest simulated failures and the labeller's
seal verdicts (None: it sealed).
"""

from __future__ import annotations

import sys
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np

from suctionbench.runlog.reader import read_run


def trials_of(run: Path) -> list[dict]:
    """The /result messages of a run directory (its `trials/` folder, or the folder itself)."""
    folder = run / "trials" if (run / "trials").is_dir() else run
    return [episode["result"] for episode in read_run(folder) if episode["result"] is not None]


def main(runs: list[str]) -> None:
    print("| run | object | trials | successes | median rwr | rwr > 0.2 | rwr > 0.5 | successes with rwr > 0.2 "
          "| simulated failures | labeller's seal |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for run in map(Path, runs):
        by_object: dict[str, list[dict]] = defaultdict(list)
        for result in trials_of(run):
            by_object[result["object"]].append(result)
        for name, results in sorted(by_object.items()):
            rwr = np.array([np.nan if r.get("label_rwr") is None else r["label_rwr"] for r in results], float)
            success = np.array([bool(r.get("success")) for r in results])
            robust = np.nan_to_num(rwr, nan=0.0) > 0.2
            failures = Counter(r.get("failure") for r in results if not r.get("success")).most_common(2)
            seals = Counter(r.get("label_seal_failure") for r in results).most_common(2)
            median = "-" if np.isnan(rwr).all() else f"{np.nanmedian(rwr):.2f}"
            print(f"| {run.name} | {name.split('/')[-1]} | {len(results)} | {int(success.sum())} | {median} | "
                  f"{int(robust.sum())} | {int((np.nan_to_num(rwr) > 0.5).sum())} | {int(success[robust].sum())} | "
                  f"{', '.join(f'{k} {n}' for k, n in failures)} | {', '.join(f'{k} {n}' for k, n in seals)} |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
