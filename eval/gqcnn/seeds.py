"""The pooled table of `eval/gqcnn/seeds.sh`: success and AP per policy and set over every seed run,
and each policy against a base policy trial by trial (exact McNemar over the pooled trials).

Usage: python eval/gqcnn/seeds.py RUNS [BASE]   (BASE: a NAME given to seeds.sh; default: the first)

Runs are RUNS/NAME_SET_sSEED (seeds.sh, or renamed benchmark runs). Trial i of one task and seed
holds the same object in the same placement for every policy, so across seeds the trials stay
paired and the discordant counts add up. Success: pooled over seeds, with its binomial standard
error; AP: the mean of the seeds' APs (each run's AP of q against the simulated outcome).
"""

from __future__ import annotations

import json
import math
import re
import sys
from collections import defaultdict
from functools import cache
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from paired import mcnemar_p, outcomes  # noqa: E402

RUN_NAME = re.compile(r"^(?P<name>.+)_(?P<set>[a-z]+)_s(?P<seed>\d+)$")


def collect(runs: Path) -> dict[tuple[str, str], dict[int, Path]]:
    """(name, set) -> {seed: run directory} of the finished runs under `runs`."""
    found: dict[tuple[str, str], dict[int, Path]] = defaultdict(dict)
    for path in sorted(runs.iterdir()):
        match = RUN_NAME.match(path.name)
        if match and (path / "run.json").is_file():
            found[match["name"], match["set"]][int(match["seed"])] = path
    return found


def run_figure(run: Path, key: str = "ap") -> float | None:
    """One figure of the run (`key`: its AP by default) as its `eval --json` line (seeds.sh: RUN.json
    beside it) gives it; None when the line or the figure is missing."""
    line = run.with_suffix(".json")
    if not line.is_file():
        return None
    value = json.loads(line.read_text()).get(key)
    return None if value is None else float(value)


def main(runs: Path, base: str | None) -> None:
    found = collect(runs)
    outcomes_of = cache(outcomes)  # each run's logs read once (the base's are compared with every policy)
    names = list(dict.fromkeys(name for name, _ in found))
    base = base or names[0]
    print(f"| policy | set | seeds | successes per seed | success % (pooled, +- se) | mean AP % | "
          f"only {base} / only policy (pooled) | McNemar p |")
    print("|---|---|---|---|---|---|---|---|")
    for (name, task), seeds in sorted(found.items(), key=lambda kv: (kv[0][1], names.index(kv[0][0]))):
        per_seed, wins, trials, only_base, only_run = [], 0, 0, 0, 0
        for seed, run in sorted(seeds.items()):
            result = outcomes_of(run)
            per_seed.append(sum(ok for _, ok in result.values()))
            wins, trials = wins + per_seed[-1], trials + len(result)
            other = found.get((base, task), {}).get(seed)
            if other is not None and name != base:
                ref = outcomes_of(other)
                shared = set(ref) & set(result)
                only_base += sum(ref[i][1] and not result[i][1] for i in shared)
                only_run += sum(result[i][1] and not ref[i][1] for i in shared)
        rate = wins / trials
        aps = [ap for ap in (run_figure(r) for r in seeds.values()) if ap is not None]
        mean_ap = f"{100 * sum(aps) / len(aps):.1f}" if aps else "-"
        paired = "-" if name == base else f"{only_base} / {only_run}"
        p = "-" if name == base else f"{mcnemar_p(only_base, only_run):.3f}"
        print(f"| {name} | {task} | {','.join(map(str, sorted(seeds)))} | {', '.join(map(str, per_seed))} | "
              f"{100 * rate:.1f} +- {100 * math.sqrt(rate * (1 - rate) / trials):.1f} | {mean_ap} | {paired} | {p} |")


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3) or not Path(sys.argv[1]).is_dir():
        sys.exit("usage: python eval/gqcnn/seeds.py RUNS [BASE]")
    main(Path(sys.argv[1]), sys.argv[2] if len(sys.argv) == 3 else None)
