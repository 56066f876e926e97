"""Dataset storage: Dex-Net tensor layout, manifests, corruption detection, atomicity, splits, card."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from conftest import remove_dataset_field

from suctionbench.dataset import storage
from suctionbench.dataset.storage import (
    FIELDS,
    DatasetReader,
    DatasetWriter,
    dexnet_compatible,
    read_card,
    read_split,
    write_card,
    write_splits,
)
from suctionbench.errors import InputError

N = 2500
PER_SHARD = 1000


def synthetic(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    """`n` random datapoints with every field; images hold ~6 datapoints, objects ~100."""
    rng = np.random.default_rng(seed)
    image_sizes = rng.integers(1, 12, size=n)  # more than enough images, cut to n datapoints
    return {
        "depth_ims_tf_table": rng.uniform(0.5, 0.7, (n, 32, 32, 1)).astype(np.float32),
        "context_ims_tf_table": rng.uniform(0.5, 0.7, (n, 32, 32, 1)).astype(np.float32),
        "object_context": rng.uniform(0.0, 0.1, (n, 6)).astype(np.float32),
        "hand_poses": rng.normal(size=(n, 7)).astype(np.float32),
        "robust_suction_wrench_resistance": rng.uniform(0, 1, n).astype(np.float32),
        "object_labels": np.sort(rng.integers(0, 25, n)).astype(np.int32),
        "pose_labels": rng.integers(0, 5, n).astype(np.int32),
        "image_labels": np.repeat(np.arange(n), image_sizes)[:n].astype(np.int32),
        "grasp_labels": rng.integers(0, 200, n).astype(np.int32),
        "seal_flags": rng.integers(0, 2, n).astype(np.uint8),
        "wrench_resistance": rng.integers(0, 2, n).astype(np.uint8),
    }


def write_dataset(directory: Path, data: dict[str, np.ndarray], per_shard: int = PER_SHARD) -> DatasetWriter:
    writer = DatasetWriter(directory, datapoints_per_shard=per_shard)
    n = len(data["hand_poses"])
    for index, start in enumerate(range(0, n, per_shard)):
        writer.write_shard(index, {name: arr[start:start + per_shard] for name, arr in data.items()})
    return writer


@pytest.fixture(scope="module")
def data():
    return synthetic(N)


@pytest.fixture(scope="module")
def pristine(tmp_path_factory, data):
    """The 3-shard dataset, written once; tests damage copies of it."""
    directory = tmp_path_factory.mktemp("pristine") / "ds"
    write_dataset(directory, data)
    return directory


@pytest.fixture
def dataset(tmp_path, pristine):
    shutil.copytree(pristine, tmp_path / "ds")
    return tmp_path / "ds"


def temp_files(directory: Path) -> list[Path]:
    return [p for p in directory.rglob("*") if p.name.endswith(".tmp")]


# -- round trip ------------------------------------------------------------------------------------


def test_round_trip_three_shards_last_partial(dataset, data):
    reader = DatasetReader(dataset)
    assert reader.shard_indices == [0, 1, 2]
    assert reader.num_datapoints == N
    assert reader.datapoints_per_shard == PER_SHARD
    assert [reader.shard_size(i) for i in range(3)] == [1000, 1000, 500]
    for index, arrays in reader.iter_shards():
        assert list(arrays) == list(FIELDS)
        n = reader.shard_size(index)
        for name, arr in arrays.items():
            spec = FIELDS[name]
            assert arr.dtype == spec.dtype
            assert arr.shape == (n, *spec.shape)
            np.testing.assert_array_equal(arr, data[name][index * PER_SHARD:index * PER_SHARD + n])
    for name in FIELDS:
        np.testing.assert_array_equal(reader.field(name), data[name])
    assert reader.verify() == []
    assert reader.verify(expected_datapoints=N) == []
    assert reader.bad_shards(expected_datapoints=N) == []


def test_file_layout_is_dexnet(dataset):
    tensors = dataset / "tensors"
    assert sorted(p.name for p in tensors.glob("hand_poses_*.npz")) == [f"hand_poses_{i:05d}.npz" for i in range(3)]
    with np.load(tensors / "depth_ims_tf_table_00002.npz") as npz:
        assert npz.files == ["arr_0"]
        assert npz["arr_0"].shape == (500, 32, 32, 1) and npz["arr_0"].dtype == np.float32
    with np.load(tensors / "hand_poses_00000.npz") as npz:
        assert npz["arr_0"].shape == (1000, 7)
    with np.load(tensors / "robust_suction_wrench_resistance_00001.npz") as npz:
        assert npz["arr_0"].shape == (1000,)


def test_shard_subset_of_fields(dataset, data):
    arrays = DatasetReader(dataset).shard(1, fields=["hand_poses"])
    assert list(arrays) == ["hand_poses"]
    np.testing.assert_array_equal(arrays["hand_poses"], data["hand_poses"][1000:2000])
    with pytest.raises(InputError, match="unknown"):
        DatasetReader(dataset).shard(1, fields=["nope"])


def test_manifests_hold_hashes_and_counts(dataset):
    for index, count in enumerate([1000, 1000, 500]):
        manifest = json.loads((dataset / "tensors" / f"shard_{index:05d}.json").read_text())
        assert manifest["num_datapoints"] == count
        assert manifest["datapoints_per_shard"] == PER_SHARD
        assert set(manifest["files"]) == {f"{name}_{index:05d}.npz" for name in FIELDS}
        for name, entry in manifest["files"].items():
            blob = (dataset / "tensors" / name).read_bytes()
            assert entry["sha256"] == hashlib.sha256(blob).hexdigest()
            assert entry["bytes"] == len(blob)


def test_writes_are_deterministic(tmp_path, data):
    """Same arrays, same bytes (np.savez_compressed would stamp the current time into the zip)."""
    write_dataset(tmp_path / "a", data)
    write_dataset(tmp_path / "b", data)
    files_a = sorted(p.relative_to(tmp_path / "a") for p in (tmp_path / "a").rglob("*") if p.is_file())
    files_b = sorted(p.relative_to(tmp_path / "b") for p in (tmp_path / "b").rglob("*") if p.is_file())
    assert files_a == files_b
    for rel in files_a:
        assert (tmp_path / "a" / rel).read_bytes() == (tmp_path / "b" / rel).read_bytes(), rel


def test_rewriting_a_shard_replaces_it(dataset, data):
    writer = DatasetWriter(dataset, datapoints_per_shard=PER_SHARD)
    other = synthetic(500, seed=9)
    writer.write_shard(2, other)
    reader = DatasetReader(dataset)
    np.testing.assert_array_equal(reader.shard(2)["hand_poses"], other["hand_poses"])
    assert reader.verify() == []


def test_inputs_of_other_width_are_converted(tmp_path, data):
    fields = {name: arr[:10] for name, arr in data.items()}
    fields["hand_poses"] = fields["hand_poses"].astype(np.float64)
    fields["object_labels"] = fields["object_labels"].astype(np.int64)
    fields["seal_flags"] = fields["seal_flags"].astype(bool)
    DatasetWriter(tmp_path).write_shard(0, fields)
    arrays = DatasetReader(tmp_path).shard(0)
    assert arrays["hand_poses"].dtype == np.float32
    assert arrays["object_labels"].dtype == np.int32
    assert arrays["seal_flags"].dtype == np.uint8


# -- validation ------------------------------------------------------------------------------------


def _bad(data, **changes):
    fields = {name: arr[:10] for name, arr in data.items()}
    for name, value in changes.items():
        if value is None:
            del fields[name]
        else:
            fields[name] = value
    return fields


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"hand_poses": None}, "missing"),
        ({"extra": np.zeros(10)}, "unknown"),
        ({"hand_poses": np.zeros((10, 6), np.float32)}, "shape"),
        ({"depth_ims_tf_table": np.zeros((10, 32, 32), np.float32)}, "shape"),
        ({"depth_ims_tf_table": np.zeros((10, 32, 32, 1), np.int32)}, "dtype"),
        ({"object_labels": np.zeros(10, np.float32)}, "dtype"),
        ({"pose_labels": np.zeros(9, np.int32)}, "different lengths"),
        ({"robust_suction_wrench_resistance": np.full(10, np.nan, np.float32)}, "NaN"),
        ({"seal_flags": np.full(10, 2, np.uint8)}, "outside"),
        ({"image_labels": np.full(10, 2**40, np.int64)}, "outside"),
    ],
)
def test_write_shard_rejects_bad_fields(tmp_path, data, changes, message):
    with pytest.raises(InputError, match=message) as info:
        DatasetWriter(tmp_path).write_shard(0, _bad(data, **changes))
    assert "\n" not in str(info.value)
    assert not (tmp_path / "tensors").exists() or not any((tmp_path / "tensors").iterdir())


def test_write_shard_rejects_bad_sizes_and_indices(tmp_path, data):
    writer = DatasetWriter(tmp_path, datapoints_per_shard=5)
    with pytest.raises(InputError, match="datapoints"):
        writer.write_shard(0, {name: arr[:6] for name, arr in data.items()})
    with pytest.raises(InputError, match="datapoints"):
        writer.write_shard(0, {name: arr[:0] for name, arr in data.items()})
    for index in (-1, 100_000, 1.5, True):
        with pytest.raises(InputError, match="shard index"):
            writer.write_shard(index, {name: arr[:5] for name, arr in data.items()})
    for size in (0, -3, 2.5):
        with pytest.raises(InputError, match="datapoints_per_shard"):
            DatasetWriter(tmp_path, datapoints_per_shard=size)


def test_writer_refuses_mixed_shard_sizes(dataset):
    with pytest.raises(InputError, match="1000"):
        DatasetWriter(dataset, datapoints_per_shard=500)


# -- corruption ------------------------------------------------------------------------------------


def _truncate(path: Path) -> None:
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])


def _flip(path: Path) -> None:
    blob = bytearray(path.read_bytes())
    mid = len(blob) // 2
    blob[mid:mid + 4] = bytes(b ^ 0xFF for b in blob[mid:mid + 4])
    path.write_bytes(bytes(blob))


CORRUPTIONS = {
    "truncate": ("hand_poses_00001.npz", _truncate),
    "flip": ("depth_ims_tf_table_00001.npz", _flip),
    "delete_file": ("seal_flags_00001.npz", Path.unlink),
    "delete_manifest": ("shard_00001.json", Path.unlink),
}


@pytest.mark.parametrize("kind", sorted(CORRUPTIONS))
def test_corruption_is_detected(dataset, data, kind):
    file_name, damage = CORRUPTIONS[kind]
    damage(dataset / "tensors" / file_name)
    reader = DatasetReader(dataset)
    with pytest.raises(InputError) as info:
        reader.shard(1)
    message = str(info.value)
    assert "\n" not in message
    assert file_name in message or "shard_00001.json" in message
    problems = reader.verify()
    assert problems and all("shard 1" in p for p in problems), problems
    assert reader.bad_shards() == [1]
    assert reader.bad_shards(expected_datapoints=N) == [1]
    # the other shards are untouched and still read
    for index in (0, 2):
        np.testing.assert_array_equal(reader.shard(index)["hand_poses"],
                                      data["hand_poses"][index * 1000:index * 1000 + reader.shard_size(index)])
    damaged_field = file_name.rsplit("_", 1)[0] if kind != "delete_manifest" else "hand_poses"
    with pytest.raises(InputError):
        reader.field(damaged_field)
    # rewriting the shard repairs the dataset (what resuming does)
    DatasetWriter(dataset).write_shard(1, {name: arr[1000:2000] for name, arr in data.items()})
    assert DatasetReader(dataset).verify() == []


def test_dataset_written_before_the_context_field(dataset, data):
    """Shards whose manifests do not list a later field (datasets written before it existed) are
    intact: their other fields read and verify; the missing field is named when asked for."""
    from suctionbench.dataset.verify import verify_dataset

    name = "context_ims_tf_table"
    assert name in storage.LATER_FIELDS
    write_card(dataset, {"datapoints": N})
    remove_dataset_field(dataset, name)
    reader = DatasetReader(dataset)
    assert reader.shard_indices == [0, 1, 2] and reader.verify(expected_datapoints=N) == []
    assert not reader.has_field(name) and reader.has_field("depth_ims_tf_table")
    assert name not in reader.shard(1) and len(reader.shard(1)) == len(FIELDS) - 1
    np.testing.assert_array_equal(reader.field("depth_ims_tf_table"), data["depth_ims_tf_table"])
    with pytest.raises(InputError, match=f"{dataset}.*shard 0 has no field '{name}'"):
        reader.field(name)
    assert not any("fields" in p for p in verify_dataset(dataset))
    # a manifest lacking a field that every dataset has is still malformed
    manifest_path = dataset / "tensors" / "shard_00002.json"
    manifest = json.loads(manifest_path.read_text())
    del manifest["files"]["hand_poses_00002.npz"]
    manifest_path.write_text(json.dumps(manifest))
    assert DatasetReader(dataset).bad_shards() == [2]


def test_corrupt_file_is_caught_without_hash_check(dataset):
    _truncate(dataset / "tensors" / "hand_poses_00001.npz")
    with pytest.raises(InputError, match="hand_poses_00001.npz"):
        DatasetReader(dataset).shard(1, verify=False)


def test_malformed_manifest_is_a_problem_not_a_crash(dataset):
    (dataset / "tensors" / "shard_00002.json").write_text("{not json")
    reader = DatasetReader(dataset)
    assert reader.shard_indices == [0, 1]
    assert reader.bad_shards() == [2]
    with pytest.raises(InputError, match="shard_00002.json"):
        reader.shard(2)


def test_verify_reports_missing_and_extra_shards(tmp_path, data):
    write_dataset(tmp_path, {name: arr[:1000] for name, arr in data.items()})  # shard 0 only
    reader = DatasetReader(tmp_path)
    problems = reader.verify(expected_datapoints=N)
    assert any("shard 1: missing" in p for p in problems) and any("shard 2: missing" in p for p in problems)
    assert reader.bad_shards(expected_datapoints=N) == [1, 2]
    assert any("1000 datapoints, expected 500" in p for p in reader.verify(expected_datapoints=500))
    assert reader.bad_shards(expected_datapoints=500) == [0]


def test_verify_reports_shards_beyond_the_expected_size(dataset):
    reader = DatasetReader(dataset)
    problems = reader.verify(expected_datapoints=1000)
    assert len(problems) == 2 and all("beyond" in p for p in problems)
    assert reader.bad_shards(expected_datapoints=1000) == []  # to delete, not to write


def test_partial_shard_in_the_middle_is_reported(tmp_path, data):
    writer = DatasetWriter(tmp_path, datapoints_per_shard=PER_SHARD)
    writer.write_shard(0, {name: arr[:400] for name, arr in data.items()})
    writer.write_shard(1, {name: arr[400:1400] for name, arr in data.items()})
    reader = DatasetReader(tmp_path)
    assert reader.bad_shards() == [0]
    assert any("only the last shard" in p for p in reader.verify())


def test_empty_and_missing_directories(tmp_path):
    reader = DatasetReader(tmp_path)
    assert reader.num_datapoints == 0 and reader.verify() == []
    assert reader.bad_shards(expected_datapoints=1500) == [0, 1]
    with pytest.raises(InputError, match="not a directory"):
        DatasetReader(tmp_path / "nope")


# -- atomicity -------------------------------------------------------------------------------------


class Boom(RuntimeError):
    pass


def _fail_on_call(monkeypatch, target: str, call: int) -> None:
    original = getattr(storage.writer, target)  # where DatasetWriter looks the helpers up
    calls = {"n": 0}

    def failing(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == call:
            raise Boom("disk on fire")
        return original(*args, **kwargs)

    monkeypatch.setattr(storage.writer, target, failing)


def test_failed_write_leaves_no_partial_shard(tmp_path, data, monkeypatch):
    fields = {name: arr[:100] for name, arr in data.items()}
    _fail_on_call(monkeypatch, "_npz_bytes", 3)
    with pytest.raises(Boom):
        DatasetWriter(tmp_path).write_shard(0, fields)
    tensors = tmp_path / "tensors"
    assert not (tensors / "shard_00000.json").exists()
    assert temp_files(tmp_path) == []
    assert list(tensors.glob("*.npz")) == []
    assert DatasetReader(tmp_path).shard_indices == []


def test_failed_manifest_write_leaves_no_partial_shard(tmp_path, data, monkeypatch):
    fields = {name: arr[:100] for name, arr in data.items()}
    _fail_on_call(monkeypatch, "_json_bytes", 1)
    with pytest.raises(Boom):
        DatasetWriter(tmp_path).write_shard(0, fields)
    assert list((tmp_path / "tensors").iterdir()) == []


def test_failed_rewrite_keeps_the_old_shard(dataset, data, monkeypatch):
    """Encoding fails before any rename, so the complete shard already there survives."""
    _fail_on_call(monkeypatch, "_npz_bytes", 5)
    with pytest.raises(Boom):
        DatasetWriter(dataset).write_shard(1, synthetic(1000, seed=3))
    assert temp_files(dataset) == []
    reader = DatasetReader(dataset)
    assert reader.verify() == []
    np.testing.assert_array_equal(reader.shard(1)["hand_poses"], data["hand_poses"][1000:2000])


def test_stale_temp_files_of_a_killed_writer_are_removed(dataset, data):
    stale = dataset / "tensors" / ".hand_poses_00001.npz.abc123.tmp"
    stale.write_bytes(b"half a file")
    DatasetWriter(dataset).write_shard(1, {name: arr[1000:2000] for name, arr in data.items()})
    assert not stale.exists()


# -- splits ----------------------------------------------------------------------------------------


def test_splits(tmp_path, data):
    images, objects = data["image_labels"], data["object_labels"]
    result = write_splits(tmp_path, images, objects, val_fraction=0.2, seed=7)
    for kind, groups, tolerance in (("image_wise", images, 0.01), ("object_wise", objects, 0.03)):
        train, val = read_split(tmp_path, kind, "train"), read_split(tmp_path, kind, "val")
        np.testing.assert_array_equal(train, result[kind]["train"])
        assert np.intersect1d(train, val).size == 0
        np.testing.assert_array_equal(np.sort(np.concatenate([train, val])), np.arange(N))
        assert np.all(np.diff(train) > 0) and np.all(np.diff(val) > 0)
        assert np.intersect1d(groups[train], groups[val]).size == 0, f"{kind}: a group on both sides"
        assert abs(len(val) / N - 0.2) <= tolerance, (kind, len(val) / N)
        metadata = json.loads((tmp_path / "splits" / kind / "metadata.json").read_text())
        assert metadata["num_val"] == len(val) and metadata["train_pct"] == pytest.approx(0.8)

    # deterministic by seed, different for another seed
    again = write_splits(tmp_path / "again", images, objects, seed=7)
    other = write_splits(tmp_path / "other", images, objects, seed=8)
    for kind in ("image_wise", "object_wise"):
        np.testing.assert_array_equal(again[kind]["val"], result[kind]["val"])
        assert (tmp_path / "splits" / kind / "val_indices.npz").read_bytes() == \
            (tmp_path / "again" / "splits" / kind / "val_indices.npz").read_bytes()
    assert not np.array_equal(other["image_wise"]["val"], result["image_wise"]["val"])


def test_given_held_out_objects_are_the_object_wise_val_side_and_only_they(tmp_path, data):
    # A second dataset of a corpus holds out what the first held out: the val side is exactly the
    # datapoints of the given objects, and the image-wise split is what the seed alone draws.
    images, objects = data["image_labels"], data["object_labels"]
    drawn = write_splits(tmp_path / "drawn", images, objects, seed=7)
    given = np.unique(objects)[::4]
    result = write_splits(tmp_path / "given", images, objects, seed=7, held_out_objects=given)
    np.testing.assert_array_equal(result["object_wise"]["val"], np.flatnonzero(np.isin(objects, given)))
    np.testing.assert_array_equal(result["image_wise"]["val"], drawn["image_wise"]["val"])
    assert not np.array_equal(result["object_wise"]["val"], drawn["object_wise"]["val"])
    metadata = json.loads((tmp_path / "given" / "splits" / "object_wise" / "metadata.json").read_text())
    assert metadata["held_out_like"] is True and metadata["num_groups_val"] == len(given)


def test_split_of_few_large_groups_keeps_both_sides(tmp_path):
    groups = np.repeat([0, 1], 50)  # 50/50: no grouping reaches 20 %, but val must not be empty
    result = write_splits(tmp_path, groups, groups, seed=0)
    assert len(result["object_wise"]["val"]) == 50 and len(result["object_wise"]["train"]) == 50
    groups = np.repeat([0, 1, 2], [80, 15, 5])
    result = write_splits(tmp_path, groups, groups, seed=0)
    assert len(result["image_wise"]["val"]) == 20  # 15 + 5: exactly 20 %


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"image_ids": np.arange(5), "object_ids": np.arange(4)}, "entries"),
        ({"image_ids": np.zeros(5), "object_ids": np.arange(5)}, "integer"),
        ({"image_ids": np.arange(0), "object_ids": np.arange(0)}, "no datapoints"),
        ({"image_ids": np.arange(5), "object_ids": np.arange(5), "val_fraction": 1.0}, "val_fraction"),
        ({"image_ids": np.arange(5), "object_ids": np.arange(5), "val_fraction": 0.0}, "val_fraction"),
    ],
)
def test_write_splits_rejects_bad_input(tmp_path, kwargs, message):
    with pytest.raises(InputError, match=message):
        write_splits(tmp_path, seed=0, **kwargs)


def test_read_split_errors(tmp_path):
    with pytest.raises(InputError, match="split kind"):
        read_split(tmp_path, "pose_wise", "train")
    with pytest.raises(InputError, match="split part"):
        read_split(tmp_path, "image_wise", "test")
    with pytest.raises(InputError, match="missing"):
        read_split(tmp_path, "image_wise", "train")


# -- dataset card ----------------------------------------------------------------------------------


def test_card_round_trip(tmp_path):
    card = {"seed": 3, "objects": ["basic/box", "typical/mug"], "camera": {"fx": 525.0}, "positive_rate": 0.118,
            "counts": {"datapoints": 2500}, "versions": {"suctionbench": "0.1.0"}}
    write_card(tmp_path, card, datapoints_per_shard=PER_SHARD)
    back = read_card(tmp_path)
    assert {k: back[k] for k in card} == card
    assert back["datapoints_per_file"] == PER_SHARD
    assert back["fields"]["depth_ims_tf_table"] == {"dtype": "float32", "height": 32, "width": 32, "channels": 1}
    assert back["fields"]["hand_poses"] == {"dtype": "float32", "height": 7}
    assert temp_files(tmp_path) == []


def test_card_takes_shard_size_from_the_shards(dataset):
    write_card(dataset, {"seed": 1})  # no size given: from the manifests
    assert read_card(dataset)["datapoints_per_file"] == PER_SHARD
    with pytest.raises(InputError, match="contradicts"):
        write_card(dataset, {"datapoints_per_file": 10}, datapoints_per_shard=PER_SHARD)


@pytest.mark.parametrize("text, message", [("{broken", "malformed"), ("[1, 2]", "JSON object"), (None, "missing")])
def test_malformed_card(tmp_path, text, message):
    if text is not None:
        (tmp_path / "config.json").write_text(text)
    with pytest.raises(InputError, match=message) as info:
        read_card(tmp_path)
    assert "config.json" in str(info.value)


@pytest.mark.parametrize("card", [{"x": float("nan")}, {"x": object()}, {1: "a"}, ["not", "a", "dict"]])
def test_unwritable_card(tmp_path, card):
    with pytest.raises(InputError, match="dataset card"):
        write_card(tmp_path, card)
    assert not (tmp_path / "config.json").exists()


# -- gqcnn compatibility ---------------------------------------------------------------------------


@pytest.fixture
def full_dataset(dataset, data):
    write_card(dataset, {"seed": 0})
    write_splits(dataset, data["image_labels"], data["object_labels"], seed=0)
    return dataset


def test_written_dataset_is_gqcnn_compatible(full_dataset):
    assert dexnet_compatible(full_dataset) == []


def _gqcnn_num_datapoints(directory: Path) -> int:
    """autolab_core.TensorDataset's count: datapoints_per_file * (num_files - 1) + size of the last file."""
    config = json.loads((directory / "config.json").read_text())
    names = sorted(p.name for p in (directory / "tensors").glob("*.npz"))
    last = max(int(name[-9:-4]) for name in names)
    with np.load(directory / "tensors" / f"hand_poses_{last:05d}.npz") as npz:
        return config["datapoints_per_file"] * last + len(npz["arr_0"])


