"""Benchmark tasks (tasks/*.toml): which objects, how many trials, how they are placed."""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

from suctionbench.errors import InputError


@dataclass(frozen=True)
class Task:
    """One benchmark task."""

    name: str
    """Task name (the TOML file's stem)."""

    set: str
    """Object set the trials draw from."""

    trials: int
    """Number of trials; trial i uses object i mod |set| and seed (seed, i), identical across policies."""

    placement: str = "drop"
    """'drop' (random orientation, settled) or 'stable' (stable pose + planar pose)."""

    seed: int = 0
    """Base seed of the trials."""

    stable_poses: int = 1
    """With 'stable' placement: trials cycle through this many most probable poses."""

    metrics: tuple[str, ...] = field(default_factory=tuple)
    """Known-state 3D metrics compared by this task (known_objects); empty for policy tasks."""

    description: str = ""
    """What the task measures."""


def tasks_dir() -> Path:
    """The shipped task definitions."""
    return Path(str(resources.files("suctionbench.tasks")))


FIELD_TYPES: dict[str, type] = {"name": str, "set": str, "trials": int, "placement": str, "seed": int,
                                 "stable_poses": int, "metrics": list, "description": str}
"""The TOML type of each task key (metrics: a list of metric names)."""


def task_path(name: str) -> Path:
    """The TOML file of a task: a shipped task by name, or a path ending in .toml; InputError
    naming the shipped tasks when there is none."""
    path = Path(name) if name.endswith(".toml") else tasks_dir() / f"{name}.toml"
    if not path.is_file():
        known = ", ".join(sorted(p.stem for p in tasks_dir().glob("*.toml")))
        raise InputError(f"task '{name}' is unknown (known: {known})")
    return path


def read_task_toml(path: Path, field_types: dict[str, type]) -> dict:
    """A task file's keys, `name` defaulting to the file's stem; InputError naming the file for
    anything but UTF-8 TOML whose keys are all in `field_types` with those types."""
    try:
        data = tomllib.loads(path.read_text())
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"task '{path}': unreadable ({type(exc).__name__}: not a UTF-8 TOML file?)") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"task '{path}': malformed TOML ({exc})") from None
    data.setdefault("name", path.stem)
    unknown = sorted(set(data) - set(field_types))
    if unknown:
        raise InputError(f"task '{path}': unknown key(s) {', '.join(unknown)} (known: {', '.join(field_types)})")
    for key, kind in field_types.items():
        if key in data and (not isinstance(data[key], kind) or isinstance(data[key], bool)):
            raise InputError(f"task '{path}': {key} = {data[key]!r} must be a {kind.__name__}")
    return data


def is_bin_task(name: str) -> bool:
    """Whether a task names a cluttered-bin task (`scene = "bin"`, suctionbench.clutter.tasks)."""
    try:
        path = task_path(name)
        return tomllib.loads(path.read_text()).get("scene") == "bin"
    except (InputError, OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return False  # load_task names the problem


def load_task(name: str) -> Task:
    """A shipped task by name, or a task TOML file by path; InputError naming the file and the key
    for anything malformed: not UTF-8 TOML, unknown keys, wrong types, values out of range."""
    from suctionbench.contact.metrics import METRICS
    from suctionbench.sim.pick import PLACEMENTS
    from suctionbench.validate import COUNT_MAX, OPTION_RULES

    path = task_path(name)
    data = read_task_toml(path, FIELD_TYPES)
    if "set" not in data:
        raise InputError(f"task '{path}': no 'set' (the object set the trials draw from)")
    if "trials" not in data:
        raise InputError(f"task '{path}': no 'trials' (how many)")
    bad = [m for m in data.get("metrics", []) if m not in METRICS]
    if bad:
        raise InputError(f"task '{path}': metrics {bad} unknown (known: {', '.join(METRICS)})")
    data["metrics"] = tuple(data.get("metrics", ()))
    if data.get("placement", "drop") not in PLACEMENTS:
        raise InputError(f"task '{path}': placement '{data['placement']}' must be one of {', '.join(PLACEMENTS)}")
    OPTION_RULES["seed"].check(data.get("seed", 0), f"task '{path}': seed")
    for key in ("trials", "stable_poses"):
        if key in data and not 1 <= data[key] <= COUNT_MAX:
            raise InputError(f"task '{path}': {key} = {data[key]} must be in [1, {COUNT_MAX}]")
    return Task(**data)
