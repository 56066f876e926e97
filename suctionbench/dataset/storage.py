"""Dataset storage in the Dex-Net 3.0 tensor layout, readable by the original gqcnn trainer.

Layout of a dataset directory ``DIR``::

    DIR/config.json                                   dataset card (+ the keys gqcnn's TensorDataset reads)
    DIR/tensors/depth_ims_tf_table_XXXXX.npz          float32 (n, 32, 32, 1)  depth thumbnails
    DIR/tensors/context_ims_tf_table_XXXXX.npz        float32 (n, 32, 32, 1)  context thumbnails (3x the view)
    DIR/tensors/hand_poses_XXXXX.npz                  float32 (n, 7)          grasp pose vectors
    DIR/tensors/robust_suction_wrench_resistance_XXXXX.npz  float32 (n,)     robust label in [0, 1]
    DIR/tensors/object_labels_XXXXX.npz               int32 (n,)   index into the card's object list
    DIR/tensors/pose_labels_XXXXX.npz                 int32 (n,)   stable pose id
    DIR/tensors/image_labels_XXXXX.npz                int32 (n,)   global image id
    DIR/tensors/seal_flags_XXXXX.npz                  uint8 (n,)   nominal seal (0/1)
    DIR/tensors/wrench_resistance_XXXXX.npz           uint8 (n,)   nominal wrench resistance (0/1)
    DIR/tensors/shard_XXXXX.json                      shard manifest, written last
    DIR/splits/{image_wise,object_wise}/{train,val}_indices.npz, metadata.json

Every ``.npz`` holds one array under the key ``arr_0``; ``XXXXX`` is the zero-padded shard index
(gqcnn parses exactly five digits); each shard holds ``datapoints_per_shard`` datapoints (Dex-Net:
1000) except the last, which may be partial. Datapoint ``j`` of shard ``i`` has the global index
``i * datapoints_per_shard + j``, the index the split files refer to -- the same arithmetic as
``autolab_core.TensorDataset``, which is why only the last shard may be partial.

Why a manifest per shard
------------------------
A shard is several files, and no file system renames several files at once. Each file is written
under a temporary name and renamed, and the manifest ``shard_XXXXX.json`` -- the sha256 and size
of every file of the shard plus its datapoint count -- is renamed into place last. So a shard is
complete iff its manifest exists and the hashes match: an interrupted or crashed write, a
truncated copy or a flipped bit is found by `DatasetReader.verify` and the shard regenerated,
without trusting file modification times or sizes. gqcnn ignores the ``.json`` files.

Why the ``.npz`` files are written by hand
------------------------------------------
``np.savez_compressed`` stamps each zip entry with the current time, so the same arrays give
different bytes (and hashes) on every run. `_npz_bytes` writes the same zip layout (one deflated
``arr_0.npy`` entry, readable by ``np.load``) with a fixed timestamp: same data, same bytes, same
manifest -- generation is reproducible down to the file hashes.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import math
import re
import zipfile
import zlib
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.errors import InputError
from suctionbench.io import atomic_path, file_digest
from suctionbench.sensing.object_context import OBJECT_CONTEXT_COLUMNS


@dataclass(frozen=True)
class FieldSpec:
    """Storage type of one per-datapoint field."""

    dtype: np.dtype
    """Dtype on disk; inputs of the same kind (float, integer) are converted to it."""

    shape: tuple[int, ...]
    """Shape of one datapoint (the stored array is (n, *shape))."""

    description: str
    """What the field holds (documentation, and the card's field list)."""

    binary: bool = False
    """Only 0 and 1 are valid values (flags)."""


THUMBNAIL_SHAPE = (32, 32, 1)
"""Height, width, channels of a depth thumbnail (GQ-CNN 3.0 input)."""

HAND_POSE_COLUMNS = (
    "pixel_row", "pixel_column", "gripper_depth", "approach_angle", "approach_x", "approach_y", "approach_z",
)
"""Columns of ``hand_poses``: grasp pixel (row, column) in the full image, gripper depth (m), angle
between the approach and the table normal (rad), approach direction in the camera frame. gqcnn's
suction network reads columns 2 and 3."""

FIELDS: dict[str, FieldSpec] = {
    "depth_ims_tf_table": FieldSpec(np.dtype(np.float32), THUMBNAIL_SHAPE, "depth thumbnail (m), grasp-centred"),
    "context_ims_tf_table": FieldSpec(np.dtype(np.float32), THUMBNAIL_SHAPE,
                                      "context thumbnail (m): 3x the crop around the grasp, block-averaged"),
    "hand_poses": FieldSpec(np.dtype(np.float32), (len(HAND_POSE_COLUMNS),), "pose vector: " +
                            ", ".join(HAND_POSE_COLUMNS)),
    "object_context": FieldSpec(np.dtype(np.float32), (len(OBJECT_CONTEXT_COLUMNS),),
                                "where the grasp lies on the visible object (m): " + ", ".join(OBJECT_CONTEXT_COLUMNS)),
    "robust_suction_wrench_resistance": FieldSpec(np.dtype(np.float32), (), "robust wrench resistance in [0, 1]"),
    "object_labels": FieldSpec(np.dtype(np.int32), (), "index into the card's object list"),
    "pose_labels": FieldSpec(np.dtype(np.int32), (), "stable pose id"),
    "image_labels": FieldSpec(np.dtype(np.int32), (), "global image id"),
    "grasp_labels": FieldSpec(np.dtype(np.int32), (), "index of the grasp candidate within its object"),
    "seal_flags": FieldSpec(np.dtype(np.uint8), (), "nominal seal formed (0/1)", binary=True),
    "wrench_resistance": FieldSpec(np.dtype(np.uint8), (), "nominal wrench resistance (0/1)", binary=True),
}
"""Every field of a shard, in storage order. All are required in every shard `DatasetWriter` writes."""

LATER_FIELDS = ("context_ims_tf_table", "object_context")
"""Fields added after the first datasets were written. A shard written before one existed has no
file for it and its manifest does not list it. Such a shard is intact, not damaged: `verify`
accepts it and readers read its other fields; `shard` raises InputError naming the field only
when asked for it, and `has_field` tells in advance (the context GQ-CNNs need the field)."""

GQCNN_FIELDS = ("depth_ims_tf_table", "hand_poses", "robust_suction_wrench_resistance")
"""The fields the original gqcnn trainer reads (image, pose, metric)."""

DEFAULT_DATAPOINTS_PER_SHARD = 1000
"""Dex-Net's datapoints per tensor file."""

MAX_SHARDS = 100_000
"""gqcnn parses the shard index from exactly five digits."""

SPLIT_KINDS = {"image_wise": "image_labels", "object_wise": "object_labels"}
"""Split name -> the field whose values group datapoints (all of a group go to one side)."""

SPLIT_PARTS = ("train", "val")

CARD_NAME = "config.json"
TENSOR_DIR = "tensors"
SPLIT_DIR = "splits"
NPZ_KEY = "arr_0"
MANIFEST_FORMAT = "suctionbench-shard-1"

_NPZ_ENTRY = NPZ_KEY + ".npy"
_ZIP_EPOCH = (1980, 1, 1, 0, 0, 0)
_MANIFEST_RE = re.compile(r"^shard_(\d{5})\.json$")
_DATA_RE = re.compile(r"^(" + "|".join(FIELDS) + r")_(\d{5})\.npz$")


def shard_file_name(field: str, index: int) -> str:
    """File name of one field of one shard (``hand_poses_00003.npz``)."""
    return f"{field}_{index:05d}.npz"


def manifest_name(index: int) -> str:
    """File name of a shard's manifest (``shard_00003.json``)."""
    return f"shard_{index:05d}.json"


def gqcnn_field_config() -> dict[str, dict[str, Any]]:
    """The card's ``fields`` entry in ``autolab_core.TensorDataset`` form (dtype, height, width, channels)."""
    out: dict[str, dict[str, Any]] = {}
    for name, spec in FIELDS.items():
        entry: dict[str, Any] = {"dtype": spec.dtype.name}
        entry.update(zip(("height", "width", "channels"), spec.shape, strict=False))
        out[name] = entry
    return out


def is_field_config(fields: Any) -> bool:
    """Whether a card's ``fields`` entry is the storage schema `gqcnn_field_config`, or that schema
    without some `LATER_FIELDS` (the card of a dataset written before they existed)."""
    schema = gqcnn_field_config()
    if not isinstance(fields, dict) or not set(schema) - set(LATER_FIELDS) <= set(fields) <= set(schema):
        return False
    return all(fields[name] == schema[name] for name in fields)


# -- low-level file helpers ------------------------------------------------------------------------


def _npz_bytes(array: np.ndarray) -> bytes:
    """An ``.npz`` holding `array` as ``arr_0``, byte-identical for identical arrays (fixed timestamp)."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED, allowZip64=True) as zf:
        info = zipfile.ZipInfo(_NPZ_ENTRY, date_time=_ZIP_EPOCH)
        info.compress_type = zipfile.ZIP_DEFLATED
        with zf.open(info, "w", force_zip64=True) as fh:
            np.lib.format.write_array(fh, np.ascontiguousarray(array), allow_pickle=False)
    return buf.getvalue()


def _json_bytes(obj: Any, what: str) -> bytes:
    """Strict JSON (no NaN / Infinity, which other readers reject), sorted keys: deterministic bytes."""
    try:
        return (json.dumps(obj, indent=2, sort_keys=True, allow_nan=False) + "\n").encode()
    except (TypeError, ValueError) as exc:
        raise InputError(f"{what}: not JSON-serialisable ({exc})") from None


def _write_bytes(path: Path, data: bytes) -> None:
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def _read_file(path: Path, what: str, missing: str) -> bytes:
    """A file's bytes, or an InputError naming it: `missing` explains an absent file."""
    try:
        return path.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{what} '{path}': missing ({missing})") from None
    except OSError as exc:
        raise InputError(f"{what} '{path}': cannot read ({exc.strerror})") from None


def _load_npz(data: bytes, path: Path) -> np.ndarray:
    """The ``arr_0`` array of an ``.npz`` held in memory; InputError naming `path` if it is unreadable."""
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as npz:
            if NPZ_KEY not in npz.files:
                raise InputError(f"shard file '{path}': no '{NPZ_KEY}' array (has {sorted(npz.files)})")
            return npz[NPZ_KEY]
    except InputError:
        raise
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile, zlib.error) as exc:
        raise InputError(f"shard file '{path}': corrupt ({type(exc).__name__}: {exc})") from None


