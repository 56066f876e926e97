"""Two eval runs of one task compared trial by trial: which policy's success rate is higher, and
whether one seeded run can tell (an exact McNemar test on the trials only one of them succeeded).

Usage: python eval/gqcnn/paired.py RUN_A RUN_B [RUN_C ...]   (each an `eval --out` directory)

Trial i of every run of a task with the same --seed holds the same object in the same placement
(`evaluation.runner`), so the runs are paired: the trials both succeed or both fail say nothing
about which policy is better; the discordant ones do. Under "no difference" each discordant trial
is a fair coin, so the two-sided p-value is the binomial tail of the smaller count (McNemar's exact
test). With 125 trials an unpaired success rate has a standard error of ~4.5 points; pairing removes
the objects' and placements' share of it.
"""

from __future__ import annotations

import sys
from math import comb
from pathlib import Path

from suctionbench.runlog.reader import read_run


def valid_results(run: Path) -> dict[int, dict]:
    """Trial index -> logged result of the run's valid trials."""
    out = {}
    for record in read_run(run / "trials"):
        if record["result"].get("valid", True):
            out[int(Path(record["path"]).stem.split("_")[-1])] = record["result"]
    return out


def outcomes(run: Path) -> dict[int, tuple[str, bool]]:
    """Trial index -> (object, success) of the run's valid trials."""
    return {i: (result["object"], bool(result["success"])) for i, result in valid_results(run).items()}


def mcnemar_p(only_a: int, only_b: int) -> float:
    """Two-sided exact McNemar p-value for `only_a` and `only_b` discordant trials."""
    n = only_a + only_b
    if n == 0:
        return 1.0
    tail = sum(comb(n, k) for k in range(min(only_a, only_b) + 1)) / 2**n
    return min(1.0, 2.0 * tail)


def main(runs: list[Path]) -> None:
    base, base_out = runs[0], outcomes(runs[0])
    print("| run | valid paired trials | successes (base, run) | only base / only run | McNemar p |")
    print("|---|---|---|---|---|")
    for run in runs[1:]:
        other = outcomes(run)
        shared = sorted(set(base_out) & set(other))
        if any(base_out[i][0] != other[i][0] for i in shared):
            sys.exit(f"{base} and {run}: trial objects differ (not the same task and seed)")
        a = sum(base_out[i][1] for i in shared)
        b = sum(other[i][1] for i in shared)
        only_a = sum(base_out[i][1] and not other[i][1] for i in shared)
        only_b = sum(other[i][1] and not base_out[i][1] for i in shared)
        print(f"| {run} vs {base} | {len(shared)} | {a}, {b} | {only_a} / {only_b} | {mcnemar_p(only_a, only_b):.3f} |")


if __name__ == "__main__":
    if len(sys.argv) < 3 or not all(Path(p, "trials").is_dir() for p in sys.argv[1:]):
        sys.exit("usage: python eval/gqcnn/paired.py RUN_A RUN_B [RUN_C ...] (eval --out directories)")
    main([Path(p) for p in sys.argv[1:]])
