"""Dataset generation: layout, determinism, resume, engines, and labels that match the labeller."""

from __future__ import annotations

import filecmp
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from suctionbench.config import CUP_DEFAULT, STANDARD_GRAVITY
from suctionbench.contact import SuctionLabeller
from suctionbench.dataset import generate as gen
from suctionbench.dataset.storage import DatasetReader, dexnet_compatible, held_out_keys, read_card, read_split
from suctionbench.errors import InputError
from suctionbench.geometry.sampling import sample_surface_grasps
from suctionbench.objects.registry import load_object

KEYS = ["basic/box_tea", "typical/mug_classic", "basic/cylinder_can"]
CONFIG = gen.GenerationConfig(datapoints=150, seed=3, grasps_per_object=40, stable_poses=2, datapoints_per_shard=64)


def run(out: Path, **kwargs):
    records = [load_object(k) for k in KEYS]
    return gen.generate_dataset(out, [str(r.directory) for r in records], KEYS, "primesense", CONFIG, **kwargs)


def same_tensors(a: Path, b: Path) -> bool:
    files = sorted(p.name for p in (a / "tensors").iterdir())
    return files == sorted(p.name for p in (b / "tensors").iterdir()) and all(
        filecmp.cmp(a / "tensors" / f, b / "tensors" / f, shallow=False) for f in files
    )


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("ds") / "reference"
    run(out)
    return out


def test_layout_shapes_dtypes_and_gqcnn_compatibility(reference):
    reader = DatasetReader(reference)
    assert reader.num_datapoints == CONFIG.datapoints
    shard = reader.shard(0)
    assert shard["depth_ims_tf_table"].shape == (64, 32, 32, 1) and shard["depth_ims_tf_table"].dtype == np.float32
    assert shard["hand_poses"].shape == (64, 7) and shard["robust_suction_wrench_resistance"].shape == (64,)
    # The context thumbnail: 3x the local crop around the same grasp, each pixel a block mean. Both
    # are centred on the grasp pixel, so their centres see the same surface: on these objects'
    # faces the block means (9 px, ~1 cm) differ from the point samples by millimetres, not by the
    # centimetres between the object and the table.
    context, local = shard["context_ims_tf_table"], shard["depth_ims_tf_table"]
    assert context.shape == local.shape and context.dtype == np.float32 and np.isfinite(context).all()
    centre = np.abs(context[:, 15:17, 15:17, 0].mean(axis=(1, 2)) - local[:, 15:17, 15:17, 0].mean(axis=(1, 2)))
    assert np.median(centre) < 0.005
    rwr = reader.field("robust_suction_wrench_resistance")
    assert np.all((rwr >= 0) & (rwr <= 1))
    # The object context of the 14 x 7 x 7 cm tea box (object 0), lying on a 14 x 7 face whichever
    # stable pose it is in: seen from above, its visible points span its footprint, 14 x 7 cm (a
    # few mm less at the percentiles, a few more with the image's depth scale), and a grasp on it
    # lies at most the half diagonal sqrt(7^2 + 3.5^2) = 7.8 cm from their centroid.
    context_box = reader.field("object_context")[reader.field("object_labels") == 0]
    assert len(context_box) and np.all(context_box[:, 0] <= 0.078 + 0.005)
    assert np.all((context_box[:, 3] > 0.12) & (context_box[:, 3] < 0.15))
    assert np.all((context_box[:, 4] > 0.06) & (context_box[:, 4] < 0.08))
    poses = reader.field("hand_poses")
    assert np.all((poses[:, 2] > 0.3) & (poses[:, 2] < 0.8))  # gripper depth: camera 0.5-0.7 m away
    assert np.all((poses[:, 3] >= 0) & (poses[:, 3] <= np.radians(80) + 1e-6))  # approach angle
    assert dexnet_compatible(reference) == []
    card = read_card(reference)
    assert card["status"] == "complete" and card["camera"]["name"] == "primesense" and card["objects"] == KEYS
    # labelled with the loads the benchmark scores a pick by (LabelConfig.for_episode)
    motion = card["config"]["label"]["perturbation"]
    assert motion["inertial_acceleration"] == CUP_DEFAULT.peak_acceleration and motion["press_compression"] > 0
    train, val = read_split(reference, "image_wise", "train"), read_split(reference, "image_wise", "val")
    assert len(set(train) & set(val)) == 0 and len(train) + len(val) == CONFIG.datapoints