def _npy_header(path: Path) -> tuple[tuple[int, ...], np.dtype]:
    """Shape and dtype of ``arr_0`` from its ``.npy`` header, decompressing only the header."""
    with zipfile.ZipFile(path) as zf:
        if _NPZ_ENTRY not in zf.namelist():
            raise KeyError(f"no '{NPZ_KEY}' array")
        with zf.open(_NPZ_ENTRY) as fh:
            version = np.lib.format.read_magic(fh)
            if version == (1, 0):
                shape, _, dtype = np.lib.format.read_array_header_1_0(fh)
            else:
                shape, _, dtype = np.lib.format.read_array_header_2_0(fh)
    return tuple(shape), np.dtype(dtype)


def _check_index(index: Any) -> int:
    if isinstance(index, bool) or not isinstance(index, int | np.integer) or not 0 <= int(index) < MAX_SHARDS:
        raise InputError(f"shard index {index!r}: must be an integer in [0, {MAX_SHARDS})")
    return int(index)


def _coerce_field(name: str, value: Any, index: int) -> np.ndarray:
    """`value` as the field's stored dtype and shape; InputError if it has the wrong kind, shape or values.

    Floats of any width become float32 and integers/bools of any width the stored integer type,
    but only when every value fits: a label that overflows int32 or a flag of 2 is a bug upstream,
    and silently wrapping it would corrupt the dataset.
    """
    spec = FIELDS[name]
    what = f"shard {index} field '{name}'"
    arr = np.asarray(value)
    if arr.ndim != 1 + len(spec.shape) or arr.shape[1:] != spec.shape:
        want = "(n, " + ", ".join(map(str, spec.shape)) + ")" if spec.shape else "(n,)"
        raise InputError(f"{what}: shape {arr.shape}, expected {want}")
    if spec.dtype.kind == "f":
        if arr.dtype.kind != "f":
            raise InputError(f"{what}: dtype {arr.dtype}, expected floating point ({spec.dtype})")
        out = arr.astype(spec.dtype, copy=False)
        if not np.isfinite(out).all():
            raise InputError(f"{what}: holds NaN or infinite values (after conversion to {spec.dtype})")
        return out
    if arr.dtype.kind not in "biu":
        raise InputError(f"{what}: dtype {arr.dtype}, expected integer ({spec.dtype})")
    if arr.size:
        lo, hi = (0, 1) if spec.binary else (np.iinfo(spec.dtype).min, np.iinfo(spec.dtype).max)
        amin, amax = int(arr.min()), int(arr.max())
        if amin < lo or amax > hi:
            raise InputError(f"{what}: values in [{amin}, {amax}] outside [{lo}, {hi}]")
    return arr.astype(spec.dtype, copy=False)


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


