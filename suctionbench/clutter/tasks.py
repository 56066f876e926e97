"""Bin-picking tasks (tasks/bin-*.toml, `scene = "bin"`): which objects fill each bin, how many
bins, and when an episode gives up.

Bin i of a task draws its object count and its objects with the seed (seed, i), so every policy
faces the same bins, and drops them in the drawn order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from suctionbench.errors import InputError
from suctionbench.evaluation.tasks import read_task_toml, task_path


@dataclass(frozen=True)
class BinTask:
    """One bin-picking task."""

    name: str
    """Task name (the TOML file's stem)."""

    sets: tuple[str, ...]
    """Object sets the bins draw from (a mix: objects drawn from their union)."""

    objects: tuple[int, int]
    """Smallest and largest number of objects in a bin (drawn uniformly per bin)."""

    trials: int
    """Number of bins (episodes)."""

    max_failures: int = 3
    """K: an episode ends after this many consecutive failed attempts."""

    max_attempts: int = 0
    """An episode ends after this many attempts in all; 0: twice the bin's object count."""

    seed: int = 0
    """Base seed of the bins."""

    description: str = ""
    """What the task measures."""

    scene: str = "bin"
    """Always "bin": what tells a bin task from a single-object one."""

    def draw(self, trial: int, available: list[str]) -> list[str]:
        """Object keys (SET/NAME) of bin `trial`, in drop order: a count in `objects`, then that
        many distinct objects of `available` (repeats only if the sets hold fewer)."""
        rng = np.random.default_rng((self.seed, trial, 7))
        count = int(rng.integers(self.objects[0], self.objects[1] + 1))
        replace = count > len(available)
        picks = rng.choice(len(available), size=count, replace=replace)
        return [available[i] for i in picks]

    def attempts_for(self, count: int) -> int:
        """The attempt limit of a bin of `count` objects."""
        return self.max_attempts or 2 * count


FIELD_TYPES: dict[str, type] = {"name": str, "scene": str, "sets": list, "objects": list, "trials": int,
                                 "max_failures": int, "max_attempts": int, "seed": int, "description": str}
"""The TOML type of each bin-task key."""

MAX_OBJECTS = 20
"""Most objects a bin holds (the pick bin's floor is 34 x 30 cm)."""


def load_bin_task(name: str) -> BinTask:
    """A shipped bin task by name, or a bin-task TOML path; InputError naming the file and the key
    for anything malformed."""
    from suctionbench.validate import COUNT_MAX, OPTION_RULES

    path = task_path(name)
    data = read_task_toml(path, FIELD_TYPES)
    if data.get("scene") != "bin":
        raise InputError(f"task '{path}': not a bin task (no scene = \"bin\")")
    for key in ("sets", "objects", "trials"):
        if key not in data:
            raise InputError(f"task '{path}': no '{key}'")
    sets = data["sets"]
    if not sets or not all(isinstance(s, str) and s for s in sets):
        raise InputError(f"task '{path}': sets = {sets!r} must be a non-empty list of set names")
    objects = data["objects"]
    if (len(objects) != 2 or not all(isinstance(n, int) and not isinstance(n, bool) for n in objects)
            or not 1 <= objects[0] <= objects[1] <= MAX_OBJECTS):
        raise InputError(f"task '{path}': objects = {objects!r} must be [low, high] with 1 <= low <= high "
                         f"<= {MAX_OBJECTS}")
    OPTION_RULES["seed"].check(data.get("seed", 0), f"task '{path}': seed")
    for key, low in (("trials", 1), ("max_failures", 1), ("max_attempts", 0)):
        if key in data and not low <= data[key] <= COUNT_MAX:
            raise InputError(f"task '{path}': {key} = {data[key]} must be in [{low}, {COUNT_MAX}]")
    data["sets"], data["objects"] = tuple(sets), (int(objects[0]), int(objects[1]))
    return BinTask(**data)