def test_same_seed_same_dataset(reference, tmp_path):
    run(tmp_path / "again")
    assert same_tensors(reference, tmp_path / "again")


def test_resume_after_a_kill_equals_an_uninterrupted_run(reference, tmp_path, monkeypatch):
    out = tmp_path / "killed"
    real = gen.run_units

    def dies_after_one(*args, **kwargs):
        for k, item in enumerate(real(*args, **kwargs)):
            if k == 1:
                raise KeyboardInterrupt  # the process is killed mid-run
            yield item

    monkeypatch.setattr(gen, "run_units", dies_after_one)
    with pytest.raises(KeyboardInterrupt):
        run(out)
    monkeypatch.setattr(gen, "run_units", real)
    assert not (out / "tensors").exists() or not any((out / "tensors").glob("*.json"))
    with pytest.raises(InputError, match="--resume"):
        run(out)  # refuses to touch an existing output without --resume
    card = run(out, resume=True)
    assert same_tensors(reference, out)
    # generation time and size: both runs recorded, the killed one with the unit it finished
    first, second = card["generation_runs"]
    units = len(gen.plan_units(len(KEYS), CONFIG.datapoints))
    assert first["units"] == 1 and second["units_before"] == 1 and second["units"] == units - 1
    summary = card["generation"]
    assert summary["untimed_units"] == 0 and summary["recorded_datapoints"] == CONFIG.datapoints
    assert summary["bytes"] == sum(f.stat().st_size for f in out.rglob("*")
                                   if f.is_file() and "units" not in f.parts and f.name != "config.json")
    assert summary["bytes_per_datapoint"] > 32 * 32 * 4  # at least the float32 grasp thumbnail


def test_shards_assembled_on_several_threads_are_the_same_bytes(reference, tmp_path):
    # Each shard reads the units it spans (64-datapoint shards over 50-datapoint units: most span
    # two, and units split across shard boundaries) and is written on its own; the result must be
    # the one-thread assembly's files, byte for byte.
    from suctionbench.dataset.storage import DatasetWriter

    out = tmp_path / "threads"
    shutil.copytree(reference, out)
    shutil.rmtree(out / "tensors")
    units = gen.plan_units(len(KEYS), CONFIG.datapoints, CONFIG)
    writer = DatasetWriter(out, datapoints_per_shard=CONFIG.datapoints_per_shard)
    stats = gen._assemble_shards(out, units, writer, CONFIG.datapoints_per_shard, CONFIG.label_threshold, threads=3)
    assert stats["datapoints"] == CONFIG.datapoints and stats["shards"] == 3
    np.testing.assert_array_equal(np.sort(stats["image_ids"]), np.sort(DatasetReader(reference).field("image_labels")))
    assert same_tensors(reference, out)


@pytest.mark.parametrize("threads", [1, 2])
def test_assembly_decompresses_each_unit_once_however_many_shards_it_spans(reference, tmp_path, monkeypatch,
                                                                           threads):
    # 8-datapoint shards over 50-datapoint units: each unit spans 7-8 shards. Reading the whole
    # unit for every shard made assembly quadratic in a unit's size (a small set's object: 120,000
    # datapoints, 120 shards); each unit is now read whole once, and the shards hold the same
    # datapoints in the same order.
    from suctionbench.dataset.storage import DatasetWriter

    out = tmp_path / "small_shards"
    shutil.copytree(reference, out)
    shutil.rmtree(out / "tensors")
    whole = []
    load = gen.load_unit

    def spy(directory, index, fields=gen.UNIT_FIELDS):
        if fields == gen.UNIT_FIELDS:
            whole.append(index)
        return load(directory, index, fields)

    monkeypatch.setattr(gen, "load_unit", spy)
    units = gen.plan_units(len(KEYS), CONFIG.datapoints, CONFIG)
    stats = gen._assemble_shards(out, units, DatasetWriter(out, datapoints_per_shard=8), 8, CONFIG.label_threshold,
                                 threads=threads)
    assert stats["shards"] == 19 and sorted(whole) == [0, 1, 2]
    card = json.loads((out / "config.json").read_text())
    (out / "config.json").write_text(json.dumps({**card, "datapoints_per_file": 8}))
    small, full = DatasetReader(out), DatasetReader(reference)
    for name in ("robust_suction_wrench_resistance", "grasp_labels", "depth_ims_tf_table"):
        np.testing.assert_array_equal(small.field(name), full.field(name))