def _existing_shard_size(tensor_dir: Path) -> int | None:
    """``datapoints_per_shard`` of the first readable manifest in `tensor_dir`, or None."""
    if not tensor_dir.is_dir():
        return None
    for path in sorted(tensor_dir.glob("shard_*.json")):
        with contextlib.suppress(OSError, ValueError, TypeError, AttributeError):
            size = json.loads(path.read_text()).get("datapoints_per_shard")
            if isinstance(size, int) and size >= 1:
                return size
    return None


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


# -- dataset card ----------------------------------------------------------------------------------


def write_card(directory: str | Path, card: Mapping[str, Any], *, datapoints_per_shard: int | None = None) -> None:
    """Write the dataset card ``config.json`` atomically, adding the keys gqcnn's TensorDataset reads.

    The card is free-form JSON (generation config, camera, cup, objects, counts, seed, versions,
    positive rate, ...). ``fields`` (the storage schema) is always set, and ``datapoints_per_file``
    from, in order: `datapoints_per_shard`, the card itself, the shards already written; a card
    written before any shard exists may lack it, the final card then gets it from the shards.
    """
    path = Path(directory) / CARD_NAME
    if not isinstance(card, Mapping) or not all(isinstance(k, str) for k in card):
        raise InputError(f"dataset card '{path}': must be a mapping with string keys")
    out = dict(card)
    fields = gqcnn_field_config()
    if "fields" in out and out["fields"] != fields:
        raise InputError(f"dataset card '{path}': 'fields' differs from the storage schema (leave it out)")
    out["fields"] = fields
    size = datapoints_per_shard if datapoints_per_shard is not None else out.get("datapoints_per_file")
    if size is None:
        size = _existing_shard_size(Path(directory) / TENSOR_DIR)
    if size is not None:
        if isinstance(size, bool) or not isinstance(size, int) or size < 1:
            raise InputError(f"dataset card '{path}': datapoints_per_file {size!r} must be a positive integer")
        if out.get("datapoints_per_file", size) != size:
            raise InputError(f"dataset card '{path}': datapoints_per_file {out['datapoints_per_file']} "
                             f"contradicts the shard size {size}")
        out["datapoints_per_file"] = size
    _write_bytes(path, _json_bytes(out, f"dataset card '{path}'"))


