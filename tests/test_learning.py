"""GQ-CNN learning: architectures, streaming data, augmentation geometry, training, checkpoints, CLI.

Everything runs on a tiny synthetic dataset (256 thumbnails: positives are a flat disc at the
grasp, negatives a ridge through it; context thumbnails a shallower, wider view of the same shape)
with the compact and context nets, so the module takes seconds.
"""

from __future__ import annotations

import json
import math
import shutil

import numpy as np
import pytest
import torch
from conftest import remove_dataset_field
from typer.testing import CliRunner

from suctionbench.cli import app
from suctionbench.dataset.storage import DatasetReader, DatasetWriter, read_split, write_splits
from suctionbench.errors import InputError
from suctionbench.learning.checkpoint import CARD_NAME, STATE_NAME, WEIGHTS_NAME, GQCNNModel, load_model, save_model
from suctionbench.learning.data import (
    AUGMENT_OFF,
    CONTEXT_FIELD,
    AugmentConfig,
    NormStats,
    SplitData,
    augment,
    symmetrize,
)
from suctionbench.learning.metrics import average_precision, precision_recall_curve, top_grasp_success
from suctionbench.learning.models import (
    LRN_ALPHA_TF,
    LRN_BETA,
    LRN_BIAS,
    LRN_RADIUS,
    MaxPool2x2,
    build_model,
    count_macs,
    count_parameters,
    tf_lrn_to_torch,
)
from suctionbench.learning.train import _loss, evaluate, score_model, train
from suctionbench.learning.train_config import TrainConfig, decision_threshold
from suctionbench.sensing.noise import DepthNoiseConfig
from suctionbench.sensing.thumbnails import (
    THUMBNAIL_GQCNN,
    ThumbnailConfig,
    extract_context_thumbnails,
    extract_thumbnails,
)

N_SYNTH = 256
"""Datapoints of the synthetic dataset (4 shards of 64)."""

FAST = {"arch": "compact", "augment": AUGMENT_OFF}
"""Training settings shared by the quick runs."""


@pytest.fixture(autouse=True)
def one_thread():
    """Train on one thread: bit-reproducible timings aside, a loaded CI machine makes torch's thread
    pool spin, which slows the tiny compact steps by an order of magnitude."""
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


# ----------------------------------------------------------------------------------------------
# synthetic dataset