def test_corrupt_unit_is_reported_and_regenerated(reference, tmp_path):
    out = tmp_path / "corrupt"
    run(out)
    unit = gen.unit_path(out, 1)
    unit.write_bytes(unit.read_bytes()[:100])  # truncated
    card = run(out, resume=True)
    assert len(card["regenerated_corrupt_units"]) == 1 and "unit_00001" in card["regenerated_corrupt_units"][0]
    assert same_tensors(reference, out)


def test_different_config_is_refused(reference, tmp_path):
    out = tmp_path / "other"
    run(out)
    records = [load_object(k) for k in KEYS]
    other = gen.GenerationConfig(datapoints=150, seed=4, grasps_per_object=40, stable_poses=2, datapoints_per_shard=64)
    with pytest.raises(InputError, match="different configuration"):
        gen.generate_dataset(out, [str(r.directory) for r in records], KEYS, "primesense", other, resume=True)


def test_holdout_like_holds_out_the_other_datasets_objects(reference, tmp_path):
    # A second dataset of the same objects (another seed) holds out exactly the reference's held-out
    # objects, so a model trained on both sees none of them; the card says where they came from.
    keys = held_out_keys(reference)
    assert 0 < len(keys) < len(KEYS)
    records = [load_object(k) for k in KEYS]
    other = gen.GenerationConfig(datapoints=150, seed=4, grasps_per_object=40, stable_poses=2, datapoints_per_shard=64)
    out = tmp_path / "second"
    card = gen.generate_dataset(out, [str(r.directory) for r in records], KEYS, "primesense", other,
                                holdout_like=reference)
    assert held_out_keys(out) == keys
    assert card["holdout_like"]["objects"] == len(keys)
    assert card["holdout_like"]["fingerprint"] == read_card(reference)["fingerprint"]
    # another corpus (here: without one of the held-out objects) is refused before anything is written
    rest = [k for k in KEYS if k != keys[0]]
    with pytest.raises(InputError, match=r"--holdout-like .*not among --objects"):
        gen.generate_dataset(tmp_path / "third", [str(load_object(k).directory) for k in rest], rest, "primesense",
                             other, holdout_like=reference)
    assert not (tmp_path / "third").exists()
    with pytest.raises(InputError, match=r"--holdout-like .*not a finished dataset"):
        gen.generate_dataset(tmp_path / "fourth", [str(r.directory) for r in records], KEYS, "primesense", other,
                             holdout_like=tmp_path)


def test_holdout_like_a_model_holds_out_what_it_never_trained_on(reference, tmp_path):
    # A model trained object-wise records its held-out objects by key, so new data can hold out the
    # same ones with only the model at hand (the dataset it came from may be gone); a model that
    # records none (image-wise) is refused before anything is written.
    from suctionbench.learning.train import train
    from suctionbench.learning.train_config import TrainConfig

    model = tmp_path / "model"
    train(reference, model, TrainConfig(arch="compact", epochs=1, batch_size=16, split="object_wise"))
    card = json.loads((model / "model.json").read_text())
    assert card["dataset"]["held_out_objects"] == held_out_keys(reference)
    other = gen.GenerationConfig(datapoints=150, seed=4, grasps_per_object=40, stable_poses=2, datapoints_per_shard=64)
    dirs = [str(load_object(k).directory) for k in KEYS]
    made = gen.generate_dataset(tmp_path / "second", dirs, KEYS, "primesense", other, holdout_like=model)
    assert held_out_keys(tmp_path / "second") == held_out_keys(reference)
    assert made["holdout_like"]["fingerprint"] == read_card(reference)["fingerprint"]
    image_wise = tmp_path / "image_wise"
    train(reference, image_wise, TrainConfig(arch="compact", epochs=1, batch_size=16, split="image_wise"))
    assert json.loads((image_wise / "model.json").read_text())["dataset"]["held_out_objects"] is None
    with pytest.raises(InputError, match=r"--holdout-like .*lists no held-out objects"):
        gen.generate_dataset(tmp_path / "third", dirs, KEYS, "primesense", other, holdout_like=image_wise)
    assert not (tmp_path / "third").exists()


