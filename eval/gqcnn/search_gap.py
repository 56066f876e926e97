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

sys.path.insert(0, str(Path(__file__).resolve().parent))
from paired import valid_results  # noqa: E402

from suctionbench.learning.data import DEFAULT_LABEL_THRESHOLD  # noqa: E402


def robust(result: dict) -> bool:
    """Whether the analytic label calls the chosen grasp robust, as the datasets label it."""
    return float(result.get("label_rwr") or 0.0) > DEFAULT_LABEL_THRESHOLD


def main(pairs: list[tuple[Path, Path]]) -> None:
    rows: dict[str, list[tuple[float, bool, bool]]] = defaultdict(list)
    for run_a, run_b in pairs:
        a, b = valid_results(run_a), valid_results(run_b)
        for trial in sorted(set(a) & set(b)):
            ra, rb = a[trial], b[trial]
            if (ra["object"], ra.get("seed")) != (rb["object"], rb.get("seed")):  # the seed fixes the placement
                sys.exit(f"{run_a} and {run_b}: trial {trial} differs (not the same task and seed)")
            if ra.get("policy_q") is None or rb.get("policy_q") is None:
                continue
            rows[ra["object"]].append((rb["policy_q"] - ra["policy_q"], robust(ra), robust(rb)))
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
