"""How sure a policy was of the trials it failed, pooled over the seeds of eval/gqcnn/seeds.sh runs.

Usage: python eval/gqcnn/confident_failures.py RUNS SET NAME [NAME ...]
Per NAME (runs RUNS/NAME_SET_sSEED): the mean q (`policy_q` of the trial log) of its successes and
of its failures, how many failures it scored q >= 0.9, and the seeds' mean share of chosen grasps
the labeller calls robust and Spearman of q with success (the runs' `eval --json` lines); then,
for the first two NAMEs, the objects whose mean q rose most from the first to the second, with
their success rates. A model whose q rises on trials that fail ranks the trials worse, which is what lowers its AP.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from paired import valid_results  # noqa: E402
from seeds import collect, run_figure  # noqa: E402


def pooled(seed_runs: list[Path]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, success, object) of every valid trial of `seed_runs`, pooled."""
    rows = [(r["policy_q"], bool(r["success"]), r["object"]) for run in seed_runs for r in valid_results(run).values()]
    q, success, objects = zip(*rows, strict=True)
    return np.asarray(q, float), np.asarray(success), np.asarray(objects)


def seed_mean(seed_runs: list[Path], key: str) -> str:
    """The runs' mean of one `eval --json` figure, or '-' where no run has it."""
    values = [v for v in (run_figure(run, key) for run in seed_runs) if v is not None]
    return f"{sum(values) / len(values):.3f}" if values else "-"


def by_object(q: np.ndarray, success: np.ndarray, objects: np.ndarray) -> dict[str, tuple[float, float]]:
    """object -> (mean q, success rate)."""
    return {str(name): (float(q[objects == name].mean()), float(success[objects == name].mean()))
            for name in np.unique(objects)}


def main(runs: Path, task_set: str, names: list[str]) -> None:
    found, tables = collect(runs), {}
    print("| policy | trials | mean q, successes | mean q, failures | failures at q >= 0.9 | "
          "labelled robust (mean of seeds) | Spearman q, success (mean of seeds) |")
    print("|---|---|---|---|---|---|---|")
    for name in names:
        seed_runs = list(found.get((name, task_set), {}).values())
        if not seed_runs:
            sys.exit(f"{runs}: no finished runs named {name}_{task_set}_sSEED")
        q, success, objects = pooled(seed_runs)
        tables[name] = by_object(q, success, objects)
        print(f"| {name} | {len(q)} | {q[success].mean():.3f} | {q[~success].mean():.3f} | "
              f"{int(((q >= 0.9) & ~success).sum())} of {int((~success).sum())} | "
              f"{seed_mean(seed_runs, 'label_positive_rate')} | {seed_mean(seed_runs, 'spearman_q')} |")
    if len(names) >= 2:
        a, b = tables[names[0]], tables[names[1]]
        shared = sorted(set(a) & set(b), key=lambda o: b[o][0] - a[o][0], reverse=True)
        print(f"\nMean q rose most ({names[0]} -> {names[1]}):")
        for name in shared[:6]:
            print(f"- {name}: q {a[name][0]:.2f} -> {b[name][0]:.2f}, success {a[name][1]:.0%} -> {b[name][1]:.0%}")


if __name__ == "__main__":
    if len(sys.argv) < 4 or not Path(sys.argv[1]).is_dir():
        sys.exit("usage: python eval/gqcnn/confident_failures.py RUNS SET NAME [NAME ...]")
    main(Path(sys.argv[1]), sys.argv[2], sys.argv[3:])