def test_the_shipped_default_names_the_objects_it_held_out(tmp_path):
    # The default's 300 held-out objects (a fifth of the 1,500-object corpus) are recorded by key,
    # so `--holdout-like` reads them from the model; objects of another corpus are refused.
    from suctionbench.learning.checkpoint import read_model_card
    from suctionbench.policies.gqcnn import default_model_dir

    keys = read_model_card(default_model_dir())["dataset"]["held_out_objects"]
    assert len(keys) == len(set(keys)) == 300 and all(k.startswith("train/train_") for k in keys)
    with pytest.raises(InputError, match=r"--holdout-like .*300 of its held-out objects are not among --objects"):
        gen.generate_dataset(tmp_path / "basic", [str(load_object(k).directory) for k in KEYS], KEYS, "primesense",
                             CONFIG, holdout_like=default_model_dir())
    assert not (tmp_path / "basic").exists()


def test_labels_agree_with_the_labeller(reference):
    # Unit u draws its candidates first from its own stream (seed, u) and labels them in stable
    # pose s with gravity rotated into that pose; labelling the same grasps directly must give
    # exactly the stored labels.
    reader = DatasetReader(reference)
    objects, poses = reader.field("object_labels"), reader.field("pose_labels")
    grasps, rwr = reader.field("grasp_labels"), reader.field("robust_suction_wrench_resistance")
    seal = reader.field("seal_flags")
    record = load_object(KEYS[0])
    rng = np.random.default_rng((CONFIG.seed, 0))
    points, approaches = sample_surface_grasps(record.mesh(), CONFIG.grasps_per_object, rng)
    checked = 0
    for s in range(CONFIG.stable_poses):
        rows = np.flatnonzero((objects == 0) & (poses == s))
        if len(rows) == 0:
            continue
        pose = np.asarray(record.stable_poses[s]["transform"])
        gravity = pose[:3, :3].T @ np.array([0.0, 0.0, -STANDARD_GRAVITY])
        labeller = SuctionLabeller(record.mesh(), CONFIG.label, mass=record.mass, com=record.com, gravity=gravity)
        seed = int(np.random.SeedSequence((CONFIG.seed, 0, s)).generate_state(1)[0])
        labels = labeller.label(points, approaches, seed, metrics=("wr", "rwr"))
        np.testing.assert_allclose(rwr[rows], labels.rwr[grasps[rows]], atol=1e-7)
        np.testing.assert_array_equal(seal[rows], labels.seal.seal[grasps[rows]])
        checked += len(rows)
    assert checked > 0


def test_ray_engine_writes_the_same_dataset_as_the_local_one(reference, tmp_path):
    pytest.importorskip("ray")
    run(tmp_path / "ray", engine="ray", workers=2)
    assert same_tensors(reference, tmp_path / "ray")


def test_bad_inputs(tmp_path):
    from suctionbench.objects.registry import resolve_objects

    with pytest.raises(InputError, match="unknown"):
        resolve_objects("no_such_set")
    with pytest.raises(InputError):
        gen.generate_dataset(tmp_path / "x", [], [], "primesense", CONFIG)
    with pytest.raises(InputError, match="camera"):
        record = load_object(KEYS[0])
        gen.generate_dataset(tmp_path / "y", [str(record.directory)], KEYS[:1], "no-such-camera", CONFIG)
    with pytest.raises(InputError, match="cannot create"):
        record = load_object(KEYS[0])
        gen.generate_dataset(Path("/proc/no/such/dir"), [str(record.directory)], KEYS[:1], "primesense", CONFIG)
    with pytest.raises(InputError, match="engine"):
        record = load_object(KEYS[0])
        gen.generate_dataset(tmp_path / "z", [str(record.directory)], KEYS[:1], "primesense", CONFIG, engine="spark")
    assert not (tmp_path / "z").exists()  # checked before anything is written