def synthetic_thumbnails(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Thumbnails (n, 32, 32) in metres, hand poses (n, 7) and metric (n,): even i positive (flat disc
    of radius 6-9 px at the grasp on a table at 0.6 m), odd i negative (a ridge through the grasp)."""
    yy, xx = np.mgrid[0:32, 0:32] - 15.5
    positive = np.arange(n) % 2 == 0
    top = rng.uniform(0.56, 0.59, n)
    images = np.empty((n, 32, 32), np.float32)
    for i in range(n):  # a few hundred tiny images
        if positive[i]:
            image = np.where(xx**2 + yy**2 <= rng.uniform(6, 9) ** 2, top[i], 0.6)
        else:
            theta = rng.uniform(0, np.pi)
            image = np.minimum(top[i] + 0.004 * np.abs(xx * np.cos(theta) + yy * np.sin(theta)), 0.6)
        images[i] = image + rng.normal(0, 0.0005, (32, 32))
    poses = np.zeros((n, 7), np.float32)
    poses[:, 0], poses[:, 1] = rng.uniform(100, 300, n), rng.uniform(100, 400, n)
    poses[:, 2], poses[:, 3], poses[:, 6] = top, rng.uniform(0, 0.6, n), 1.0
    metric = np.where(positive, rng.uniform(0.5, 1.0, n), rng.uniform(0.0, 0.15, n)).astype(np.float32)
    return images, poses, metric


def synthetic_context(images: np.ndarray) -> np.ndarray:
    """Context thumbnails for `synthetic_thumbnails`: the middle of the same shape at half the size (2 x 2
    block means) in a wider view of the 0.6 m table."""
    n = len(images)
    small = images.reshape(n, 32 // 2, 2, 32 // 2, 2).mean(axis=(2, 4))  # 16 x 16, then cut to the middle 10
    context = np.full((n, 32, 32), 0.6, np.float32)
    context[:, 11:21, 11:21] = small[:, 3:13, 3:13]
    return context


def write_synthetic(directory, n: int = N_SYNTH, per_shard: int = 64, seed: int = 0, grasps_per_image: int = 1
                    ) -> None:
    rng = np.random.default_rng(seed)
    images, poses, metric = synthetic_thumbnails(n, rng)
    context = synthetic_context(images)
    objects = (np.arange(n) // 32).astype(np.int32)
    writer = DatasetWriter(directory, per_shard)
    for start in range(0, n, per_shard):
        part = slice(start, start + per_shard)
        k = len(metric[part])
        writer.write_shard(start // per_shard, {
            "depth_ims_tf_table": images[part, ..., None], "context_ims_tf_table": context[part, ..., None],
            "hand_poses": poses[part], "object_context": np.zeros((k, 6), np.float32),
            "robust_suction_wrench_resistance": metric[part], "object_labels": objects[part],
            "pose_labels": np.zeros(k, np.int32),
            "image_labels": (np.arange(start, start + k) // grasps_per_image).astype(np.int32),
            "grasp_labels": np.zeros(k, np.int32), "seal_flags": np.ones(k, np.uint8),
            "wrench_resistance": (metric[part] > 0.2).astype(np.uint8),
        })
    writer.write_card({
        "config": {"label_threshold": 0.2, "label": {"cup": {"name": "default", "radius": 0.0075}}},
        "camera": {"name": "primesense", "fx": 525.0, "fy": 525.0}, "fingerprint": "synthetic", "datapoints": n,
        "positive_rate": float((metric > 0.2).mean()),
    })
    write_splits(directory, np.arange(n), objects, seed=seed)


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    directory = tmp_path_factory.mktemp("learning") / "synthetic"
    write_synthetic(directory)
    return directory


def without_context(dataset, directory):
    """A copy of `dataset` as written before datasets stored the context thumbnail."""
    shutil.copytree(dataset, directory)
    return remove_dataset_field(directory, CONTEXT_FIELD)


def train_arrays(dataset, kind: str = "image_wise", image_channels: int = 1
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Images, network poses and metric of a split, read directly (the reference for the streaming reader)."""
    data = SplitData(dataset, kind, "train", image_channels=image_channels)
    parts = [data.load_shard(s) for s in data.shards]
    return tuple(np.concatenate([getattr(p, name) for p in parts]) for name in ("images", "poses", "metric"))


def weights_of(directory) -> dict[str, torch.Tensor]:
    return load_model(directory).network.state_dict()


# ----------------------------------------------------------------------------------------------
# networks


def test_dn3_shapes_and_parameter_count():
    # conv1_1 7*7*1*64 + 64 = 3,200; conv1_2 5*5*64*64 + 64 = 102,464; conv2_1 = conv2_2 = 3*3*64*64 + 64 = 36,928;
    # fc3 (8*8*64)*1024 + 1024 = 4,195,328; pc1 2*128 + 128 = 384; fc4 (1024 + 128)*1024 + 1024 = 1,180,672;
    # fc5 1024*2 + 2 = 2,050. Sum: 5,557,954.
    model = build_model("dn3", torch.Generator().manual_seed(0))
    assert count_parameters(model) == 3_200 + 102_464 + 2 * 36_928 + 4_195_328 + 384 + 1_180_672 + 2_050 == 5_557_954
    assert model(torch.zeros(5, 1, 32, 32), torch.zeros(5, 2)).shape == (5, 2)
    # SAME padding keeps 32 -> 32 -> pool 16 -> 16 -> pool 8; MACs: convs at those sizes + the fc layers.
    convs = 32 * 32 * 49 * 64 + 32 * 32 * 25 * 64 * 64 + 2 * 16 * 16 * 9 * 64 * 64
    assert count_macs(model) == convs + 4096 * 1024 + 2 * 128 + 1152 * 1024 + 1024 * 2


def test_compact_shapes_and_parameter_count():
    # conv1 5*5*16 + 16 = 416; conv2 = conv3 = 3*3*16*16 + 16 = 2,320; fc3 (5*5*16)*64 + 64 = 25,664;
    # pc1 2*16 + 16 = 48; fc4 (64 + 16)*64 + 64 = 5,184; fc5 64*2 + 2 = 130. Sum: 36,082.
    model = build_model("compact")
    assert count_parameters(model) == 416 + 2 * 2_320 + 25_664 + 48 + 5_184 + 130 == 36_082
    assert model(torch.zeros(3, 1, 32, 32), torch.zeros(3, 2)).shape == (3, 2)
    assert count_macs(model) < count_macs(build_model("dn3")) / 100


def test_context_net_reads_the_context_channel_with_its_own_stream():
    # compact's image stream twice (2 x 30,720) + pc1 48 + fc4 (2 * 64 + 16) * 64 + 64 = 9,280 +
    # fc5 130 = 70,898. The grasp stream reads channel 0 only and the context stream channel 1 only:
    # changing one channel changes the logits, and a net whose context stream is zeroed ignores it.
    model = build_model("context", torch.Generator().manual_seed(0))
    assert model.image_channels == 2
    assert count_parameters(model) == 2 * 30_720 + 48 + 9_280 + 130 == 70_898
    # MACs: compact's image stream (its total less pc1 2*16, fc4 80*64 and fc5 64*2) twice, pc1,
    # fc4 (2 * 64 + 16) * 64 and fc5.
    stream = count_macs(build_model("compact")) - 32 - 80 * 64 - 128
    assert count_macs(model) == 2 * stream + 32 + 144 * 64 + 128
    images, poses = torch.randn(4, 2, 32, 32, generator=torch.Generator().manual_seed(1)), torch.zeros(4, 2)
    base = model(images, poses)
    for channel in (0, 1):
        changed = images.clone()
        changed[:, channel] += 1.0
        assert not torch.allclose(model(changed, poses), base), channel
    with torch.no_grad():
        for p in model.context_stream.parameters():
            p.zero_()
    changed = images.clone()
    changed[:, 1] = torch.randn(4, 32, 32)
    assert torch.equal(model(changed, poses), model(images, poses))


def test_the_wide_object_context_net_is_context_wide_reading_six_more_pose_inputs():
    # context-pose-wide: context-wide's layers (281,058 parameters) whose first pose layer (32
    # units) also reads the 6 object-context inputs: 6 x 32 = 192 weights more.
    assert count_parameters(build_model("context-pose-wide")) == 281_058 + 6 * 32 == 281_250
    assert count_parameters(build_model("context-wide")) == 281_058


def test_initialisation_is_seeded_truncated_he():
    a = build_model("dn3", torch.Generator().manual_seed(3))
    b = build_model("dn3", torch.Generator().manual_seed(3))
    for (name, pa), pb in zip(a.named_parameters(), b.parameters(), strict=True):
        assert torch.equal(pa, pb), name
    weight = a.image_stream.conv1_2[0].weight  # fan_in 5*5*64
    std = math.sqrt(2.0 / 1600)
    assert weight.abs().max() <= 2 * std + 1e-7
    assert 0.8 * std < weight.std() < std  # a normal cut at 2 sigma has std 0.88 sigma
    assert torch.count_nonzero(a.merge.fc5.bias) == 0


def test_lrn_matches_tensorflow_formula():
    x = torch.randn(2, 9, 4, 4, generator=torch.Generator().manual_seed(0)) * 30  # large enough that LRN bites
    got = tf_lrn_to_torch(LRN_RADIUS, LRN_ALPHA_TF, LRN_BETA, LRN_BIAS)(x)
    sq = x.numpy().astype(np.float64) ** 2
    want = np.empty_like(sq)
    for c in range(9):  # tf.nn.local_response_normalization, written out
        window = sq[:, max(0, c - LRN_RADIUS):c + LRN_RADIUS + 1].sum(axis=1)
        want[:, c] = x.numpy()[:, c] / (LRN_BIAS + LRN_ALPHA_TF * window) ** LRN_BETA
    np.testing.assert_allclose(got.numpy(), want, rtol=1e-5)
    assert not np.allclose(want, x.numpy(), rtol=1e-3)


@pytest.mark.parametrize("shape", [(3, 4, 28, 28), (2, 3, 9, 11)])  # even, and odd (last row/column dropped)
def test_fast_pool_is_max_pool2d_and_trains_through_it(shape):
    # Without autograd the four strided views' maxima are max_pool2d's values exactly (max is
    # exact); with autograd the pool is max_pool2d, so training's gradients are unchanged.
    x = torch.randn(*shape, generator=torch.Generator().manual_seed(1))
    x[0, 0, :4, :4] = 0.0  # ties, as after a ReLU
    pool = MaxPool2x2()
    with torch.no_grad():
        assert torch.equal(pool(x), torch.nn.functional.max_pool2d(x, 2))
    a, b = x.clone().requires_grad_(), x.clone().requires_grad_()
    (pool(a) * torch.arange(pool(a).numel()).reshape(pool(a).shape)).sum().backward()
    (torch.nn.functional.max_pool2d(b, 2) * torch.arange(pool(a).numel()).reshape(pool(a).shape)).sum().backward()
    assert torch.equal(a.grad, b.grad)


def test_unknown_arch_is_input_error():
    with pytest.raises(InputError, match="architecture 'resnet'"):
        build_model("resnet")
    with pytest.raises(InputError, match="arch"):
        TrainConfig(arch="resnet")
    assert TrainConfig(arch="context").arch == "context" and TrainConfig(arch="context-wide").arch == "context-wide"


# ----------------------------------------------------------------------------------------------
# data


def test_streaming_covers_the_split_once_in_shuffled_order(dataset):
    data = SplitData(dataset, "image_wise", "train")
    images, _, _ = train_arrays(dataset)
    assert data.num_datapoints == len(images) == len(read_split(dataset, "image_wise", "train"))
    batches = list(data.batches(50, np.random.default_rng(0), shuffle_shards=2))
    assert [len(b) for b in batches[:-1]] == [50] * (len(batches) - 1)
    streamed = np.concatenate([b.images for b in batches])
    assert len(streamed) == len(images)
    key = lambda arr: arr.reshape(len(arr), -1)[:, :4].tolist()  # noqa: E731 - rows as sortable keys
    assert sorted(key(streamed)) == sorted(key(images))  # every datapoint exactly once
    assert key(streamed) != key(images)  # ... not in index order
    in_order = np.concatenate([b.images for b in data.batches(50)])
    np.testing.assert_array_equal(in_order, images)


def test_reading_threads_do_not_change_the_batches(dataset):
    # Threads only read a pool's shards at once; the pool is assembled in the shards' order, so the
    # shuffled batches are the same datapoints in the same order for any thread count.
    def streamed(threads: int) -> np.ndarray:
        data = SplitData(dataset, "image_wise", "train", image_channels=2, load_threads=threads)
        return np.concatenate([b.images for b in data.batches(50, np.random.default_rng(5), shuffle_shards=3)])

    one = streamed(1)
    np.testing.assert_array_equal(streamed(3), one)
    np.testing.assert_array_equal(streamed(8), one)
    with pytest.raises(InputError, match="load_threads"):
        TrainConfig(load_threads=0)


def test_normalisation_statistics(dataset):
    images, poses, _ = train_arrays(dataset)
    stats = SplitData(dataset, "image_wise", "train").compute_stats()
    assert stats.count == len(images)
    assert stats.image_mean == pytest.approx(images.astype(np.float64).mean(), rel=1e-12)
    assert stats.image_std == pytest.approx(images.astype(np.float64).std(), rel=1e-9)
    np.testing.assert_allclose(stats.pose_mean, poses.astype(np.float64).mean(axis=0), rtol=1e-12)
    np.testing.assert_allclose(stats.pose_std, poses.astype(np.float64).std(axis=0), rtol=1e-9)
    assert NormStats.from_dict(stats.to_dict()) == stats


def test_two_channel_split_reads_the_context_field_with_per_channel_statistics(dataset):
    one, two = train_arrays(dataset), train_arrays(dataset, image_channels=2)
    assert one[0].shape[1:] == (1, 32, 32) and two[0].shape[1:] == (2, 32, 32)
    np.testing.assert_array_equal(two[0][:, :1], one[0])
    np.testing.assert_array_equal(two[1], one[1])
    np.testing.assert_array_equal(two[2], one[2])
    assert not np.allclose(two[0][:, 0], two[0][:, 1])  # the context channel is the context field
    stats = SplitData(dataset, "image_wise", "train", image_channels=2).compute_stats()
    wide = two[0].astype(np.float64)
    assert stats.image_channels == 2
    np.testing.assert_allclose(stats.image_mean, wide.mean(axis=(0, 2, 3)), rtol=1e-12)
    np.testing.assert_allclose(stats.image_std, wide.std(axis=(0, 2, 3)), rtol=1e-9)
    assert stats.image_std[0] != pytest.approx(stats.image_std[1], rel=0.05)
    # channel 0's statistics are the one-channel ones (up to the summation order of two columns)
    single = SplitData(dataset, "image_wise", "train").compute_stats()
    assert (stats.image_mean[0], stats.image_std[0]) == pytest.approx((single.image_mean, single.image_std),
                                                                      rel=1e-12)
    assert (stats.pose_mean, stats.pose_std) == (single.pose_mean, single.pose_std)


def test_dataset_without_the_context_field(dataset, tmp_path):
    """A dataset written before the context thumbnail was stored still trains one-channel nets; the
    context nets are refused with the dataset and the missing field named."""
    old = without_context(dataset, tmp_path / "old")
    reader = DatasetReader(old)
    assert reader.verify() == [] and not reader.has_field(CONTEXT_FIELD) and DatasetReader(dataset).has_field(
        CONTEXT_FIELD)
    np.testing.assert_array_equal(train_arrays(old)[0], train_arrays(dataset)[0])
    for make in (lambda: SplitData(old, "image_wise", "train", image_channels=2),
                 lambda: train(old, tmp_path / "out", TrainConfig(arch="context", epochs=1, augment=AUGMENT_OFF))):
        with pytest.raises(InputError) as info:
            make()
        assert str(old) in str(info.value) and CONTEXT_FIELD in str(info.value)
    assert not (tmp_path / "out").exists()
    result = CliRunner().invoke(app, ["train", "--dataset", str(old), "--out", str(tmp_path / "cli"), "--arch",
                                      "context", "--epochs", "1", "--json"])
    assert result.exit_code == 2 and CONTEXT_FIELD in json.loads(result.stdout.strip().splitlines()[-1])["error"]


def test_subset_is_seeded(dataset):
    a = SplitData(dataset, "object_wise", "train", max_datapoints=40, subset_rng=np.random.default_rng(1))
    b = SplitData(dataset, "object_wise", "train", max_datapoints=40, subset_rng=np.random.default_rng(1))
    assert a.num_datapoints == 40
    np.testing.assert_array_equal(np.concatenate([x.images for x in a.batches(64)]),
                                  np.concatenate([x.images for x in b.batches(64)]))


def test_object_subset_keeps_whole_objects_then_thins_them(dataset):
    # --max-objects: every kept datapoint belongs to one of N training objects, every datapoint of
    # those objects is kept (before --max-datapoints thins them), the draw is seeded, and with both
    # limits the count is the datapoint limit while the objects stay those N.
    whole = SplitData(dataset, "object_wise", "train")
    objects_of = lambda data: data.values("object_labels")  # noqa: E731
    per_object = np.bincount(objects_of(whole))
    a = SplitData(dataset, "object_wise", "train", max_objects=3, subset_rng=np.random.default_rng(4))
    kept = np.unique(objects_of(a))
    assert len(kept) == 3 and set(kept) <= set(np.unique(objects_of(whole)))
    assert a.num_datapoints == per_object[kept].sum()
    again = SplitData(dataset, "object_wise", "train", max_objects=3, subset_rng=np.random.default_rng(4))
    np.testing.assert_array_equal(objects_of(again), objects_of(a))
    thinned = SplitData(dataset, "object_wise", "train", max_objects=3, max_datapoints=40,
                        subset_rng=np.random.default_rng(4))
    assert thinned.num_datapoints == 40 and set(np.unique(objects_of(thinned))) <= set(kept)
    everything = SplitData(dataset, "object_wise", "train", max_objects=10**6)
    assert everything.num_datapoints == whole.num_datapoints


def test_object_pattern_keeps_the_matching_objects_only(dataset, tmp_path):
    # --train-objects: the datapoints kept are exactly those of the objects whose card key matches
    # the shell pattern (here every second object is a "household" one); a pattern that matches no
    # object, or a dataset whose card names none, is an InputError naming the option.
    named = tmp_path / "named"
    shutil.copytree(dataset, named)
    card = json.loads((named / "config.json").read_text())
    count = N_SYNTH // 32
    card["objects"] = [f"train/train_{i:05d}_{'household' if i % 2 == 0 else 'blob'}" for i in range(count)]
    (named / "config.json").write_text(json.dumps(card))
    whole = SplitData(named, "object_wise", "train")
    labels = whole.values("object_labels")
    kept = SplitData(named, "object_wise", "train", objects_matching="*household*")
    assert set(np.unique(kept.values("object_labels"))) == {i for i in np.unique(labels) if i % 2 == 0}
    assert kept.num_datapoints == int(np.sum(labels % 2 == 0))
    with pytest.raises(InputError, match="--train-objects '\\*nothing\\*': matches none"):
        SplitData(named, "object_wise", "train", objects_matching="*nothing*")
    with pytest.raises(InputError, match="beyond its card's 0 objects"):
        SplitData(dataset, "object_wise", "train", objects_matching="*household*")


def test_split_subset_draws_from_the_split_itself(dataset):
    # The fit check's subset: datapoints of the (possibly already subsampled) training split only,
    # the requested count of them, each once, seeded, in whole shards but the last.
    train_split = SplitData(dataset, "object_wise", "train", max_datapoints=60, subset_rng=np.random.default_rng(2))
    part = train_split.subset(25, np.random.default_rng(3))
    rows = lambda data: {(k, int(i)) for k, v in data._local.items() for i in v}  # noqa: E731
    assert part.num_datapoints == 25 and rows(part) <= rows(train_split) and len(rows(part)) == 25
    whole = [k for k in part._local if len(part._local[k]) == len(train_split._local[k])]
    assert len(whole) >= len(part._local) - 1  # every shard it reads is used in full, bar one
    again = train_split.subset(25, np.random.default_rng(3))
    assert rows(again) == rows(part)
    assert train_split.subset(1000, np.random.default_rng(0)).num_datapoints == 60  # at most the whole split
    np.testing.assert_array_equal(np.concatenate([b.metric for b in part.batches(64)]),
                                  np.concatenate([b.metric for b in again.batches(64)]))


def scene_depth(height: int = 220, width: int = 260) -> np.ndarray:
    """A depth image with no symmetry: a tilted table with two bumps of different sizes."""
    v, u = np.mgrid[0:height, 0:width].astype(np.float64)
    depth = 0.65 + 0.0004 * u - 0.0002 * v
    depth -= 0.03 * np.exp(-((u - 140) ** 2 + (v - 100) ** 2) / (2 * 12**2))
    depth -= 0.015 * np.exp(-((u - 110) ** 2 + (v - 130) ** 2) / (2 * 5**2))
    return depth.astype(np.float32)


@pytest.mark.parametrize("mirror", ["columns", "rows"])
@pytest.mark.parametrize(("flip_rows", "flip_cols"), [(False, False), (False, True), (True, False), (True, True)])
def test_symmetrisation_equals_thumbnail_of_mirrored_scene(mirror, flip_rows, flip_cols):
    """Flipping a thumbnail is what `extract_thumbnails` cuts from the mirrored (or the same) scene, and the
    signed angle is negated exactly when the thumbnail's down axis then points against the approach."""
    depth = scene_depth()
    height, width = depth.shape
    pixel, theta, tilt = np.array([127.3, 109.6]), 0.7, 0.4  # grasp (u, v), approach image angle, tilt
    thumb = extract_thumbnails(depth, pixel[None], np.array([theta]))[0]
    got, angle = symmetrize(torch.from_numpy(thumb)[None, None], torch.tensor([tilt]),
                            torch.tensor([flip_rows]), torch.tensor([flip_cols]))

    # An odd number of flips is a mirror image of the scene; the grasp and its approach mirror with it.
    mirrored = flip_rows != flip_cols
    scene, grasp, approach = depth, pixel, theta
    if mirrored and mirror == "columns":
        scene, grasp, approach = depth[:, ::-1], np.array([width - 1 - pixel[0], pixel[1]]), math.pi - theta
    elif mirrored:
        scene, grasp, approach = depth[::-1], np.array([pixel[0], height - 1 - pixel[1]]), -theta
    # Flipped rows: the thumbnail's down axis points against the (mirrored) approach's image.
    axis = approach + math.pi if flip_rows else approach
    want = extract_thumbnails(np.ascontiguousarray(scene), grasp[None], np.array([axis]))[0]
    np.testing.assert_allclose(got[0, 0].numpy(), want, atol=2e-6)
    assert not np.allclose(want, thumb, atol=1e-4) or not (flip_rows or flip_cols)
    assert float(angle[0]) == pytest.approx(-tilt if flip_rows else tilt)


def test_augmentation_signs_are_per_sample_and_reproducible():
    thumb = torch.from_numpy(extract_thumbnails(scene_depth(), np.array([[127.3, 109.6]]), np.array([0.7]))[0])
    images = thumb.expand(64, 1, 32, 32).clone()
    poses = torch.stack([torch.full((64,), 0.6), torch.linspace(0.1, 0.5, 64)], dim=1)
    config = AugmentConfig(noise=False, symmetrize=True)
    out, out_poses = augment(images, poses, torch.Generator().manual_seed(5), config)
    rows_flipped = torch.tensor([torch.equal(o[0], thumb.flip(0)) or torch.equal(o[0], thumb.flip(0).flip(1))
                                 for o in out])
    np.testing.assert_array_equal(out_poses[:, 1].numpy(),
                                  torch.where(rows_flipped, -poses[:, 1], poses[:, 1]).numpy())
    assert 10 < int(rows_flipped.sum()) < 54  # both signs in one batch (gqcnn flipped whole batches)
    again, _ = augment(images, poses, torch.Generator().manual_seed(5), config)
    assert torch.equal(out, again)
    noisy, noisy_poses = augment(images, poses, torch.Generator().manual_seed(5), AugmentConfig(symmetrize=False))
    assert torch.equal(noisy_poses, poses) and not torch.equal(noisy, images)
    assert (noisy - images).abs().max() < 0.1  # Gamma ~3 % of 0.6 m plus a few mm of field


def two_channel_thumbnails(count: int) -> tuple[torch.Tensor, torch.Tensor]:
    """`count` copies of (grasp, context) thumbnails of the asymmetric scene (neither has a mirror or
    180-degree symmetry), and pose vectors with distinct angles."""
    depth, pixel, theta = scene_depth(), np.array([[127.3, 109.6]]), np.array([0.7])
    grasp = extract_thumbnails(depth, pixel, theta)[0]
    context = extract_context_thumbnails(depth, pixel, theta, ThumbnailConfig(crop_size=160, out_size=32))[0]
    images = torch.from_numpy(np.stack([grasp, context]))[None].repeat(count, 1, 1, 1)
    poses = torch.stack([torch.full((count,), 0.6), torch.linspace(0.1, 0.5, count)], dim=1)
    return images, poses


def which_flip(image: torch.Tensor, original: torch.Tensor) -> tuple[bool, bool]:
    """(rows flipped, columns flipped) that turn `original` into `image` (2-D); AssertionError if none does."""
    matches = [(r, c) for r in (False, True) for c in (False, True)
               if torch.equal(image, original.flip(0) if r and not c else original.flip(1) if c and not r
                              else original.flip(0).flip(1) if r else original)]
    assert len(matches) == 1, matches
    return matches[0]


def test_symmetrisation_flips_both_channels_together():
    images, poses = two_channel_thumbnails(64)
    out, out_poses = augment(images, poses, torch.Generator().manual_seed(11), AugmentConfig(noise=False))
    flips = [which_flip(o[0], images[0, 0]) for o in out]
    assert [which_flip(o[1], images[0, 1]) for o in out] == flips  # the context channel went the same way
    assert len(set(flips)) == 4  # all four symmetries occur in the batch
    rows = torch.tensor([r for r, _ in flips])
    np.testing.assert_array_equal(out_poses[:, 1].numpy(), torch.where(rows, -poses[:, 1], poses[:, 1]).numpy())


def test_noise_one_gamma_per_image_field_on_the_grasp_channel_only():
    """Both channels come from one depth image: the same multiplicative factor scales both, the
    additive field (grasp thumbnail's grid) reaches channel 0 only. The draws do not depend on the
    channel count, so channel 0 is exactly what the one-channel augmentation gives."""
    images, poses = two_channel_thumbnails(32)
    config = AugmentConfig(gp_prob=1.0, symmetrize=False)
    out, _ = augment(images, poses, torch.Generator().manual_seed(3), config)
    alone, _ = augment(images[:, :1], poses, torch.Generator().manual_seed(3), config)
    assert torch.equal(out[:, :1], alone)
    alpha = out[:, 1] / images[:, 1]  # channel 1: alpha * depth, nothing added
    assert torch.allclose(alpha, alpha[:, :1, :1].expand_as(alpha), rtol=1e-5, atol=0)
    assert alpha[:, 0, 0].std() > 0.01  # Gamma(1000, 0.001): ~3 % per image
    field = out[:, 0] - alpha[:, :1, :1] * images[:, 0]  # channel 0: the same alpha plus the field
    assert field.abs().amax(dim=(1, 2)).min() > 1e-3
    # without the field (no GP), channel 0 is the same alpha times its depth
    scaled, _ = augment(images, poses, torch.Generator().manual_seed(3), AugmentConfig(gp_prob=0.0, symmetrize=False))
    torch.testing.assert_close(scaled[:, 0] / images[:, 0], scaled[:, 1, :1, :1].expand(-1, 32, 32) /
                               images[:, 1, :1, :1], rtol=1e-5, atol=0)
    quiet = AugmentConfig(gp_prob=1.0, symmetrize=False, depth_noise=DepthNoiseConfig(gp_sigma=0.0))
    np.testing.assert_array_equal(augment(images, poses, torch.Generator().manual_seed(3), quiet)[0][:, 1].numpy(),
                                  out[:, 1].numpy())


# ----------------------------------------------------------------------------------------------
# metrics


def test_average_precision_by_hand():
    labels, scores = np.array([1, 0, 1, 0]), np.array([0.9, 0.8, 0.7, 0.1])
    assert average_precision(labels, scores) == pytest.approx(0.5 * 1 + 0.5 * 2 / 3)
    precision, recall, thresholds = precision_recall_curve(np.array([1, 0, 1]), np.array([0.5, 0.5, 0.2]))
    np.testing.assert_allclose(precision, [0.5, 2 / 3])  # the tie is one operating point
    np.testing.assert_allclose(recall, [0.5, 1.0])
    np.testing.assert_allclose(thresholds, [0.5, 0.2])
    assert math.isnan(average_precision(np.zeros(3), np.ones(3)))


def test_top_grasp_success_by_hand():
    # image 7: top score 0.9 is a negative -> 0; image 3: top 0.8 shared by a positive and a negative
    # (a tie, picked at random) -> 0.5; image 5 has one grasp, nothing to rank: left out.
    groups = np.array([7, 7, 7, 3, 3, 3, 5])
    labels = np.array([0, 1, 1, 1, 0, 0, 1])
    scores = np.array([0.9, 0.2, 0.8, 0.8, 0.8, 0.1, 0.99])
    got = top_grasp_success(labels, scores, groups)
    assert got["images"] == 2
    assert got["top_grasp_success"] == pytest.approx((0 + 0.5) / 2)
    assert got["top_grasp_ceiling"] == 1.0  # both images hold a positive grasp
    assert got["top_grasp_random"] == pytest.approx((2 / 3 + 1 / 3) / 2)
    # a perfect ranking reaches the ceiling
    assert top_grasp_success(labels, labels + 0.1 * np.arange(7) / 7, groups)["top_grasp_success"] == 1.0
    assert math.isnan(top_grasp_success(labels[:1], scores[:1], groups[:1])["top_grasp_success"])


# ----------------------------------------------------------------------------------------------
# training


def test_compact_overfits_the_synthetic_set(dataset, tmp_path):
    metrics = train(dataset, tmp_path, TrainConfig(epochs=20, **FAST))
    assert metrics["epochs"] == 20 and metrics["num_train"] + metrics["num_val"] == N_SYNTH
    model = load_model(tmp_path)
    images, poses, metric = train_arrays(dataset)
    accuracy = np.mean((model.predict(images, poses) > 0.5) == (metric > 0.2))
    assert accuracy >= 0.99
    assert metrics["val_ap"] > 0.9
    card = json.loads((tmp_path / CARD_NAME).read_text())
    assert card["training"]["status"] == "complete" and len(card["history"]) == 20
    assert card["dataset"]["camera"]["name"] == "primesense" and card["dataset"]["cup"]["name"] == "default"
    # the card says how the images were made, and the model reads its grasps the same way
    assert card["dataset"]["noise_model"] == "paper" and model.thumbnail == THUMBNAIL_GQCNN
    assert card["label"]["threshold"] == 0.2 and card["versions"]["torch"] == torch.__version__
    assert (tmp_path / "precision_recall.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_soft_target_is_the_cross_entropy_against_the_metric():
    # With targets in {0, 1} the soft loss is the binary one. For a metric m in (0, 1) the loss
    # -(m log q + (1 - m) log(1 - q)) has its minimum at q = m (its derivative in the logit is q - m),
    # so its gradient vanishes where the softmax equals the metric, and nowhere else.
    logits = torch.tensor([[0.3, -1.2], [2.0, 0.5], [-0.4, 0.9]])
    hard = np.array([0.0, 1.0, 1.0])
    assert torch.allclose(_loss(logits, hard, torch.tensor([0, 1, 1]), "soft"),
                          _loss(logits, hard, torch.tensor([0, 1, 1]), "binary"))
    metric = np.array([0.25, 0.9, 0.6])
    at_metric = torch.log(torch.tensor(np.column_stack([1 - metric, metric]), dtype=torch.float32)).requires_grad_()
    _loss(at_metric, metric, torch.tensor([1, 1, 1]), "soft").backward()
    assert float(at_metric.grad.abs().max()) < 1e-6
    shifted = (at_metric.detach() + torch.tensor([0.0, 0.5])).requires_grad_()
    _loss(shifted, metric, torch.tensor([1, 1, 1]), "soft").backward()
    assert float(shifted.grad.abs().min()) > 1e-3


class _ConstantQ(torch.nn.Module):
    """A network that says q for every grasp."""

    def __init__(self, q: float):
        super().__init__()
        self.logit = math.log(q / (1 - q))

    def forward(self, images, poses):
        return torch.stack([torch.zeros(len(images)), torch.full((len(images),), self.logit)], dim=1)


def test_a_soft_network_is_scored_at_the_labels_own_threshold(dataset):
    # A soft network's q estimates the metric (the soft cross-entropy is least at q = E[metric]),
    # so "positive" (metric > 0.2) for it is q > 0.2; a binary network's q estimates P(metric >
    # 0.2), so q > 0.5. A network saying q = 0.3 everywhere thus calls every grasp positive when
    # it is soft (accuracy = the positive rate) and every grasp negative when binary (1 - rate).
    assert decision_threshold("soft", 0.2) == 0.2 and decision_threshold("binary", 0.2) == 0.5
    val = SplitData(dataset, "image_wise", "val")
    stats = val.compute_stats()
    soft = evaluate(_ConstantQ(0.3), val, stats, 0.2, torch.device("cpu"), "soft")
    binary = evaluate(_ConstantQ(0.3), val, stats, 0.2, torch.device("cpu"), "binary")
    assert 0 < soft["positive_rate"] < 1
    assert soft["accuracy"] == pytest.approx(soft["positive_rate"])
    assert binary["accuracy"] == pytest.approx(1 - binary["positive_rate"]) == soft["accuracy_at_half"]


def test_soft_target_learns_the_expected_metric(dataset, tmp_path):
    # The synthetic positives' metric is U(0.5, 1) whatever the image (synthetic_thumbnails), so the
    # best a net can say of an unseen positive is the conditional mean, 0.75: the minimiser of the
    # expected soft cross-entropy E[-(m log q + (1 - m) log(1 - q))] is q = E[m]. A binary target
    # would drive the same q towards 1.
    metrics = train(dataset, tmp_path, TrainConfig(epochs=20, target="soft", **FAST))
    assert metrics["val_ap"] > 0.9  # scored against the binary label, as the binary target's run
    val = SplitData(dataset, "image_wise", "val")
    parts = [val.load_shard(s) for s in val.shards]
    images, poses, metric = (np.concatenate([getattr(p, k) for p in parts]) for k in ("images", "poses", "metric"))
    q = load_model(tmp_path).predict(images, poses)
    positive = metric > 0.2
    assert abs(float(q[positive].mean()) - 0.75) < 0.1 and float(q[~positive].mean()) < 0.2
    card = json.loads((tmp_path / CARD_NAME).read_text())
    assert card["label"]["target"] == "soft" and card["training"]["config"]["target"] == "soft"
    with pytest.raises(InputError, match="target"):
        TrainConfig(target="hinge")


def _strip_timing(metrics: dict) -> dict:
    """Metrics without wall-clock figures and output paths, which differ between equal runs."""
    return {k: v for k, v in metrics.items()
            if "seconds" not in k and "per_s" not in k and k not in ("out", "model", "pr_curve")}


def test_same_seed_same_model(dataset, tmp_path):
    config = TrainConfig(arch="compact", epochs=1, seed=7)  # augmentation on: noise and flips are seeded too
    first, second = train(dataset, tmp_path / "a", config), train(dataset, tmp_path / "b", config)
    assert _strip_timing(first) == _strip_timing(second)
    for (name, a), b in zip(weights_of(tmp_path / "a").items(), weights_of(tmp_path / "b").values(), strict=True):
        assert torch.equal(a, b), name
    train(dataset, tmp_path / "c", TrainConfig(arch="compact", epochs=1, seed=8))
    key = "merge.fc5.weight"
    assert not torch.equal(weights_of(tmp_path / "a")[key], weights_of(tmp_path / "c")[key])


def test_init_starts_from_the_given_model(dataset, tmp_path):
    # Fine-tuning: with a vanishing learning rate (1e-12) and no weight decay, SGD moves no weight
    # measurably, so a run started from model A ends with A's weights (and A's normalisation);
    # a run from random weights does not.
    train(dataset, tmp_path / "a", TrainConfig(epochs=1, seed=3, **FAST))
    still = {"learning_rate": 1e-12, "weight_decay": 0.0, "momentum": 0.0}
    train(dataset, tmp_path / "tuned", TrainConfig(epochs=1, seed=4, init=str(tmp_path / "a"), **still, **FAST))
    train(dataset, tmp_path / "fresh", TrainConfig(epochs=1, seed=4, **still, **FAST))
    a, tuned, fresh = (weights_of(tmp_path / n) for n in ("a", "tuned", "fresh"))
    for name in a:
        assert torch.allclose(a[name], tuned[name], atol=1e-9), name
    assert not torch.allclose(a["merge.fc5.weight"], fresh["merge.fc5.weight"])
    with pytest.raises(InputError, match="--init"):
        train(dataset, tmp_path / "wrong", TrainConfig(arch="dn3", epochs=1, init=str(tmp_path / "a")))


def test_init_grows_a_narrower_model_into_a_wider_arch(dataset, tmp_path):
    # --init with a narrower model of the same layout grows it (suctionbench.learning.grow): with a
    # vanishing learning rate the wider model predicts what its parent predicts (the growth keeps
    # the function; SGD at 1e-12 moves nothing measurably), and it keeps the parent's normalisation.
    train(dataset, tmp_path / "a", TrainConfig(arch="context-pose", epochs=1, seed=3))
    still = {"learning_rate": 1e-12, "weight_decay": 0.0, "momentum": 0.0}
    metrics = train(dataset, tmp_path / "grown", TrainConfig(arch="context-pose-wide", epochs=1, seed=4,
                                                             init=str(tmp_path / "a"), **still))
    assert metrics["parameters"] == 281_250
    parent, grown = load_model(tmp_path / "a"), load_model(tmp_path / "grown")
    assert grown.stats.to_dict() == parent.stats.to_dict()
    data = SplitData(dataset, "image_wise", "val", image_channels=2, object_context=True)
    batch = data.load_shard(data.shards[0])
    np.testing.assert_allclose(grown.predict(batch.images, batch.poses), parent.predict(batch.images, batch.poses),
                               atol=1e-5)
    with pytest.raises(InputError, match="cannot grow into --arch context-pose .layer image_stream.conv1.0 is narr"):
        train(dataset, tmp_path / "shrunk", TrainConfig(arch="context-pose", epochs=1, init=str(tmp_path / "grown")))


def test_resume_equals_uninterrupted_run(dataset, tmp_path):
    config = TrainConfig(arch="compact", epochs=3, seed=2, shuffle_shards=2)
    straight = train(dataset, tmp_path / "straight", config)
    train(dataset, tmp_path / "resumed", TrainConfig(arch="compact", epochs=1, seed=2, shuffle_shards=2))
    resumed = train(dataset, tmp_path / "resumed", config)
    assert resumed["resumed_from_epoch"] == 1 and resumed["epochs_trained_now"] == 2
    assert _strip_timing({**straight, "resumed_from_epoch": 1, "epochs_trained_now": 2}) == _strip_timing(resumed)
    for (name, a), b in zip(weights_of(tmp_path / "straight").items(), weights_of(tmp_path / "resumed").values(),
                            strict=True):
        assert torch.equal(a, b), name
    done = train(dataset, tmp_path / "resumed", config)  # nothing left to do
    assert done["epochs_trained_now"] == 0 and done["val_accuracy"] == resumed["val_accuracy"]
    with pytest.raises(InputError, match="differs in: config.learning_rate"):
        train(dataset, tmp_path / "resumed", TrainConfig(arch="compact", epochs=3, seed=2, learning_rate=0.1))


def test_context_net_trains_saves_reloads_and_predicts(dataset, tmp_path):
    metrics = train(dataset, tmp_path, TrainConfig(arch="context", epochs=3, seed=1))  # augmentation on
    assert metrics["arch"] == "context" and metrics["parameters"] == 70_898 and math.isfinite(metrics["val_ap"])
    assert 0 <= metrics["fit_accuracy"] <= 1 and math.isfinite(metrics["fit_ap"])  # the un-augmented fit check
    card = json.loads((tmp_path / CARD_NAME).read_text())
    assert card["image_channels"] == 2 and card["inputs"]["images"].startswith("(N, 2, 32, 32)")
    assert len(card["normalisation"]["image_mean"]) == 2 and len(card["normalisation"]["image_std"]) == 2
    model = load_model(tmp_path)
    assert model.image_channels == 2 and model.stats.image_channels == 2
    images, poses, metric = train_arrays(dataset, image_channels=2)
    q = model.predict(images, poses)
    assert q.shape == (len(metric),) and np.all((q >= 0) & (q <= 1))
    # the same network in the trainer's validation pass and through the reloaded model
    from suctionbench.learning.train import evaluate

    val = SplitData(dataset, "image_wise", "val", image_channels=2)
    scores = evaluate(model.network, val, model.stats, 0.2, torch.device("cpu"))["scores"]
    val_images = np.concatenate([b.images for b in val.batches(64)])
    val_poses = np.concatenate([b.poses for b in val.batches(64)])
    np.testing.assert_allclose(model.predict(val_images, val_poses), scores, rtol=1e-6, atol=1e-7)
    assert card["metrics"]["val_ap"] == metrics["val_ap"]
    with pytest.raises(InputError, match=r"expected \(N, 2, 32, 32\)"):
        model.predict(images[:, 0], poses)
    # resuming continues the two-channel run
    more = train(dataset, tmp_path, TrainConfig(arch="context", epochs=4, seed=1))
    assert more["resumed_from_epoch"] == 3 and more["epochs_trained_now"] == 1


def test_object_context_net_reads_the_field_into_its_pose_stream(dataset, tmp_path):
    # context-pose: the context net whose pose vector is 2 + 6 long, the dataset's object context
    # appended in storage order; the model card and predict() ask for (N, 8).
    metrics = train(dataset, tmp_path, TrainConfig(arch="context-pose", epochs=1, seed=1))
    assert metrics["parameters"] == 70_898 + 6 * 16 and math.isfinite(metrics["val_ap"])
    card = json.loads((tmp_path / CARD_NAME).read_text())
    assert card["inputs"]["poses"].startswith("(N, 8)") and len(card["normalisation"]["pose_mean"]) == 8
    model = load_model(tmp_path)
    assert model.pose_dim == 8
    data = SplitData(dataset, "image_wise", "train", image_channels=2, object_context=True)
    batch = data.load_shard(data.shards[0])
    assert batch.poses.shape[1] == 8 and not batch.poses[:, 2:].any()  # the fixture's zeros
    q = model.predict(batch.images, batch.poses)
    assert np.all((q >= 0) & (q <= 1))
    with pytest.raises(InputError, match=r"expected \(\d+, 8\)"):
        model.predict(batch.images, batch.poses[:, :2])


def test_learning_rate_staircase(dataset, tmp_path):
    # 205 training datapoints, batch 64: 4 steps an epoch; decay every 0.5 * 205 = 102.5 examples seen.
    train(dataset, tmp_path, TrainConfig(epochs=2, decay_epochs=0.5, decay_rate=0.5, **FAST))
    history = json.loads((tmp_path / CARD_NAME).read_text())["history"]
    assert [h["lr"] for h in history] == [0.01, 0.01 * 0.5 ** math.floor(4 * 64 / 102.5)]


def test_history_scores_each_views_top_grasp(tmp_path):
    # After every epoch the trainer records the label of each held-out view's top-scored grasp (what
    # the policies act on): the same figure `model score` computes from the saved model on the same
    # split, so the two agree; four grasps per view (32 per object, object-wise split: a view's grasps
    # stay together), so every view is ranked.
    data_dir = tmp_path / "views"
    write_synthetic(data_dir, grasps_per_image=4)
    out = tmp_path / "run"
    train(data_dir, out, TrainConfig(epochs=1, split="object_wise", **FAST))
    recorded = json.loads((out / CARD_NAME).read_text())["history"][-1]["val_top_grasp_success"]
    model = load_model(out)
    data = model.split_data(data_dir, "object_wise", "val")
    scored = score_model(model, data, 0.2)
    expected = top_grasp_success(scored["labels"], scored["scores"], data.values("image_labels"))
    assert expected["images"] == data.num_datapoints // 4
    assert recorded == pytest.approx(expected["top_grasp_success"]) and 0.0 <= recorded <= 1.0


# ----------------------------------------------------------------------------------------------
# checkpoints


def test_checkpoint_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    stats = NormStats(0.58, 0.01, (0.58, 0.3), (0.01, 0.2), count=10)
    model = GQCNNModel(build_model("compact", torch.Generator().manual_seed(1)), stats, {"arch": "compact"})
    images = rng.uniform(0.55, 0.6, (300, 32, 32)).astype(np.float32)
    poses = np.column_stack([rng.uniform(0.55, 0.6, 300), rng.uniform(0, 0.6, 300)]).astype(np.float32)
    before = model.predict(images, poses, batch_size=128)
    save_model(tmp_path, model)
    loaded = load_model(tmp_path)
    after = loaded.predict(images[..., None], poses)
    np.testing.assert_array_equal(before, after)
    assert before.shape == (300,) and ((before >= 0) & (before <= 1)).all()
    assert loaded.card["normalisation"] == stats.to_dict() and loaded.arch == "compact"


def test_normalisation_statistics_per_channel_and_scalar_compatibility():
    two = NormStats((0.58, 0.6), (0.01, 0.004), (0.58, 0.3), (0.01, 0.2), count=10)
    data = two.to_dict()
    assert data["image_mean"] == [0.58, 0.6] and data["image_std"] == [0.01, 0.004]
    assert NormStats.from_dict(json.loads(json.dumps(data))) == two and two.image_channels == 2
    images = torch.tensor([0.59, 0.61]).reshape(1, 2, 1, 1).expand(3, 2, 4, 4)
    normalised, _ = two.normalise(images, torch.zeros(3, 2))
    torch.testing.assert_close(normalised[:, 0], torch.full((3, 4, 4), 1.0))  # (0.59 - 0.58) / 0.01
    torch.testing.assert_close(normalised[:, 1], torch.full((3, 4, 4), 2.5))  # (0.61 - 0.6) / 0.004
    with pytest.raises(ValueError, match="2 channel"):
        two.normalise(images[:, :1], torch.zeros(3, 2))
    # one channel: scalars in and out, however given, and the card form every model has used
    one = NormStats(0.58, 0.01, (0.58, 0.3), (0.01, 0.2), count=10)
    assert NormStats((0.58,), [0.01], (0.58, 0.3), (0.01, 0.2), count=10) == one and one.image_channels == 1
    assert one.to_dict() == {"image_mean": 0.58, "image_std": 0.01, "pose_mean": [0.58, 0.3],
                             "pose_std": [0.01, 0.2], "count": 10}
    x = torch.rand(5, 1, 32, 32, generator=torch.Generator().manual_seed(0)) * 0.1 + 0.55
    assert torch.equal(one.normalise(x, torch.zeros(5, 2))[0], (x - 0.58) / 0.01)
    # a one-channel card as models trained before the context stream keep it (the shipped compact
    # model of 2026-11, its statistics rounded)
    old = {"image_mean": 0.5806, "image_std": 0.0736, "pose_mean": [0.5553, 0.5045], "pose_std": [0.0685, 0.4449],
           "count": 160007}
    assert NormStats.from_dict(old).to_dict() == old
    for bad in ({**data, "image_std": [0.01]}, {**data, "image_std": [0.01, 0.0]}, {**data, "image_mean": "x"},
                {**data, "image_mean": []}):
        with pytest.raises(InputError, match="normalisation"):
            NormStats.from_dict(bad)


def test_checkpoint_round_trip_two_channels(tmp_path):
    rng = np.random.default_rng(0)
    stats = NormStats((0.58, 0.6), (0.01, 0.004), (0.58, 0.3), (0.01, 0.2), count=10)
    model = GQCNNModel(build_model("context", torch.Generator().manual_seed(1)), stats, {"arch": "context"})
    images = rng.uniform(0.55, 0.6, (70, 2, 32, 32)).astype(np.float32)
    poses = np.column_stack([rng.uniform(0.55, 0.6, 70), rng.uniform(0, 0.6, 70)]).astype(np.float32)
    before = model.predict(images, poses, batch_size=32)
    save_model(tmp_path / "m", model)
    loaded = load_model(tmp_path / "m")
    # Same batching as `before`: a batch of another size may take another BLAS path (last-bit
    # differences), which is not what a checkpoint round trip is about.
    np.testing.assert_array_equal(loaded.predict(images, poses, batch_size=32), before)
    assert loaded.card["image_channels"] == 2 and loaded.stats == stats
    with pytest.raises(InputError, match="image channel"):  # a one-channel normalisation for a two-channel net
        GQCNNModel(build_model("context"), NormStats(0.58, 0.01, (0.58, 0.3), (0.01, 0.2)), {"arch": "context"})
    card = json.loads((tmp_path / "m" / CARD_NAME).read_text())
    card["image_channels"] = 1
    (tmp_path / "m" / CARD_NAME).write_text(json.dumps(card))
    with pytest.raises(InputError, match="image channel"):
        load_model(tmp_path / "m")


def test_bad_inputs(dataset, tmp_path):
    with pytest.raises(InputError, match="not a directory"):
        train(tmp_path / "missing", tmp_path / "out", TrainConfig(**FAST))
    with pytest.raises(InputError, match="not a directory"):
        load_model(tmp_path / "missing")
    with pytest.raises(InputError, match="device"):
        TrainConfig(device="tpu")

    stats = NormStats(0.58, 0.01, (0.58, 0.3), (0.01, 0.2))
    model = GQCNNModel(build_model("compact"), stats, {"arch": "compact"})
    save_model(tmp_path / "m", model)
    with pytest.raises(InputError, match="images: shape"):
        load_model(tmp_path / "m").predict(np.zeros((2, 16, 16), np.float32), np.zeros((2, 2)))
    with pytest.raises(InputError, match="poses: shape"):
        load_model(tmp_path / "m").predict(np.zeros((2, 32, 32), np.float32), np.zeros((3, 2)))
    weights = tmp_path / "m" / WEIGHTS_NAME
    data = weights.read_bytes()
    weights.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match="sha256 does not match"):
        load_model(tmp_path / "m")
    (tmp_path / "m" / CARD_NAME).write_text("{not json")
    with pytest.raises(InputError, match="malformed JSON"):
        load_model(tmp_path / "m")

    out = tmp_path / "run"
    train(dataset, out, TrainConfig(epochs=1, **FAST))
    (out / STATE_NAME).write_bytes(b"garbage")
    with pytest.raises(InputError, match="training checkpoint"):
        train(dataset, out, TrainConfig(epochs=2, **FAST))
    assert train(dataset, out, TrainConfig(epochs=1, **FAST), overwrite=True)["epochs_trained_now"] == 1


# ----------------------------------------------------------------------------------------------
# CLI


def test_cli_train_and_show(dataset, tmp_path):
    runner = CliRunner()
    out = tmp_path / "model"
    result = runner.invoke(app, ["train", "--dataset", str(dataset), "--out", str(out), "--arch", "compact",
                                 "--epochs", "1", "--seed", "3", "--no-augment", "--max-val-datapoints", "30",
                                 "--max-objects", "4", "--json"])
    assert result.exit_code == 0, result.output
    trained = json.loads(result.stdout.strip().splitlines()[-1])
    assert trained["ok"] and trained["epochs"] == 1 and trained["arch"] == "compact"
    assert trained["num_val"] == 30  # the validation subset
    card = json.loads((out / CARD_NAME).read_text())
    assert "train" in card["command"] and "--seed 3" in card["command"] and "--max-val-datapoints 30" in card["command"]
    assert "--max-objects 4" in card["command"] and card["training"]["config"]["max_train_objects"] == 4
    assert "--target binary" in card["command"] and card["label"]["target"] == "binary"  # the default, spelled out

    result = runner.invoke(app, ["model", "show", str(out), "--json"])
    assert result.exit_code == 0, result.output
    shown = json.loads(result.stdout.strip().splitlines()[-1])
    assert shown["arch"] == "compact" and shown["parameters"] == 36_082
    assert shown["val_accuracy"] == trained["val_accuracy"]

    # model score: the run's own validation datapoints (image_wise, its 30-datapoint subset drawn
    # with the run's seed is not reproduced here, so the whole split) against the card's label
    result = runner.invoke(app, ["model", "score", str(out), "--dataset", str(dataset), "--split", "image_wise",
                                 "--json"])
    assert result.exit_code == 0, result.output
    scored = json.loads(result.stdout.strip().splitlines()[-1])
    assert scored["datapoints"] == len(read_split(dataset, "image_wise", "val")) and scored["target"] == "binary"
    assert scored["decision_threshold"] == 0.5 and scored["accuracy"] == scored["accuracy_at_half"]
    assert 0.0 <= scored["accuracy"] <= 1.0 and 0.0 < scored["positive_rate"] < 1.0
    # each synthetic datapoint is an image of its own: no image has two grasps to rank
    assert scored["images"] == 0 and scored["top_grasp_success"] is None
    # a dataset whose grasp thumbnails were cut otherwise (48 px crops) is refused, not scored
    other = tmp_path / "cut48"
    shutil.copytree(dataset, other)
    card_path = other / "config.json"
    card = json.loads(card_path.read_text())
    card["config"]["thumbnail"] = {"crop_size": 48, "out_size": 32, "sampling": "point"}
    card_path.write_text(json.dumps(card))
    result = runner.invoke(app, ["model", "score", str(out), "--dataset", str(other), "--json"])
    error = json.loads(result.stdout.strip().splitlines()[-1])["error"]
    assert result.exit_code == 2 and "48 px crops" in error and "96 px crops" in error
    result = runner.invoke(app, ["model", "score", str(out), "--dataset", str(dataset), "--part", "test", "--json"])
    assert result.exit_code == 2 and "split part 'test'" in json.loads(result.stdout.strip().splitlines()[-1])["error"]

    result = runner.invoke(app, ["train", "--dataset", str(tmp_path / "nope"), "--out", str(out), "--json"])
    assert result.exit_code == 2 and "not a directory" in json.loads(result.stdout.strip().splitlines()[-1])["error"]
    result = runner.invoke(app, ["train", "--dataset", str(dataset), "--out", str(out), "--arch", "vgg", "--json"])
    assert result.exit_code == 2
    result = runner.invoke(app, ["model", "show", str(tmp_path / "nope"), "--json"])
    assert result.exit_code == 2


def test_cli_learning_rate_sets_the_base_of_the_schedule(dataset, tmp_path):
    # --learning-rate replaces gqcnn's base 0.01; the staircase decays from it (lr = base * 0.95 **
    # floor(examples seen / examples per decay), and each epoch records the rate it started at, so
    # the first epoch's, with no example seen, is the base itself). The card's command names it
    # only when it is not gqcnn's 0.01, so earlier cards' commands are unchanged.
    runner = CliRunner()
    base = ["train", "--dataset", str(dataset), "--arch", "compact", "--epochs", "1", "--no-augment", "--json"]
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "low"), "--learning-rate", "0.0025"])
    assert result.exit_code == 0, result.output
    card = json.loads((tmp_path / "low" / CARD_NAME).read_text())
    assert card["history"][0]["lr"] == pytest.approx(0.0025) and "--learning-rate 0.0025" in card["command"]
    assert card["training"]["config"]["learning_rate"] == 0.0025
    result = runner.invoke(app, [*base, "--out", str(tmp_path / "default")])
    card = json.loads((tmp_path / "default" / CARD_NAME).read_text())
    assert card["history"][0]["lr"] == pytest.approx(0.01) and "--learning-rate" not in card["command"]
    for bad in ("0", "-0.1", "nan"):
        result = runner.invoke(app, [*base, "--out", str(tmp_path / "bad"), "--learning-rate", bad])
        error = json.loads(result.stdout.strip().splitlines()[-1])["error"]
        assert result.exit_code == 2 and "--learning-rate" in error, error
    assert not (tmp_path / "bad").exists()


