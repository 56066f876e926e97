"""The dataset as a whole: its card ``config.json``, its train/val splits and gqcnn compatibility.

These are the files beside the shards that the original gqcnn trainer (autolab_core
TensorDataset) reads -- the card with ``datapoints_per_file`` and ``fields``, the split index files
and their ``metadata.json`` -- and `dexnet_compatible`, which checks a directory the way that code
would read it. They depend on the format only, never on the writer or the reader.
"""

from __future__ import annotations

import zipfile
import zlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.dataset.storage.format import (
    _DATA_RE,
    CARD_NAME,
    FIELDS,
    GQCNN_FIELDS,
    NPZ_KEY,
    SPLIT_DIR,
    SPLIT_KINDS,
    SPLIT_PARTS,
    TENSOR_DIR,
    _existing_shard_size,
    _json_bytes,
    _load_npz,
    _npy_header,
    _npz_bytes,
    _read_file,
    _write_bytes,
    gqcnn_field_config,
    shard_file_name,
)
from suctionbench.errors import InputError
from suctionbench.io import read_json

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
    card = read_json(path, "dataset card", "not a dataset directory?")
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
    seed: int | np.random.Generator, held_out_objects: Any = None,
) -> dict[str, dict[str, np.ndarray]]:
    """Write image-wise and object-wise train/val splits of datapoint indices; returns them.

    ``image_ids[i]`` and ``object_ids[i]`` belong to global datapoint ``i``. Image-wise keeps all
    datapoints of an image on one side (val images are drawn at random from `seed`); object-wise
    does the same per object, so validation measures generalisation to unseen objects. With
    `held_out_objects` (object ids) those objects, and only those, are object-wise val, whatever
    `seed` would draw: a second dataset of a corpus then holds out what the first held out
    (`generate --holdout-like`), and a model trained on both has seen no held-out object. Files:
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
        if kind == "object_wise" and held_out_objects is not None:
            val = np.isin(groups, np.asarray(held_out_objects))
        else:
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
        if kind == "object_wise" and held_out_objects is not None:
            metadata["held_out_like"] = True  # the val objects were given (`held_out_objects`), not drawn
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


def held_out_keys(directory: str | Path, what: str = "--holdout-like") -> list[str]:
    """The keys of the objects a dataset holds out (its object-wise val side), sorted; InputError
    naming `what` if `directory` is no finished dataset with an object-wise split."""
    from suctionbench.dataset.storage.reader import DatasetReader

    try:
        objects = read_card(directory).get("objects")
        val = read_split(directory, "object_wise", "val")
        labels = DatasetReader(directory).field("object_labels", verify=False)
    except InputError as exc:
        raise InputError(f"{what} '{directory}': not a finished dataset ({exc})") from None
    if not isinstance(objects, list) or not objects:
        raise InputError(f"{what} '{directory}': its card lists no objects")
    if len(val) == 0 or int(val.max()) >= len(labels):
        raise InputError(f"{what} '{directory}': its object-wise split does not match its {len(labels)} datapoints")
    ids = np.unique(labels[val])
    if int(ids.max()) >= len(objects):
        raise InputError(f"{what} '{directory}': object ids beyond its card's {len(objects)} objects")
    return sorted(str(objects[i]) for i in ids)


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