def read_card(directory: str | Path) -> dict[str, Any]:
    """The dataset card; InputError if it is missing, not JSON, or not a JSON object."""
    path = Path(directory) / CARD_NAME
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise InputError(f"dataset card '{path}': missing (not a dataset directory?)") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"dataset card '{path}': unreadable ({exc})") from None
    try:
        card = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"dataset card '{path}': malformed JSON (line {exc.lineno}: {exc.msg})") from None
    if not isinstance(card, dict):
        raise InputError(f"dataset card '{path}': expected a JSON object, got {type(card).__name__}")
    return card


# -- splits ----------------------------------------------------------------------------------------


def _group_split(groups: np.ndarray, val_fraction: float, rng: np.random.Generator) -> np.ndarray:
    """Boolean val mask over datapoints such that every group lies wholly on one side.

    Groups are visited in a random order and each joins val if that brings the val count closer
    to the target; this lands within half of the smallest remaining group of the target when the
    groups are many and small (images), and does as well as one greedy pass can when they are few
    and large (objects). With two or more groups both sides get at least one, since a trainer
    cannot use an empty side.
    """
    ids, inverse, counts = np.unique(groups, return_inverse=True, return_counts=True)
    target = val_fraction * len(groups)
    in_val = np.zeros(len(ids), dtype=bool)
    total = 0
    sizes = counts.tolist()  # Python ints: the loop runs once per group (images can number millions)
    for g in rng.permutation(len(ids)).tolist():
        if abs(total + sizes[g] - target) < abs(total - target):
            in_val[g] = True
            total += sizes[g]
    if len(ids) >= 2:
        order = np.argsort(counts, kind="stable")
        if not in_val.any():
            in_val[order[0]] = True
        elif in_val.all():
            in_val[order[0]] = False
    return in_val[inverse]


