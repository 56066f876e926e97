"""Which object directories suctionbench may replace: only those it wrote (an object.toml with an
object record's identity, mesh.stl, parts/part_NNN.stl), so that building an object never deletes
a user's files. `build_object` asks before it replaces a directory; `objects build` and
`objects import --overwrite` ask for all their targets before any work."""

from __future__ import annotations

import re
import tomllib
from collections.abc import Iterable
from pathlib import Path

from suctionbench.errors import InputError

_PART_RE = re.compile(r"part_\d{3,}\.stl")


def foreign_object_entry(directory: Path) -> str | None:
    """Why `directory`, which building an object there would replace, may hold something
    suctionbench did not write; None if it is absent, empty, or an object as suctionbench writes it:
    an object.toml with an object record's identity (name, generator, geometry hash; any version of
    the record, so a rebuild after the record changed still replaces it), mesh.stl, and
    parts/part_NNN.stl (replacing it loses nothing)."""
    directory = Path(directory)
    if not directory.exists() and not directory.is_symlink():
        return None
    if directory.is_symlink() or not directory.is_dir():
        return "is not a directory"
    if not any(directory.iterdir()):
        return None
    try:
        record = tomllib.loads((directory / "object.toml").read_text())
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        record = None
    if not isinstance(record, dict) or not {"name", "generator", "geometry_hash"} <= set(record):
        return "holds no object.toml of suctionbench"
    for entry in sorted(directory.iterdir()):
        stray = entry
        if entry.name == "parts" and entry.is_dir() and not entry.is_symlink():
            stray = next((p for p in sorted(entry.iterdir())
                          if p.is_symlink() or not p.is_file() or not _PART_RE.fullmatch(p.name)), None)
        elif entry.name in ("object.toml", "mesh.stl") and entry.is_file() and not entry.is_symlink():
            stray = None
        if stray is not None:
            return f"holds '{stray.relative_to(directory)}', which suctionbench did not write"
    return None


def check_replaceable_objects(directories: Iterable[Path]) -> None:
    """InputError naming the first of `directories` that may hold something suctionbench did not write."""
    for directory in directories:
        reason = foreign_object_entry(directory)
        if reason is not None:
            raise InputError(f"object directory '{directory}': {reason}; nothing replaced (move it away or "
                             "choose another --out / --root)")