def test_gqcnn_index_arithmetic_matches(full_dataset):
    assert _gqcnn_num_datapoints(full_dataset) == DatasetReader(full_dataset).num_datapoints == N


def _break_shape(d: Path) -> None:
    np.savez_compressed(d / "tensors" / "hand_poses_00001.npz", np.zeros((1000, 6), np.float32))


def _break_key(d: Path) -> None:
    np.savez_compressed(d / "tensors" / "hand_poses_00001.npz", poses=np.zeros((1000, 7), np.float32))


def _break_size(d: Path) -> None:
    for name in storage.GQCNN_FIELDS:
        path = d / "tensors" / f"{name}_00001.npz"
        with np.load(path) as npz:
            arr = npz["arr_0"][:10]
        np.savez_compressed(path, arr)


def _break_card(d: Path) -> None:
    card = json.loads((d / "config.json").read_text())
    del card["fields"]["hand_poses"]
    (d / "config.json").write_text(json.dumps(card))


BREAKAGES = {
    "missing_file": (lambda d: (d / "tensors" / "robust_suction_wrench_resistance_00001.npz").unlink(), "missing"),
    "wrong_shape": (_break_shape, "expected float32"),
    "wrong_key": (_break_key, "arr_0"),
    "partial_middle_shard": (_break_size, "every shard except the last"),
    "no_card": (lambda d: (d / "config.json").unlink(), "config.json"),
    "card_fields": (_break_card, "fields.hand_poses"),
    "split_metadata": (lambda d: (d / "splits" / "image_wise" / "metadata.json").unlink(), "metadata.json"),
}


@pytest.mark.parametrize("kind", sorted(BREAKAGES))
def test_broken_dataset_is_not_gqcnn_compatible(full_dataset, kind):
    breakage, message = BREAKAGES[kind]
    breakage(full_dataset)
    problems = dexnet_compatible(full_dataset)
    assert any(message in p for p in problems), problems