def test_smoothed_approaches_blend_faces_at_edges_like_a_depth_normal():
    import trimesh

    from suctionbench.geometry.sampling import smoothed_approaches

    # 10 cm cube, 3 mm ball. Face centre: only the top face -> exactly its normal. On the edge
    # between top (+z) and side (+x): equal areas of both faces in the ball -> the bisector. 1 mm
    # inside the edge: the side holds a half disc of radius sqrt(3^2 - 1^2) mm (12.6 mm^2), the top
    # the disc less the 1 mm segment (28.3 - 8.25 = 20.0 mm^2) -> approach ~ -(12.6, 0, 20.0)/|.|.
    box = trimesh.creation.box((0.1, 0.1, 0.1))
    points = np.array([[0.0, 0.0, 0.05], [0.05, 0.0, 0.05], [0.049, 0.0, 0.05]])
    down = np.tile([0.0, 0.0, -1.0], (3, 1))
    smoothed = smoothed_approaches(box, points, down, 0.003, np.random.default_rng(0))
    expected = np.array([[0, 0, -1.0], [-1.0, 0, -1.0], [-12.57, 0, -20.0]])
    expected /= np.linalg.norm(expected, axis=1, keepdims=True)
    angles = np.degrees(np.arccos(np.clip(np.sum(smoothed * expected, axis=1), -1, 1)))
    assert angles[0] == 0.0 and angles[1] < 6.0 and angles[2] < 6.0  # ~100 samples per disc: a few deg
    # A 2 mm plate: the far face (opposite normal) is left out, so the top keeps its normal.
    plate = trimesh.creation.box((0.1, 0.1, 0.002))
    flat = smoothed_approaches(plate, np.array([[0.0, 0.0, 0.001]]), down[:1], 0.003, np.random.default_rng(0))
    np.testing.assert_allclose(flat, down[:1])


def test_dataset_show_reports_generation_time_and_size(reference):

    from typer.testing import CliRunner

    from suctionbench.cli import app

    result = CliRunner().invoke(app, ["dataset", "show", str(reference), "--json"])
    assert result.exit_code == 0, result.output
    shown = json.loads(result.stdout.strip().splitlines()[-1])
    generation = read_card(reference)["generation"]
    assert shown["generation_bytes"] == generation["bytes"] > 0
    assert shown["generation_recorded_seconds"] == generation["recorded_seconds"] > 0
    assert shown["generation_untimed_units"] == 0
    # what a model trained on it will read: the image noise and how the grasp thumbnails were cut
    assert shown["noise"] == read_card(reference)["config"].get("noise_model", "paper")
    assert shown["grasp_thumbnail"] == "96 px crops at 32 x 32, point samples"


def test_a_passed_check_is_trusted_until_a_file_changes(reference, tmp_path, monkeypatch):
    import shutil

    from suctionbench.dataset import verify

    data = tmp_path / "copy"
    shutil.copytree(reference, data)
    (data / verify.VERIFIED_NAME).unlink(missing_ok=True)
    state = verify.check_dataset(data)  # a full read
    assert not (data / verify.VERIFIED_NAME).exists()  # recorded only once the command succeeded
    verify.record_check(data, state)
    assert (data / verify.VERIFIED_NAME).is_file() and verify.foreign_entries(data) == []
    calls = []
    monkeypatch.setattr(verify, "verify_dataset", lambda d: calls.append(d) or [])
    assert verify.check_dataset(data) is None
    assert calls == []  # nothing changed: the record stands in for the read
    monkeypatch.undo()
    shard = sorted((data / "tensors").glob("robust_suction_wrench_resistance_*.npz"))[0]
    blob = bytearray(shard.read_bytes())
    blob[-30] ^= 0xFF  # a damaged shard: size kept, modification time moves
    shard.write_bytes(bytes(blob))
    with pytest.raises(InputError, match="sha256|hash|manifest"):
        verify.check_dataset(data)