def write_splits(
    directory: str | Path, image_ids: Any, object_ids: Any, val_fraction: float = 0.2, *,
    seed: int | np.random.Generator,
) -> dict[str, dict[str, np.ndarray]]:
    """Write image-wise and object-wise train/val splits of datapoint indices; returns them.

    ``image_ids[i]`` and ``object_ids[i]`` belong to global datapoint ``i``. Image-wise keeps all
    datapoints of an image on one side (val images are drawn at random from `seed`); object-wise
    does the same per object, so validation measures generalisation to unseen objects. Files:
    ``splits/<kind>/{train,val}_indices.npz`` (sorted int64, key ``arr_0``) and ``metadata.json``,
    the layout ``autolab_core.TensorDataset.split`` reads.
    """
    images = np.asarray(image_ids)
    objects = np.asarray(object_ids)
    for name, arr in (("image_ids", images), ("object_ids", objects)):
        if arr.ndim != 1 or arr.dtype.kind not in "iu":
            raise InputError(f"splits: {name} must be a 1-D integer array, got {arr.dtype}{arr.shape}")
    if len(images) != len(objects):
        raise InputError(f"splits: image_ids has {len(images)} entries but object_ids {len(objects)}")
    if len(images) == 0:
        raise InputError("splits: no datapoints to split")
    if not isinstance(val_fraction, int | float) or not 0.0 < val_fraction < 1.0:
        raise InputError(f"splits: val_fraction {val_fraction!r} must be in (0, 1)")
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    result: dict[str, dict[str, np.ndarray]] = {}
    for kind, groups in (("image_wise", images), ("object_wise", objects)):
        val = _group_split(groups, float(val_fraction), rng)
        parts = {"train": np.flatnonzero(~val).astype(np.int64), "val": np.flatnonzero(val).astype(np.int64)}
        split_dir = Path(directory) / SPLIT_DIR / kind
        for part, indices in parts.items():
            _write_bytes(split_dir / f"{part}_indices.npz", _npz_bytes(indices))
        metadata = {
            "field_name": SPLIT_KINDS[kind], "train_pct": 1.0 - float(val_fraction),
            "val_fraction_requested": float(val_fraction), "val_fraction": len(parts["val"]) / len(groups),
            "num_train": len(parts["train"]), "num_val": len(parts["val"]),
            "num_groups_train": len(np.unique(groups[~val])), "num_groups_val": len(np.unique(groups[val])),
            "seed": int(seed) if isinstance(seed, int | np.integer) else None,
        }
        _write_bytes(split_dir / "metadata.json", _json_bytes(metadata, f"split metadata '{split_dir}'"))
        result[kind] = parts
    return result


def read_split(directory: str | Path, kind: str, part: str) -> np.ndarray:
    """Datapoint indices of one side of a split (`kind` image_wise / object_wise, `part` train / val)."""
    if kind not in SPLIT_KINDS:
        raise InputError(f"split kind '{kind}': unknown (known: {list(SPLIT_KINDS)})")
    if part not in SPLIT_PARTS:
        raise InputError(f"split part '{part}': unknown (known: {list(SPLIT_PARTS)})")
    path = Path(directory) / SPLIT_DIR / kind / f"{part}_indices.npz"
    data = _read_file(path, "split file", "splits not written yet?")
    arr = _load_npz(data, path)
    if arr.ndim != 1 or arr.dtype.kind not in "iu":
        raise InputError(f"split file '{path}': expected 1-D integer indices, got {arr.dtype}{arr.shape}")
    return arr


# -- gqcnn compatibility ---------------------------------------------------------------------------