def test_the_saved_weights_are_the_moving_average_of_the_iterates(dataset, tmp_path, monkeypatch):
    # --average d: after every SGD step k the average is a_1 = w_1, a_k = d a_(k-1) + (1 - d) w_k
    # (an exponential moving average, Polyak averaging); the averaged network is the one scored and
    # saved. Recomputed here from the iterates the trainer hands to the average.
    iterates: list[dict[str, torch.Tensor]] = []
    update = torch.optim.swa_utils.AveragedModel.update_parameters

    def spy(self, model):
        iterates.append({k: v.detach().clone() for k, v in model.named_parameters()})
        return update(self, model)

    monkeypatch.setattr(torch.optim.swa_utils.AveragedModel, "update_parameters", spy)
    decay = 0.9
    metrics = train(dataset, tmp_path / "avg", TrainConfig(**FAST, epochs=1, seed=4, average=decay))
    expected = dict(iterates[0])
    for w in iterates[1:]:
        expected = {k: decay * expected[k] + (1 - decay) * w[k] for k in expected}
    saved = weights_of(tmp_path / "avg")
    assert len(iterates) > 1 and set(saved) == set(expected)
    for name, value in expected.items():
        torch.testing.assert_close(saved[name], value, rtol=1e-5, atol=1e-6)
    assert not torch.equal(saved[next(iter(saved))], iterates[-1][next(iter(saved))])  # not the last iterate
    model = load_model(tmp_path / "avg")  # and it is what the card's validation figures score
    val = SplitData(dataset, "image_wise", "val")
    from suctionbench.learning.train import evaluate

    assert evaluate(model.network, val, model.stats, 0.2, torch.device("cpu"))["accuracy"] == metrics["val_accuracy"]


