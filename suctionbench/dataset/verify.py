"""Whole-dataset checks on top of `suctionbench.dataset.storage`: is a directory a complete,
uncorrupted dataset (`verify_dataset`, `check_dataset`), and is it one that suctionbench wrote, so
that `--overwrite` may remove it (`remove_dataset`)?

`storage` checks one shard at a time against its manifest; here the card says how many
datapoints the dataset must hold, every shard is hashed, decoded and checked for shape and
finite values in range (a manifest rewritten to match NaN labels passes the hashes, not this),
and the splits must index those datapoints.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from suctionbench.dataset.storage import (
    _DATA_RE,
    _MANIFEST_RE,
    CARD_NAME,
    FIELDS,
    SPLIT_DIR,
    SPLIT_KINDS,
    SPLIT_PARTS,
    TENSOR_DIR,
    DatasetReader,
    dexnet_compatible,
    is_field_config,
    read_card,
)
from suctionbench.errors import InputError
from suctionbench.io import atomic_path

UNIT_DIR = "units"
"""Per-object work units of a generation run (suctionbench.dataset.generate)."""

_UNIT_RE = re.compile(r"^unit_\d{5}\.npz$")
_TEMP_RE = re.compile(r"^\..+\.tmp$")  # suctionbench.io.atomic_path's temporary files

VERIFIED_NAME = "verified.json"
"""A dataset's record that `check_dataset` passed, with the size and modification time of every
file it read: while they are unchanged a later check trusts it (a training run then still
hash-checks each shard it reads, `DatasetReader`), so a 2.8 M-datapoint dataset is not read in
full once more before every run."""

LABEL_FIELD = "robust_suction_wrench_resistance"
LABEL_RANGE = (0.0, 1.0)
"""A robust wrench resistance is a probability."""


def _owned_names(parent: str) -> re.Pattern[str] | set[str]:
    if parent == TENSOR_DIR:
        return re.compile(f"(?:{_DATA_RE.pattern})|(?:{_MANIFEST_RE.pattern})")
    if parent == UNIT_DIR:
        return _UNIT_RE
    return {f"{part}_indices.npz" for part in SPLIT_PARTS} | {"metadata.json"}


def foreign_entries(directory: str | Path) -> list[Path]:
    """Entries of `directory` that are not part of a suctionbench dataset's layout (user files)."""
    directory = Path(directory)
    layout = {CARD_NAME, TENSOR_DIR, SPLIT_DIR, UNIT_DIR, VERIFIED_NAME}
    foreign: list[Path] = []

    def scan(folder: Path, allowed: re.Pattern[str] | set[str]) -> None:
        for entry in sorted(folder.iterdir()):
            ok = entry.is_file() and not entry.is_symlink() and (
                _TEMP_RE.match(entry.name) is not None
                or (allowed.match(entry.name) is not None if isinstance(allowed, re.Pattern)
                    else entry.name in allowed))
            if not ok:
                foreign.append(entry)

    for entry in sorted(directory.iterdir()):
        if entry.name not in layout or entry.is_symlink():
            foreign.append(entry)
        elif entry.name in (CARD_NAME, VERIFIED_NAME):
            if not entry.is_file():
                foreign.append(entry)
        elif not entry.is_dir():
            foreign.append(entry)
        elif entry.name == SPLIT_DIR:
            for kind in sorted(entry.iterdir()):
                if kind.name in SPLIT_KINDS and kind.is_dir() and not kind.is_symlink():
                    scan(kind, _owned_names(SPLIT_DIR))
                else:
                    foreign.append(kind)
        else:
            scan(entry, _owned_names(entry.name))
    return foreign


def remove_dataset(directory: str | Path) -> None:
    """Delete a dataset directory that suctionbench wrote (for ``generate --overwrite``).

    Proof of ownership: a dataset card with the storage schema (every card `write_card` writes has
    it), and nothing in the directory outside the dataset layout. Otherwise nothing is deleted and
    InputError names what is in the way: --overwrite never removes a user's files.
    """
    directory = Path(directory)
    if not directory.exists():
        return
    if not directory.is_dir() or directory.is_symlink():
        raise InputError(f"--overwrite '{directory}': not a dataset directory (a file or link); not removed")
    entries = list(directory.iterdir())
    if not entries:
        return
    try:
        card = read_card(directory)
    except InputError:
        card = None
    if card is None or not is_field_config(card.get("fields")):
        raise InputError(f"--overwrite '{directory}': holds no suctionbench dataset card ({CARD_NAME}), so it was "
                         "not written by suctionbench; nothing removed (choose another --out)")
    foreign = foreign_entries(directory)
    if foreign:
        more = f" and {len(foreign) - 1} more" if len(foreign) > 1 else ""
        raise InputError(f"--overwrite '{directory}': holds '{foreign[0].relative_to(directory)}'{more}, which "
                         "suctionbench did not write; nothing removed (move it away or choose another --out)")
    for sub in (TENSOR_DIR, UNIT_DIR, SPLIT_DIR):
        folder = directory / sub
        if not folder.is_dir():
            continue
        for path in sorted(folder.rglob("*"), key=lambda p: len(p.parts), reverse=True):
            path.rmdir() if path.is_dir() else path.unlink()
        folder.rmdir()
    (directory / VERIFIED_NAME).unlink(missing_ok=True)
    (directory / CARD_NAME).unlink(missing_ok=True)