def dexnet_compatible(directory: str | Path) -> list[str]:
    """Problems that would stop the original gqcnn trainer (autolab_core TensorDataset) reading `directory`.

    Checks what that code relies on: ``config.json`` with ``datapoints_per_file`` and ``fields``
    describing the image, pose and metric fields; the three tensor files for every shard index
    0..N-1 with ``arr_0`` of shape (n, 32, 32, 1), (n, 7), (n,) and the declared dtype, all shards
    full but the last (its datapoint index arithmetic assumes so); and, where a split exists,
    its index files and ``metadata.json``. Reads only ``.npy`` headers, so it is fast on big
    datasets; data corruption is `DatasetReader.verify`'s job. [] means compatible.
    """
    directory = Path(directory)
    problems: list[str] = []
    dps: int | None = None
    try:
        card = read_card(directory)
    except InputError as exc:
        problems.append(str(exc))
        card = {}
    if card:
        dps = card.get("datapoints_per_file")
        if isinstance(dps, bool) or not isinstance(dps, int) or dps < 1:
            problems.append(f"config.json: 'datapoints_per_file' missing or not a positive integer ({dps!r})")
            dps = None
        declared = card.get("fields")
        wanted = gqcnn_field_config()
        for name in GQCNN_FIELDS:
            if not isinstance(declared, dict) or declared.get(name) != wanted[name]:
                got = declared.get(name) if isinstance(declared, dict) else None
                problems.append(f"config.json: fields.{name} is {got!r}, expected {wanted[name]!r}")

    tensor_dir = directory / TENSOR_DIR
    if not tensor_dir.is_dir():
        return problems + [f"'{tensor_dir}': missing"]
    indices: dict[str, set[int]] = {name: set() for name in GQCNN_FIELDS}
    for path in tensor_dir.iterdir():
        m = _DATA_RE.match(path.name)
        if m and m.group(1) in indices:
            indices[m.group(1)].add(int(m.group(2)))
    all_indices = set().union(*indices.values())
    if not all_indices:
        return problems + [f"'{tensor_dir}': no tensor files"]
    num_shards = max(all_indices) + 1
    sizes: list[int | None] = []
    for index in range(num_shards):
        lengths = set()
        for name in GQCNN_FIELDS:
            path = tensor_dir / shard_file_name(name, index)
            if index not in indices[name]:
                problems.append(f"'{path}': missing")
                continue
            spec = FIELDS[name]
            try:
                shape, dtype = _npy_header(path)
            except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile, zlib.error) as exc:
                problems.append(f"'{path}': unreadable as an npz with '{NPZ_KEY}' ({exc})")
                continue
            if len(shape) != 1 + len(spec.shape) or shape[1:] != spec.shape or dtype != spec.dtype:
                want = f"{spec.dtype}(n, {', '.join(map(str, spec.shape))})" if spec.shape else f"{spec.dtype}(n,)"
                problems.append(f"'{path}': {dtype}{shape}, expected {want}")
                continue
            lengths.add(shape[0])
        if len(lengths) > 1:
            problems.append(f"shard {index}: gqcnn files hold different numbers of datapoints {sorted(lengths)}")
        sizes.append(lengths.pop() if len(lengths) == 1 else None)
    if dps is not None:
        for index, n in enumerate(sizes):
            if n is None:
                continue
            if index < num_shards - 1 and n != dps:
                problems.append(f"shard {index}: {n} datapoints, but every shard except the last must hold {dps}")
            elif not 1 <= n <= dps:
                problems.append(f"shard {index}: {n} datapoints, expected 1 to {dps}")
    total = None if dps is None or sizes[-1] is None else dps * (num_shards - 1) + sizes[-1]

    split_root = directory / SPLIT_DIR
    for kind in SPLIT_KINDS:
        split_dir = split_root / kind
        if not split_dir.is_dir():
            continue
        if not (split_dir / "metadata.json").is_file():
            problems.append(f"'{split_dir / 'metadata.json'}': missing (gqcnn reads it with the split)")
        parts = []
        for part in SPLIT_PARTS:
            try:
                parts.append(read_split(directory, kind, part))
            except InputError as exc:
                problems.append(str(exc))
        if len(parts) == 2 and total is not None:
            both = np.concatenate(parts)
            if both.size and (both.min() < 0 or both.max() >= total):
                problems.append(f"split {kind}: indices outside [0, {total})")
            if len(np.unique(both)) != both.size:
                problems.append(f"split {kind}: train and val overlap")
    return problems
