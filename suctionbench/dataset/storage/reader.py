"""Reading and checking shards: `DatasetReader`, which trusts a shard only through its manifest.

Reading is separate from writing because its job is the opposite one: to find what a killed,
interrupted or corrupted write left behind (missing files, wrong hashes, mis-sized shards) and
report it, which is what `verify`, resuming a generation run and the trainers rely on.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.dataset.storage.card import read_card
from suctionbench.dataset.storage.format import (
    _DATA_RE,
    _MANIFEST_RE,
    DEFAULT_DATAPOINTS_PER_SHARD,
    FIELDS,
    LATER_FIELDS,
    MANIFEST_FORMAT,
    TENSOR_DIR,
    _load_npz,
    _read_file,
    manifest_name,
    shard_file_name,
)
from suctionbench.errors import InputError
from suctionbench.io import file_digest

# -- reader ----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Problem:
    shard: int | None
    message: str


class DatasetReader:
    """Reads a dataset directory shard by shard, verifying file hashes against the manifests.

    Only shards with a readable manifest are listed; `verify` (and `bad_shards`) report what is
    missing, incomplete or corrupt, which is what resuming a generation run needs.
    """

    def __init__(self, directory: str | Path):
        self.directory = Path(directory)
        if not self.directory.is_dir():
            raise InputError(f"dataset '{self.directory}': not a directory")
        self.tensor_dir = self.directory / TENSOR_DIR
        self._manifests: dict[int, dict[str, Any]] = {}
        self._bad_manifests: dict[int, str] = {}
        if self.tensor_dir.is_dir():
            for path in sorted(self.tensor_dir.iterdir()):
                m = _MANIFEST_RE.match(path.name)
                if m:
                    index = int(m.group(1))
                    try:
                        self._manifests[index] = self._parse_manifest(path, index)
                    except InputError as exc:
                        self._bad_manifests[index] = str(exc)
        self.datapoints_per_shard = self._shard_size()

    @property
    def shard_indices(self) -> list[int]:
        """Indices of the shards with a valid manifest, ascending."""
        return sorted(self._manifests)

    @property
    def num_shards(self) -> int:
        return len(self._manifests)

    @property
    def num_datapoints(self) -> int:
        """Datapoints in the listed shards (from the manifests, without reading data)."""
        return sum(m["num_datapoints"] for m in self._manifests.values())

    def shard_size(self, index: int) -> int:
        """Datapoints in shard `index` (from its manifest)."""
        return self._manifest(index)["num_datapoints"]

    def has_field(self, name: str, shards: Sequence[int] | None = None) -> bool:
        """Whether every listed shard (or every one of `shards`) stores field `name`, by its manifest:
        False for a `LATER_FIELDS` field in a dataset (or shard) written before the field existed."""
        indices = self.shard_indices if shards is None else shards
        return all(shard_file_name(name, i) in self._manifest(i)["files"] for i in indices)

    def shard(self, index: int, *, verify: bool = True, fields: Sequence[str] | None = None) -> dict[str, np.ndarray]:
        """The arrays of shard `index` (all the fields it stores, or only `fields`), checked against
        the manifest.

        With ``verify=True`` each file's sha256 must match the manifest; either way a missing or
        unreadable file, or an array of the wrong shape or dtype, raises InputError naming the file.
        Each file is read once: the same bytes are hashed and decoded.
        """
        manifest = self._manifest(index)
        stored = [name for name in FIELDS if shard_file_name(name, index) in manifest["files"]]
        names = stored if fields is None else list(fields)
        unknown = [name for name in names if name not in FIELDS]
        if unknown:
            raise InputError(f"fields {unknown}: unknown (known: {list(FIELDS)})")
        n = manifest["num_datapoints"]
        out: dict[str, np.ndarray] = {}
        for name in names:
            file_name = shard_file_name(name, index)
            if file_name not in manifest["files"]:  # only a LATER_FIELDS field can be absent
                raise InputError(f"dataset '{self.directory}': shard {index} has no field '{name}' (written "
                                 "before suctionbench stored it; regenerate the dataset to add it)")
            path = self.tensor_dir / file_name
            data = _read_file(path, "shard file", f"shard {index} is incomplete")
            if verify:
                expected = manifest["files"][file_name]
                if len(data) != expected["bytes"] or hashlib.sha256(data).hexdigest() != expected["sha256"]:
                    raise InputError(f"shard file '{path}': sha256 does not match the manifest (corrupt or modified)")
            arr = _load_npz(data, path)
            del data
            spec = FIELDS[name]
            if arr.shape != (n, *spec.shape) or arr.dtype != spec.dtype:
                want = f"{spec.dtype}{(n, *spec.shape)}"
                raise InputError(f"shard file '{path}': {arr.dtype}{arr.shape}, expected {want}")
            out[name] = arr
        return out

    def iter_shards(self, *, verify: bool = True, fields: Sequence[str] | None = None
                    ) -> Iterator[tuple[int, dict[str, np.ndarray]]]:
        """Yield ``(index, arrays)`` for every listed shard in index order, one shard in memory at a time."""
        for index in self.shard_indices:
            yield index, self.shard(index, verify=verify, fields=fields)

    def field(self, name: str, *, verify: bool = True) -> np.ndarray:
        """One field of the whole dataset, concatenated in datapoint order (small datasets and tests).

        Requires a complete, gap-free dataset, since otherwise position in the result would not be
        the global datapoint index that splits refer to. Reads only this field's files.
        """
        if name not in FIELDS:
            raise InputError(f"field '{name}': unknown (known: {list(FIELDS)})")
        self._require_contiguous()
        spec = FIELDS[name]
        parts = [arrays[name] for _, arrays in self.iter_shards(verify=verify, fields=[name])]
        return np.concatenate(parts) if parts else np.zeros((0, *spec.shape), spec.dtype)

    def verify(self, expected_datapoints: int | None = None) -> list[str]:
        """One line per problem: missing, incomplete, corrupt or mis-sized shards; [] if all is well.

        Hashes every file (streamed, one file at a time). With `expected_datapoints`, shards the
        full dataset should have but lacks are reported too, and so are shards beyond it.
        """
        return [p.message for p in self._problems(expected_datapoints)]

    def bad_shards(self, expected_datapoints: int | None = None) -> list[int]:
        """Indices of shards that must be (re)written for the dataset to be complete, ascending.

        Shards beyond `expected_datapoints` are reported by `verify` but not listed here: they
        need deleting, not writing.
        """
        problems = self._problems(expected_datapoints)
        limit = None if expected_datapoints is None else math.ceil(expected_datapoints / self._size_or_default())
        bad = {p.shard for p in problems if p.shard is not None}
        return sorted(i for i in bad if limit is None or i < limit)

    # -- internals --

    def _parse_manifest(self, path: Path, index: int) -> dict[str, Any]:
        try:
            manifest = json.loads(path.read_text())
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise InputError(f"shard {index}: manifest '{path}' unreadable ({type(exc).__name__})") from None
        expected_files = {shard_file_name(name, index) for name in FIELDS}
        required_files = expected_files - {shard_file_name(name, index) for name in LATER_FIELDS}
        ok = (
            isinstance(manifest, dict) and manifest.get("format") == MANIFEST_FORMAT
            and manifest.get("shard") == index
            and isinstance(manifest.get("num_datapoints"), int) and manifest["num_datapoints"] >= 1
            and isinstance(manifest.get("datapoints_per_shard"), int)
            and manifest["num_datapoints"] <= manifest["datapoints_per_shard"]
            and isinstance(manifest.get("files"), dict)
            and required_files <= set(manifest["files"]) <= expected_files
            and all(isinstance(f, dict) and isinstance(f.get("sha256"), str) and isinstance(f.get("bytes"), int)
                    for f in manifest["files"].values())
        )
        if not ok:
            raise InputError(f"shard {index}: manifest '{path}' malformed (not a {MANIFEST_FORMAT} manifest "
                             "for this shard)")
        return manifest

    def _shard_size(self) -> int | None:
        """The dataset's shard size: the card's ``datapoints_per_file`` if set, else the first manifest's."""
        with contextlib.suppress(InputError):
            size = read_card(self.directory).get("datapoints_per_file")
            if isinstance(size, int) and size >= 1:
                return size
        for index in self.shard_indices:
            return self._manifests[index]["datapoints_per_shard"]
        return None

    def _manifest(self, index: int) -> dict[str, Any]:
        if index in self._bad_manifests:
            raise InputError(self._bad_manifests[index])
        if index not in self._manifests:
            path = self.tensor_dir / manifest_name(index)
            raise InputError(f"shard {index}: no manifest '{path}' (shard missing or incomplete)")
        return self._manifests[index]

    def _require_contiguous(self) -> None:
        indices = self.shard_indices
        if self._bad_manifests or indices != list(range(len(indices))):
            raise InputError(f"dataset '{self.directory}': shards missing or incomplete (run verify)")
        for i in indices[:-1]:
            if self._manifests[i]["num_datapoints"] != self.datapoints_per_shard:
                raise InputError(f"dataset '{self.directory}': shard {i} is partial but not the last (run verify)")

    def _size_or_default(self) -> int:
        """Shard size for planning before any shard or card records one (Dex-Net's 1000)."""
        return self.datapoints_per_shard or DEFAULT_DATAPOINTS_PER_SHARD

    def _problems(self, expected_datapoints: int | None) -> list[_Problem]:
        dps = self._size_or_default()
        problems: list[_Problem] = []
        on_disk: dict[int, set[str]] = {}
        if self.tensor_dir.is_dir():
            for path in self.tensor_dir.iterdir():
                m = _DATA_RE.match(path.name)
                if m:
                    on_disk.setdefault(int(m.group(2)), set()).add(path.name)

        present = set(self._manifests) | set(self._bad_manifests) | set(on_disk)
        if expected_datapoints is not None:
            if isinstance(expected_datapoints, bool) or not isinstance(expected_datapoints, int) \
                    or expected_datapoints < 0:
                raise InputError(f"expected_datapoints {expected_datapoints!r}: must be a non-negative integer")
            num_expected = math.ceil(expected_datapoints / dps)
        else:
            num_expected = max(present) + 1 if present else 0

        for index in range(max(num_expected, max(present) + 1 if present else 0)):
            prefix = f"shard {index}"
            if index >= num_expected:
                if index in present:
                    problems.append(_Problem(index, f"{prefix}: beyond the expected {expected_datapoints} "
                                                    "datapoints"))
                continue
            if index in self._bad_manifests:
                problems.append(_Problem(index, self._bad_manifests[index]))
                continue
            if index not in self._manifests:
                what = "data files without a manifest (interrupted write)" if index in on_disk else "missing"
                problems.append(_Problem(index, f"{prefix}: {what}"))
                continue
            manifest = self._manifests[index]
            for file_name, expected in sorted(manifest["files"].items()):
                path = self.tensor_dir / file_name
                try:
                    digest, size = file_digest(path)
                except FileNotFoundError:
                    problems.append(_Problem(index, f"{prefix}: file '{path}' missing"))
                    continue
                except OSError as exc:
                    problems.append(_Problem(index, f"{prefix}: file '{path}' unreadable ({exc.strerror})"))
                    continue
                if size != expected["bytes"]:
                    problems.append(_Problem(index, f"{prefix}: file '{path}' has {size} bytes, manifest says "
                                                    f"{expected['bytes']} (truncated or modified)"))
                elif digest != expected["sha256"]:
                    problems.append(_Problem(index, f"{prefix}: file '{path}' sha256 does not match the manifest "
                                                    "(corrupt or modified)"))
            n = manifest["num_datapoints"]
            if manifest["datapoints_per_shard"] != dps:
                problems.append(_Problem(index, f"{prefix}: written with {manifest['datapoints_per_shard']} "
                                                f"datapoints per shard, the dataset uses {dps}"))
            elif expected_datapoints is not None:
                want = min(dps, expected_datapoints - index * dps)
                if n != want:
                    problems.append(_Problem(index, f"{prefix}: {n} datapoints, expected {want}"))
            elif index < num_expected - 1 and n != dps:
                problems.append(_Problem(index, f"{prefix}: {n} datapoints, but only the last shard may hold "
                                                f"fewer than {dps}"))
        return problems