def verify_dataset(directory: str | Path) -> list[str]:
    """One line per problem that makes `directory` unfit to train on; [] for a complete, sound dataset.

    The card must be a suctionbench card with its datapoint count and, if it has a status, be
    'complete'; every shard the count implies must be present and match its manifest (sizes,
    sha256); every array must have its field's shape and dtype, hold finite values and labels in
    [0, 1]; the splits must index exactly those datapoints. Reads every byte once per shard.
    """
    directory = Path(directory)
    if not directory.is_dir():
        reason = " (not found)" if not directory.exists() else ""
        return [f"dataset '{directory}': not a directory{reason}"]
    try:
        card = read_card(directory)
    except InputError as exc:
        return [str(exc)]
    problems: list[str] = []
    card_path = directory / CARD_NAME
    if not is_field_config(card.get("fields")):
        problems.append(f"dataset card '{card_path}': no storage schema ('fields'): not a suctionbench dataset card")
    expected = card.get("datapoints")
    if isinstance(expected, bool) or not isinstance(expected, int) or expected < 1:
        problems.append(f"dataset card '{card_path}': 'datapoints' is {expected!r}, expected a positive count")
        expected = None
    status = card.get("status", "complete")
    if status != "complete":
        problems.append(f"dataset card '{card_path}': status '{status}' (generation did not finish: "
                        "rerun generate with --resume)")
    if not (directory / TENSOR_DIR).is_dir():
        return problems + [f"dataset '{directory}': no {TENSOR_DIR}/ directory"]
    reader = DatasetReader(directory)
    shard_problems = reader.verify(expected)
    problems += shard_problems
    problems += [p for p in dexnet_compatible(directory) if p not in problems and "config.json" not in p]
    if shard_problems:
        return problems  # values of damaged shards are not worth decoding
    for index in reader.shard_indices:
        arrays = reader.shard(index, verify=False)  # hashes were checked by verify()
        for name, arr in arrays.items():
            if FIELDS[name].dtype.kind == "f" and not np.isfinite(arr).all():
                bad = int((~np.isfinite(arr)).sum())
                problems.append(f"shard {index} field '{name}': {bad} NaN or infinite values")
        labels = arrays[LABEL_FIELD]
        finite = labels[np.isfinite(labels)]
        if finite.size and (finite.min() < LABEL_RANGE[0] or finite.max() > LABEL_RANGE[1]):
            problems.append(f"shard {index} field '{LABEL_FIELD}': values in [{finite.min():g}, {finite.max():g}] "
                            f"outside {list(LABEL_RANGE)}")
    for kind in SPLIT_KINDS:
        if not (directory / SPLIT_DIR / kind).is_dir():
            problems.append(f"dataset '{directory}': split '{kind}' missing ({SPLIT_DIR}/{kind}/)")
    return problems


def check_dataset(directory: str | Path) -> dict[str, list[int]] | None:
    """InputError with the first problem (and how many there are) if `directory` fails `verify_dataset`.

    A pass that `record_check` recorded (`VERIFIED_NAME`) stands in for the full read while no file
    of the card, shards and splits has changed size or modification time (nor been added or
    removed). Returns what `record_check` records after the command succeeds (the files' state when
    they were read), or None when the record was trusted or the state could not be read.
    """
    directory = Path(directory)
    state = _file_state(directory)
    try:
        if state is not None and json.loads((directory / VERIFIED_NAME).read_text()) == state:
            return None
    except (OSError, ValueError):
        pass
    problems = verify_dataset(directory)
    if problems:
        more = f" (and {len(problems) - 1} more problems)" if len(problems) > 1 else ""
        first = problems[0] if str(directory) in problems[0] else f"dataset '{directory}': {problems[0]}"
        raise InputError(first + more)
    return state


def record_check(directory: str | Path, state: dict[str, list[int]] | None) -> None:
    """Record `check_dataset`'s pass in the dataset, once the command that checked it succeeded (a
    refused command writes nothing): only if no file changed since it was read, and silently not
    on a read-only dataset (which is then checked in full every time)."""
    directory = Path(directory)
    if state is None or state != _file_state(directory):
        return
    try:
        with atomic_path(directory / VERIFIED_NAME) as tmp:
            tmp.write_text(json.dumps(state))
    except OSError:
        pass


def _file_state(directory: Path) -> dict[str, list[int]] | None:
    """Size and modification time (ns) of the card and every file under the shards and splits,
    by relative path; None if the directory cannot be listed."""
    try:
        paths = [directory / CARD_NAME] + sorted(p for sub in (TENSOR_DIR, SPLIT_DIR)
                                                 for p in (directory / sub).rglob("*") if p.is_file())
        stats = {str(p.relative_to(directory)): p.stat() for p in paths}
    except OSError:
        return None
    return {name: [st.st_size, st.st_mtime_ns] for name, st in stats.items()}