def test_spaced_top_keeps_the_best_grasps_a_spacing_apart():
    # Greedy non-maximum suppression: in order of falling q, a grasp is kept unless one already
    # kept lies closer than the spacing (10 mm). q 0.9 (x = 0) is kept; 0.8 (5 mm from it) is not;
    # 0.7 (12 mm) is; 0.6 (20 mm: 8 mm from 0.7's) is not; 0.5 (30 mm: 18 mm from 0.7's) is.
    from suctionbench.dataset.proposals import spaced_top

    q = np.array([0.6, 0.9, 0.5, 0.8, 0.7])
    points = np.array([[0.020, 0, 0], [0, 0, 0], [0.030, 0, 0], [0.005, 0, 0], [0.012, 0, 0]])
    assert spaced_top(q, points, 5, 0.01).tolist() == [1, 4, 2]
    assert spaced_top(q, points, 2, 0.01).tolist() == [1, 4]
    assert spaced_top(q, points, 5, 0.0).tolist() == [1, 3, 4, 0, 2]


def test_proposals_are_the_policys_grasps_labelled_first_on_each_image(monkeypatch):
    # generate --proposals: on every image the dense policy's best grasps (at most K, 1 cm apart)
    # come first, with ids -1, -2, ...; their labels are the labeller's verdict on exactly those
    # grasps, taken into the object's frame, with the seed (seed, unit, image, 2).
    from suctionbench.dataset import proposals as prop
    from suctionbench.dataset.render import TableScene
    from suctionbench.policies.gqcnn import default_model_dir

    seen: list[tuple[np.ndarray, np.ndarray]] = []  # object pose, camera pose per render
    proposed: list[tuple[np.ndarray, np.ndarray]] = []  # camera-frame points, approaches per image
    render, propose = TableScene.render, prop.Proposer.propose

    def spy_render(self, object_pose, camera_pose):
        seen.append((np.array(object_pose), np.array(camera_pose)))
        return render(self, object_pose, camera_pose)

    def spy_propose(self, *args):
        out = propose(self, *args)
        proposed.append(out)
        return out

    monkeypatch.setattr(TableScene, "render", spy_render)
    monkeypatch.setattr(prop.Proposer, "propose", spy_propose)
    config = gen.GenerationConfig(datapoints=40, seed=3, grasps_per_object=40, stable_poses=2,
                                  proposals=str(default_model_dir()), proposals_per_image=3)
    record = load_object(KEYS[0])
    arrays = gen.generate_unit(gen.Unit(0, 40), str(record.directory), "primesense", config)
    ids, images, poses = arrays["grasp_labels"], arrays["image_labels"], arrays["pose_labels"]
    checked = 0
    for image, ((object_pose, camera_pose), (points, approaches)) in enumerate(zip(seen, proposed, strict=True)):
        rows = np.flatnonzero(images == image)
        k = len(points)
        assert 1 <= k <= 3 and ids[rows[:k]].tolist() == [-1 - i for i in range(k)] and (ids[rows[k:]] >= 0).all()
        if k > 1:
            gaps = np.linalg.norm(points[:, None] - points[None], axis=2)[np.triu_indices(k, 1)]
            assert gaps.min() >= prop.PROPOSAL_SPACING
        world = points @ camera_pose[:3, :3].T + camera_pose[:3, 3]
        turn, shift = object_pose[:3, :3], object_pose[:3, 3]
        s = int(poses[rows[0]])
        gravity = np.asarray(record.stable_poses[s]["transform"])[:3, :3].T @ np.array([0.0, 0.0, -STANDARD_GRAVITY])
        labeller = SuctionLabeller(record.mesh(), config.label, mass=record.mass, com=record.com, gravity=gravity)
        seed = int(np.random.SeedSequence((config.seed, 0, image, 2)).generate_state(1)[0])
        labels = labeller.label((world - shift) @ turn, approaches @ camera_pose[:3, :3].T @ turn, seed,
                                metrics=("wr", "rwr"))
        np.testing.assert_allclose(arrays["robust_suction_wrench_resistance"][rows[:k]], labels.rwr, atol=1e-7)
        np.testing.assert_array_equal(arrays["seal_flags"][rows[:k]], labels.seal.seal)
        checked += k
    assert checked >= 3


def test_proposals_need_a_trained_model(tmp_path):
    record = load_object(KEYS[0])
    config = gen.GenerationConfig(datapoints=10, proposals=str(tmp_path / "no_model"))
    with pytest.raises(InputError, match="--proposals .*no_model.*not a trained model"):
        gen.generate_dataset(tmp_path / "x", [str(record.directory)], KEYS[:1], "primesense", config)
    assert not (tmp_path / "x").exists()


