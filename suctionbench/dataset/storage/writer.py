"""Writing shards: `DatasetWriter`, the one place that creates a shard's files and its manifest.

Kept apart from the reader because writing is where atomicity lives (every file under a temporary
name, the old manifest retired before any file changes, the new manifest renamed into place last),
and from the card because the card is written once per run while shards are written by many
processes at once.
"""

from __future__ import annotations

import contextlib
import hashlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.dataset.storage.card import write_card
from suctionbench.dataset.storage.format import (
    DEFAULT_DATAPOINTS_PER_SHARD,
    FIELDS,
    MANIFEST_FORMAT,
    TENSOR_DIR,
    _check_index,
    _coerce_field,
    _existing_shard_size,
    _json_bytes,
    _npz_bytes,
    _write_bytes,
    manifest_name,
    shard_file_name,
)
from suctionbench.errors import InputError
from suctionbench.io import atomic_path

# -- writer ----------------------------------------------------------------------------------------


class DatasetWriter:
    """Writes shards of a dataset directory; each `write_shard` is all-or-nothing.

    Shards may be written in any order and by several processes at once (one process per shard
    index), which is what parallel generation and resuming need; rewriting a shard replaces it.
    """

    def __init__(self, directory: str | Path, datapoints_per_shard: int = DEFAULT_DATAPOINTS_PER_SHARD):
        if isinstance(datapoints_per_shard, bool) or not isinstance(datapoints_per_shard, int | np.integer) \
                or datapoints_per_shard < 1:
            raise InputError(f"datapoints_per_shard {datapoints_per_shard!r}: must be a positive integer")
        self.directory = Path(directory)
        self.datapoints_per_shard = int(datapoints_per_shard)
        self.tensor_dir = self.directory / TENSOR_DIR
        # Shards of different sizes would break the index arithmetic i * datapoints_per_shard + j.
        existing = _existing_shard_size(self.tensor_dir)
        if existing is not None and existing != self.datapoints_per_shard:
            raise InputError(f"dataset '{self.directory}': holds shards of {existing} datapoints, "
                             f"cannot add shards of {self.datapoints_per_shard}")

    def write_shard(self, index: int, fields: Mapping[str, np.ndarray]) -> dict[str, Any]:
        """Validate and write all files of shard `index`, manifest last; returns the manifest.

        `fields` must hold every name in `FIELDS`, each with 1 to ``datapoints_per_shard``
        datapoints, all of the same length. Nothing is written when validation fails; when
        writing fails (disk full, interrupt) no file of the new shard and no temporary file is
        left, and if encoding fails before the first rename an older complete shard at the same
        index stays intact.
        """
        index = _check_index(index)
        arrays = self._validate(index, fields)
        n = len(arrays[next(iter(FIELDS))])
        names = [shard_file_name(name, index) for name in FIELDS]
        self._remove_stale_temps(index)
        manifest_path = self.tensor_dir / manifest_name(index)
        committing = False
        try:
            files: dict[str, dict[str, Any]] = {}
            with contextlib.ExitStack() as stack:
                # All temporary files first: a failure here leaves an older shard at this index intact ...
                for file_name, arr in zip(names, arrays.values(), strict=True):
                    data = _npz_bytes(arr)
                    files[file_name] = {"sha256": hashlib.sha256(data).hexdigest(), "bytes": len(data)}
                    tmp = stack.enter_context(atomic_path(self.tensor_dir / file_name))
                    tmp.write_bytes(data)
                    del data
                # ... then retire the old manifest before any file of the shard changes; leaving the
                # stack renames every temporary file over its final name (or deletes them all on error).
                committing = True
                manifest_path.unlink(missing_ok=True)
            manifest = {
                "format": MANIFEST_FORMAT, "shard": index, "num_datapoints": n,
                "datapoints_per_shard": self.datapoints_per_shard, "files": files,
            }
            _write_bytes(manifest_path, _json_bytes(manifest, f"manifest of shard {index}"))
        except BaseException:
            if committing:  # no manifest made it: remove the shard's data files, so no partial shard lingers
                for file_name in names:
                    (self.tensor_dir / file_name).unlink(missing_ok=True)
            raise
        return manifest

    def write_card(self, card: Mapping[str, Any]) -> None:
        """`write_card` with this writer's shard size recorded (``datapoints_per_file``)."""
        write_card(self.directory, card, datapoints_per_shard=self.datapoints_per_shard)

    def _validate(self, index: int, fields: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
        if not isinstance(fields, Mapping):
            raise InputError(f"shard {index}: fields must be a mapping of name -> array, got {type(fields).__name__}")
        missing = [name for name in FIELDS if name not in fields]
        unknown = sorted(str(name) for name in fields if name not in FIELDS)
        if missing or unknown:
            parts = ([f"missing {missing}"] if missing else []) + ([f"unknown {unknown}"] if unknown else [])
            raise InputError(f"shard {index}: fields {'; '.join(parts)} (expected {list(FIELDS)})")
        arrays = {name: _coerce_field(name, fields[name], index) for name in FIELDS}
        lengths = {name: len(arr) for name, arr in arrays.items()}
        if len(set(lengths.values())) != 1:
            raise InputError(f"shard {index}: fields have different lengths {lengths}")
        n = next(iter(lengths.values()))
        if not 1 <= n <= self.datapoints_per_shard:
            raise InputError(f"shard {index}: {n} datapoints, expected 1 to {self.datapoints_per_shard}")
        return arrays

    def _remove_stale_temps(self, index: int) -> None:
        """Delete temporary files of this shard left by a killed process (atomic_path cleans up otherwise)."""
        if not self.tensor_dir.is_dir():
            return
        for final in [shard_file_name(name, index) for name in FIELDS] + [manifest_name(index)]:
            for tmp in self.tensor_dir.glob(f".{final}.*.tmp"):
                tmp.unlink(missing_ok=True)