def test_an_averaged_run_resumes_to_the_uninterrupted_weights(dataset, tmp_path):
    config = TrainConfig(**FAST, epochs=2, seed=5, shuffle_shards=2, average=0.95)
    train(dataset, tmp_path / "straight", config)
    train(dataset, tmp_path / "resumed", TrainConfig(**FAST, epochs=1, seed=5, shuffle_shards=2, average=0.95))
    train(dataset, tmp_path / "resumed", config)
    for (name, a), b in zip(weights_of(tmp_path / "straight").items(), weights_of(tmp_path / "resumed").values(),
                            strict=True):
        assert torch.equal(a, b), name
    with pytest.raises(InputError, match="average"):
        TrainConfig(average=1.0)


# ----------------------------------------------------------------------------------------------
# CUDA (bfloat16 autocast): run where torch sees a GPU (`pytest -m gpu`), skipped elsewhere


@pytest.mark.gpu
def test_cuda_bfloat16_training_learns_and_its_model_predicts_on_the_cpu(dataset, tmp_path):
    # The synthetic set separates by shape (disc vs ridge), which the CPU run learns to 99 %
    # (test_compact_overfits_the_synthetic_set); bfloat16 keeps 8 bits of mantissa, enough for
    # SGD's forward and backward passes with float32 master weights, so the CUDA run must learn it
    # too. The saved weights are float32 and load on the CPU: there, in float32, the model's q
    # differs from the trainer's bfloat16 validation scores only by bfloat16 rounding (relative
    # 2^-8 per operand, a few hundredths of a logit through the network), far below 0.05 in q.
    from suctionbench.learning.train import evaluate

    metrics = train(dataset, tmp_path, TrainConfig(epochs=20, device="cuda", load_threads=2, **FAST))
    card = json.loads((tmp_path / CARD_NAME).read_text())
    assert card["training"]["device"].startswith("cuda") and card["training"]["mixed_precision"] == "bfloat16"
    assert metrics["val_ap"] > 0.9
    model = load_model(tmp_path)
    assert next(model.network.parameters()).device.type == "cpu"
    images, poses, metric = train_arrays(dataset)
    assert np.mean((model.predict(images, poses) > 0.5) == (metric > 0.2)) >= 0.99
    val = SplitData(dataset, "image_wise", "val")
    cuda_scores = evaluate(model.network.to("cuda"), val, model.stats, 0.2, torch.device("cuda"))["scores"]
    model = load_model(tmp_path)
    cpu_scores = evaluate(model.network, val, model.stats, 0.2, torch.device("cpu"))["scores"]
    assert np.abs(cuda_scores - cpu_scores).max() < 0.05