def test_a_dataset_in_the_sensors_noise_says_so_and_paper_datasets_keep_their_fingerprint(reference, tmp_path):
    # `noise_model` decides the images, so it enters the fingerprint (a resumed run must match it);
    # but datasets written before it was a choice (all in the paper's noise) must still resume, so
    # for "paper" the fingerprint is the hash of the settings without the field, as it was.
    import dataclasses
    import hashlib

    from suctionbench.config import to_dict

    card = read_card(reference)
    settings = to_dict(CONFIG)
    for key in ("proposals", "proposals_per_image", "noise_model", "thumbnail", "grasps_per_image"):
        del settings[key]
    old = {"config": settings, "camera": card["camera"], "objects": KEYS}
    assert card["fingerprint"] == hashlib.sha256(json.dumps(old, sort_keys=True).encode()).hexdigest()[:16]
    records = [load_object(k) for k in KEYS]
    sensor = gen.generate_dataset(tmp_path / "sensor", [str(r.directory) for r in records], KEYS, "primesense",
                                  dataclasses.replace(CONFIG, noise_model="sensor"))
    assert sensor["config"]["noise_model"] == "sensor" and sensor["fingerprint"] != card["fingerprint"]
    with pytest.raises(InputError, match="--noise 'kinect': unknown"):
        gen.generate_dataset(tmp_path / "k", [str(records[0].directory)], KEYS[:1], "primesense",
                             dataclasses.replace(CONFIG, noise_model="kinect"))
    assert not (tmp_path / "k").exists()  # refused before anything is written


def test_a_dataset_without_noise_is_its_sensor_twin_but_for_the_images():
    # `--noise none` renders the same scenes and records the same grasps with the same labels as
    # `--noise sensor` with the same seed (it makes the same draws), so an ablation of the sensor's
    # noise changes nothing else; only the grasp and context thumbnails differ.
    import dataclasses

    record = load_object(KEYS[0])
    config = dataclasses.replace(CONFIG, grasps_per_object=40)
    runs = {model: gen.generate_unit(gen.Unit(0, 40), str(record.directory), "primesense",
                                     dataclasses.replace(config, noise_model=model)) for model in ("sensor", "none")}
    images = ("depth_ims_tf_table", "context_ims_tf_table")
    for name, values in runs["sensor"].items():
        if name in images:
            assert not np.array_equal(values, runs["none"][name])
        elif name != "object_context":  # measured on the image: the visible object's centroid and extent
            np.testing.assert_array_equal(values, runs["none"][name], err_msg=name)
    assert len(runs["none"]["robust_suction_wrench_resistance"]) == 40


def test_grasps_per_image_spreads_an_objects_candidates_over_more_images():
    # With a cap, each image records at most that many of its visible candidates (distinct ones),
    # so the same quota takes more images. The cap draws which candidates, not their labels: a
    # (stable pose, candidate) pair carries the same robust label as without the cap (each pose's
    # labels have their own seed).
    import dataclasses

    record = load_object(KEYS[0])
    config = dataclasses.replace(CONFIG, grasps_per_object=120)
    runs = {cap: gen.generate_unit(gen.Unit(0, 90), str(record.directory), "primesense",
                                   dataclasses.replace(config, grasps_per_image=cap)) for cap in (0, 12)}
    images = {cap: np.unique(a["image_labels"], return_counts=True) for cap, a in runs.items()}
    assert images[12][1].max() <= 12 and images[0][1].max() > 12
    assert len(images[12][0]) > len(images[0][0])
    capped = runs[12]
    for image in images[12][0]:
        ids = capped["grasp_labels"][capped["image_labels"] == image]
        assert len(np.unique(ids)) == len(ids)
    label = {(int(s), int(g)): r for s, g, r in zip(runs[0]["pose_labels"], runs[0]["grasp_labels"],
                                                     runs[0]["robust_suction_wrench_resistance"], strict=True)}
    shared = [(label[(int(s), int(g))], r) for s, g, r in zip(capped["pose_labels"], capped["grasp_labels"],
                                                               capped["robust_suction_wrench_resistance"], strict=True)
              if (int(s), int(g)) in label]
    assert len(shared) >= 10
    np.testing.assert_array_equal(*np.array(shared).T)


