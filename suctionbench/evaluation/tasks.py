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


def load_task(name: str) -> Task:
    """A shipped task by name, or a task TOML file by path."""
    path = Path(name) if name.endswith(".toml") else tasks_dir() / f"{name}.toml"
    if not path.is_file():
        known = ", ".join(sorted(p.stem for p in tasks_dir().glob("*.toml")))
        raise InputError(f"task '{name}' is unknown (known: {known})")
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"task '{path}': malformed TOML ({exc})") from None
    data.setdefault("name", path.stem)
    data["metrics"] = tuple(data.get("metrics", ()))
    try:
        task = Task(**data)
    except TypeError as exc:
        raise InputError(f"task '{path}': {exc}") from None
    if task.trials < 1:
        raise InputError(f"task '{path}': trials must be at least 1")
    return task