@pytest.mark.gpu
def test_a_cpu_run_resumes_on_cuda_with_augmentation_on_the_gpu(dataset, tmp_path):
    # `device` may differ between a checkpoint and the run resuming it (RESUME_IGNORES): the resume
    # state saved on the CPU loads onto the GPU (weights, momentum, both RNG states) and training
    # continues there, with the context-pose net and gqcnn's noise and flips drawn from the CPU
    # generator and applied to CUDA tensors.
    config = {"arch": "context-pose", "seed": 4, "target": "soft", "average": 0.99}
    train(dataset, tmp_path, TrainConfig(epochs=1, **config))
    more = train(dataset, tmp_path, TrainConfig(epochs=3, device="cuda", **config))
    assert more["resumed_from_epoch"] == 1 and more["epochs_trained_now"] == 2
    history = json.loads((tmp_path / CARD_NAME).read_text())["history"]
    assert len(history) == 3 and all(math.isfinite(h["val_loss"]) for h in history)
    model = load_model(tmp_path)
    data = SplitData(dataset, "image_wise", "train", image_channels=2, object_context=True)
    batch = data.load_shard(data.shards[0])
    q = model.predict(batch.images, batch.poses)
    assert np.all(np.isfinite(q)) and np.all((q >= 0) & (q <= 1))


def test_bench_train_times_one_epoch_on_a_dataset_it_writes_and_removes():
    # The timing dataset is written in the trainer's format (it trains on it) into a temporary
    # folder; the Dex-Net schedule's hours are 25 epochs x 2.8 M images at the measured rate.
    import tempfile
    from pathlib import Path

    from suctionbench.bench import bench_train

    before = set(Path(tempfile.gettempdir()).glob("suctionbench-bench-train-*"))
    result = bench_train(archs=["compact"], datapoints=1000, reference_datapoints=1000, device="cpu",
                         batch_size=64, seed=0, cores=0)
    assert result["device"] == "cpu" and result["compact_parameters"] == 36_082
    rate = result["compact_cpu_images_per_s"]
    assert rate > 0
    assert result["compact_cpu_hours_dex_net_schedule"] == pytest.approx(25 * 2.8e6 / rate / 3600, rel=0.01)
    assert set(Path(tempfile.gettempdir()).glob("suctionbench-bench-train-*")) == before
    with pytest.raises(InputError, match="device 'tpu'"):
        bench_train(archs=["compact"], datapoints=1000, reference_datapoints=1000, device="tpu",
                    batch_size=64, seed=0, cores=0)