def test_a_dataset_smaller_than_asked_says_which_objects_stopped_short(tmp_path):
    # An object whose visible candidates cannot fill its share in `max_images_per_object` images
    # stops there. One image of the tea box shows at most its 40 candidates (CONFIG), so with one
    # image per object a share of 75 cannot be met: the card lists the unit with what it holds,
    # and the CLI adds a note naming the object and the remedy (exit 0: the data is valid).
    import dataclasses

    from typer.testing import CliRunner

    from suctionbench.cli import app

    record = load_object(KEYS[0])
    config = dataclasses.replace(CONFIG, datapoints=75, max_images_per_object=1)
    card = gen.generate_dataset(tmp_path / "short", [str(record.directory)], KEYS[:1], "primesense", config)
    assert 0 < card["datapoints"] <= 40
    assert card["short_units"] == [{"unit": 0, "object": KEYS[0], "datapoints": card["datapoints"], "quota": 75}]
    assert DatasetReader(tmp_path / "short").num_datapoints == card["datapoints"]
    full = gen.generate_dataset(tmp_path / "full", [str(record.directory)], KEYS[:1], "primesense",
                                dataclasses.replace(config, max_images_per_object=gen.MAX_IMAGES_PER_UNIT))
    assert full["datapoints"] == 75 and full["short_units"] == []
    result = CliRunner().invoke(app, ["generate", "--objects", str(record.directory), "--datapoints", "75",
                                      "--grasps-per-object", "40", "--max-images-per-object", "1",
                                      "--out", str(tmp_path / "cli"), "--workers", "1", "--json"])
    assert result.exit_code == 0, result.output
    line = json.loads(result.stdout.strip().splitlines()[-1])
    assert line["ok"] and line["datapoints"] < 75 and line["short_units"] == 1
    assert "of the 75 datapoints asked for" in result.stderr and "--max-images-per-object 1" in result.stderr


@pytest.mark.parametrize("change", [{"sampling": "mean"}, {"crop_size": 64}], ids=["block-means", "crop-64"])
def test_grasp_thumbnail_options_change_only_the_grasp_thumbnails_of_a_dataset(reference, tmp_path, change):
    # The sampling and the crop decide only how the grasp thumbnail reads the noisy image: the
    # images, grasps, labels and context thumbnails draw the same random numbers, so they are equal
    # bit for bit. Block means instead of each 3 x 3 block's centre differ, on the (smooth) object
    # surfaces, by about the noise the mean removes (a few mm at most), not by the object's depth
    # relief. A 64 px crop samples every 2nd image pixel instead of every 3rd: its four central
    # pixels lie 1 px from the grasp pixel (diagonally) instead of 1.5 px, so their mean is the
    # surface's depth at the grasp either way, within the noise and a few mm of slope.
    import dataclasses

    from suctionbench.config import to_dict
    from suctionbench.sensing.thumbnails import THUMBNAIL_GQCNN

    thumbnail = dataclasses.replace(THUMBNAIL_GQCNN, **change)
    records = [load_object(k) for k in KEYS]
    card = gen.generate_dataset(tmp_path / "other", [str(r.directory) for r in records], KEYS, "primesense",
                                dataclasses.replace(CONFIG, thumbnail=thumbnail))
    assert card["config"]["thumbnail"] == to_dict(thumbnail)
    assert card["fingerprint"] != read_card(reference)["fingerprint"]
    a, b = DatasetReader(reference).shard(0), DatasetReader(tmp_path / "other").shard(0)
    for field in ("context_ims_tf_table", "robust_suction_wrench_resistance", "hand_poses", "object_context"):
        np.testing.assert_array_equal(a[field], b[field])
    before, after = a["depth_ims_tf_table"], b["depth_ims_tf_table"]
    assert not np.array_equal(before, after)
    if "sampling" in change:
        assert np.median(np.abs(before - after)) < 0.005 < np.ptp(before[0])
    centre = (slice(None), slice(15, 17), slice(15, 17))
    assert np.median(np.abs(before[centre].mean(axis=(1, 2)) - after[centre].mean(axis=(1, 2)))) < 0.005
