"""The on-disk format of a dataset directory: what every other storage module agrees on.

The field table (`FIELDS`, `FieldSpec`), the directory and file names, the manifest format and
the byte-level helpers that write and read single files (deterministic ``.npz`` and JSON bytes,
atomic writes, checked reads). It imports no other storage module, so the writer, the reader and
the card all build on it without an import cycle.
"""

from __future__ import annotations

import contextlib
import io
import json
import re
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.errors import InputError
from suctionbench.io import atomic_path
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
