"""Two policies on the same trials (same task and seed): per object, how often the second policy's
chosen grasp has the higher q, and how many of each policy's chosen grasps the analytic label calls
robust. Run on a CEM and a dense run with the same model, it separates the search from the network:
the same q function, so a higher q and more robust grasps chosen by one policy is what its search
found and the other's missed.

Usage: python eval/gqcnn/search_gap.py RUN_A RUN_B [RUN_A2 RUN_B2 ...]   (pairs of `eval --out`
directories; pairs of several seeds are pooled)
"""

from __future__ import annotations

import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

from suctionbench.runlog.reader import read_run

ROBUST = 0.2
"""The label threshold of the datasets (robust wrench resistance above it: robust)."""


def chosen(run: Path) -> dict[int, tuple[tuple[str, str], float | None, float]]:
    """Trial index -> (object and trial seed, the policy's q, the chosen grasp's robust label) of a run."""
    out = {}
    for record in read_run(run / "trials"):
        result = record["result"]
        trial = int(Path(record["path"]).stem.split("_")[-1])
        where = (result["object"], str(result.get("seed")))  # the trial seed fixes the placement
        out[trial] = (where, result.get("policy_q"), float(result.get("label_rwr") or 0.0))
    return out


def main(pairs: list[tuple[Path, Path]]) -> None:
    rows: dict[str, list[tuple[float, bool, bool]]] = defaultdict(list)
    for run_a, run_b in pairs:
        a, b = chosen(run_a), chosen(run_b)
        for trial in sorted(set(a) & set(b)):
            if a[trial][0] != b[trial][0]:
                sys.exit(f"{run_a} and {run_b}: trial {trial} differs (not the same task and seed)")
            if a[trial][1] is None or b[trial][1] is None:
                continue
            rows[a[trial][0][0]].append((b[trial][1] - a[trial][1], a[trial][2] > ROBUST, b[trial][2] > ROBUST))
    print("| object | trials | B's q higher % | median q B - A | robust chosen (A, B) |")
    print("|---|---|---|---|---|")
    for name, values in sorted(rows.items()):
        v = np.asarray(values, float)
        print(f"| {name} | {len(v)} | {100 * np.mean(v[:, 0] > 0):.0f} | {np.median(v[:, 0]):+.3f} | "
              f"{int(v[:, 1].sum())}, {int(v[:, 2].sum())} |")


if __name__ == "__main__":
    args = [Path(p) for p in sys.argv[1:]]
    if len(args) < 2 or len(args) % 2 or not all((p / "trials").is_dir() for p in args):
        sys.exit("usage: python eval/gqcnn/search_gap.py RUN_A RUN_B [RUN_A2 RUN_B2 ...] (eval --out directories)")
    main(list(zip(args[::2], args[1::2], strict=True)))
