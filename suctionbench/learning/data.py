"""Training data for GQ-CNNs: streaming shard loading, normalisation statistics and augmentation.

Streaming. A dataset can hold millions of thumbnails (Dex-Net 3.0: 2.8 M, 11 GB), so nothing here
loads it whole: `SplitData` keeps only the split's datapoint indices (8 bytes a datapoint) and reads
one shard at a time through `DatasetReader` (hash-checked against its manifest). An epoch visits
the shards in a random order, pools `shuffle_shards` of them at a time, shuffles the pool and cuts
it into batches; what is left over joins the next pool, so every training datapoint is seen exactly
once per epoch and memory stays at a few shards whatever the dataset size. The next pool is read
on a background thread while the current one trains (decompression and hashing release the GIL).
All randomness comes from a `numpy.random.Generator` the caller passes in and checkpoints.

Normalisation (gqcnn): one scalar mean and standard deviation over every pixel of every training
image, and a per-dimension mean and standard deviation of the pose vector [gripper depth, approach
angle], from the training split only, in one streaming pass (per-shard moments merged with Chan et
al.'s parallel formula, so the result does not suffer from E[x^2] - E[x]^2 cancellation).

Augmentation and the sign of the approach angle
-----------------------------------------------
Thumbnails are cut so that the image of the approach axis points DOWN the middle column, and the
dataset's angle is the unsigned tilt arccos(-v . n) >= 0 of the approach from the downward table
normal (`suctionbench.sensing.thumbnails`). The network's second pose input is read here as a
*signed* angle: +tilt when the approach's image points down the thumbnail's middle column (every
stored datapoint), -tilt when it points up. Under that reading the symmetries act as follows
(c = 15.5 is the thumbnail centre; the grasp stays on it under all of them):

- left-right flip, column j -> 31 - j: mirrors the scene across the middle column, which contains
  the approach's image; the mirrored grasp still tilts down the column by the same amount (a mirror
  keeps angles to the table normal), so the angle is unchanged. It is exactly the thumbnail
  `extract_thumbnails` cuts from the mirrored depth image for the mirrored grasp.
- up-down flip, row i -> 31 - i: the same mirrored scene, but now the thumbnail's down axis points
  against the approach's image, so the angle changes sign.
- 180-degree rotation (both flips): the unmirrored scene seen with the down axis reversed, so the
  angle changes sign; it is the thumbnail cut with image angle theta + pi.

So the sign flips exactly when the rows are flipped. gqcnn drew the three symmetries with p = 0.5
each but negated the angle of the whole batch whenever the draw for the current image said so (a
bug: most samples then disagree with their image); here every sample carries its own flags. Three
fair coins (rotate, flip left-right, flip up-down) compose to "flip rows" = rotate xor up-down and
"flip columns" = rotate xor left-right, two independent fair coins, so `symmetrize` draws those
two directly: the same distribution over the four symmetries with fewer draws. At inference the
policy passes the dataset's unsigned angle, i.e. the "down" case the network was trained on too.

Noise (gqcnn's Dex-Net 3.0 recipe, `apply_depth_noise_torch`): every training image gets a Gamma
multiplicative factor and, with probability 0.5, the additive correlated field; the pose's gripper
depth is not scaled (as in gqcnn; the dataset stores the noise-free depth next to noisy thumbnails).
Noise acts on depths in metres, so it is applied before normalisation, and symmetrisation after.
"""

from __future__ import annotations

import contextlib
import math
import queue
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch

from suctionbench.dataset.storage import DatasetReader, read_split
from suctionbench.errors import InputError
from suctionbench.sensing.noise import DepthNoiseConfig, apply_depth_noise_torch

IMAGE_FIELD = "depth_ims_tf_table"
"""Dataset field with the depth thumbnails (n, 32, 32, 1), metres."""

POSE_FIELD = "hand_poses"
"""Dataset field with the pose vectors (n, 7); `POSE_COLUMNS` are the network's input."""

METRIC_FIELD = "robust_suction_wrench_resistance"
"""Dataset field thresholded into the label."""

POSE_COLUMNS = (2, 3)
"""Columns of ``hand_poses`` the network reads: gripper depth (m), approach angle (rad)."""

DEFAULT_LABEL_THRESHOLD = 0.2
"""Label = metric > this when the dataset card does not say (gqcnn's ``metric_thresh`` for Dex-Net 3.0)."""

MIN_STD = 1e-8
"""A standard deviation below this (a constant input, e.g. every approach vertical) is replaced by 1,
so normalisation only centres that input instead of dividing by ~0."""


@dataclass(frozen=True)
class Batch:
    """A batch as stored: images (B, 32, 32) float32 metres, poses (B, 2) float32 unsigned, metric (B,)."""

    images: np.ndarray
    poses: np.ndarray
    metric: np.ndarray

    def __len__(self) -> int:
        return len(self.metric)


@dataclass(frozen=True)
class NormStats:
    """Input normalisation of a GQ-CNN: x_normalised = (x - mean) / std."""

    image_mean: float
    """Mean depth (m) over all pixels of all training thumbnails."""

    image_std: float
    """Standard deviation (m) of those pixels."""

    pose_mean: tuple[float, float]
    """Mean of [gripper depth (m), approach angle (rad)] over the training datapoints."""

    pose_std: tuple[float, float]
    """Standard deviation of each pose dimension (1 where the input is constant, see `MIN_STD`)."""

    count: int = 0
    """Number of datapoints the statistics come from."""

    def to_dict(self) -> dict[str, Any]:
        return {"image_mean": self.image_mean, "image_std": self.image_std, "pose_mean": list(self.pose_mean),
                "pose_std": list(self.pose_std), "count": self.count}

    @classmethod
    def from_dict(cls, data: Any, source: str = "normalisation") -> NormStats:
        """Inverse of `to_dict`; InputError naming `source` if a value is missing or not a usable number."""
        try:
            stats = cls(float(data["image_mean"]), float(data["image_std"]),
                        tuple(float(x) for x in data["pose_mean"]), tuple(float(x) for x in data["pose_std"]),
                        int(data.get("count", 0)))
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(f"{source}: malformed normalisation statistics ({exc!r})") from None
        values = [stats.image_mean, stats.image_std, *stats.pose_mean, *stats.pose_std]
        if len(stats.pose_mean) != 2 or len(stats.pose_std) != 2 or not all(map(math.isfinite, values)) \
                or min(stats.image_std, *stats.pose_std) <= 0:
            raise InputError(f"{source}: normalisation statistics must be finite with positive stds, got {data}")
        return stats

    def normalise(self, images: torch.Tensor, poses: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Network inputs from images (B, 1, H, W) in metres and poses (B, 2)."""
        mean = torch.tensor(self.pose_mean, dtype=poses.dtype, device=poses.device)
        std = torch.tensor(self.pose_std, dtype=poses.dtype, device=poses.device)
        return (images - self.image_mean) / self.image_std, (poses - mean) / std


@dataclass(frozen=True)
class AugmentConfig:
    """Training-time augmentation (defaults: gqcnn's Dex-Net 3.0 recipe)."""

    noise: bool = True
    """Gamma multiplicative noise on every training image (gqcnn ``multiplicative_denoising``)."""

    gp_prob: float = 0.5
    """Probability that a noised image also gets the correlated additive field (gqcnn
    ``gaussian_process_rate``); only used when `noise` is on."""

    symmetrize: bool = True
    """Random 180-degree rotation / left-right / up-down flip per sample, with the angle's sign
    corrected per sample (module docstring)."""

    depth_noise: DepthNoiseConfig = field(default_factory=DepthNoiseConfig)
    """Noise model parameters (defaults: the paper's, gqcnn's sigma 5 mm and rescale factor 4)."""

    def __post_init__(self) -> None:
        if not (isinstance(self.gp_prob, int | float) and 0.0 <= self.gp_prob <= 1.0):
            raise InputError(f"augmentation gp_prob {self.gp_prob!r}: must be in [0, 1]")

    @property
    def enabled(self) -> bool:
        return self.noise or self.symmetrize


AUGMENT_GQCNN = AugmentConfig()
"""gqcnn's Dex-Net 3.0 augmentation: Gamma noise, GP field with p 0.5, symmetrisation."""

AUGMENT_OFF = AugmentConfig(noise=False, symmetrize=False)
"""No augmentation."""


def symmetrize(images: torch.Tensor, angles: torch.Tensor, flip_rows: torch.Tensor, flip_cols: torch.Tensor
               ) -> tuple[torch.Tensor, torch.Tensor]:
    """Flip each sample's rows and/or columns as its flags say; negate the signed angle where the rows flip.

    images (B, C, H, W), angles (B,), flags (B,) bool. Rows and columns both flipped is the
    180-degree rotation. Why rows, and only rows, change the sign: module docstring.
    """
    rows = flip_rows.to(images.device)[:, None, None, None]
    cols = flip_cols.to(images.device)[:, None, None, None]
    images = torch.where(rows, images.flip(-2), images)
    images = torch.where(cols, images.flip(-1), images)
    return images, torch.where(flip_rows.to(angles.device), -angles, angles)


def augment(images: torch.Tensor, poses: torch.Tensor, generator: torch.Generator, config: AugmentConfig
            ) -> tuple[torch.Tensor, torch.Tensor]:
    """Augmented copies of images (B, 1, H, W) in metres and poses (B, 2) [depth, angle].

    Draws from `generator` (on its device) in a fixed order whatever is enabled per sample, so a run
    is reproducible from the generator state.
    """
    if config.noise:
        images = apply_depth_noise_torch(images, generator, config.depth_noise, prob=1.0, gp_prob=config.gp_prob)
    if config.symmetrize:
        flips = torch.rand(2, len(images), generator=generator, device=generator.device) < 0.5
        images, angles = symmetrize(images, poses[:, 1], flips[0], flips[1])
        poses = torch.stack([poses[:, 0], angles], dim=1)
    return images, poses


def labels_of(metric: np.ndarray, threshold: float) -> np.ndarray:
    """Binary labels (int64, for cross-entropy): metric > threshold, as gqcnn."""
    return (np.asarray(metric) > threshold).astype(np.int64)


def label_threshold(card: dict[str, Any]) -> float:
    """The dataset's label threshold: ``card["config"]["label_threshold"]``, else `DEFAULT_LABEL_THRESHOLD`."""
    config = card.get("config")
    value = config.get("label_threshold") if isinstance(config, dict) else None
    if value is None:
        return DEFAULT_LABEL_THRESHOLD
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(f"dataset card: config.label_threshold {value!r} is not a number")
    return float(value)


# -- moments ---------------------------------------------------------------------------------------


@dataclass
class _Moments:
    """Count, mean and sum of squared deviations (M2) per column of a stream of (n, d) blocks."""

    n: int = 0
    mean: np.ndarray | float = 0.0
    m2: np.ndarray | float = 0.0

    def add(self, values: np.ndarray) -> None:
        """Merge in a block of rows (Chan, Golub & LeVeque's pairwise update), in float64."""
        values = np.asarray(values, dtype=np.float64)
        n_b = len(values)
        if n_b == 0:
            return
        mean_b = values.mean(axis=0)
        m2_b = ((values - mean_b) ** 2).sum(axis=0)
        n = self.n + n_b
        delta = mean_b - self.mean
        self.mean = self.mean + delta * (n_b / n)
        self.m2 = self.m2 + m2_b + delta**2 * (self.n * n_b / n)
        self.n = n

    def std(self) -> np.ndarray:
        std = np.sqrt(np.asarray(self.m2) / max(self.n, 1))
        return np.where(std < MIN_STD, 1.0, std)


# -- streaming over a split ------------------------------------------------------------------------


def _load_ahead(load: Callable[[Any], Any], keys: list[Any]) -> Iterator[Any]:
    """Yield ``load(key)`` for each key in order, loading the next one on a background thread.

    One item ahead at most, so memory holds two loads. An exception in the loader is re-raised in
    the consumer; a consumer that stops early leaves the thread to finish its one pending load.
    """
    results: queue.Queue = queue.Queue(maxsize=1)
    stop = threading.Event()

    def worker() -> None:
        for key in keys:
            if stop.is_set():
                return
            try:
                item = (True, load(key))
            except BaseException as exc:  # handed to the consumer, which re-raises it
                item = (False, exc)
            results.put(item)
            if not item[0]:
                return

    thread = threading.Thread(target=worker, daemon=True)
    thread.start()
    try:
        for _ in keys:
            ok, value = results.get()
            if not ok:
                raise value
            yield value
    finally:
        stop.set()
        while thread.is_alive():  # unblock a worker waiting to put an item nobody will take
            with contextlib.suppress(queue.Empty):
                results.get_nowait()
            thread.join(timeout=0.01)


class SplitData:
    """One side of a dataset split (e.g. image-wise train), read shard by shard.

    Holds the dataset reader and, per shard, the local indices of the split's datapoints in it;
    `batches` streams them. `max_datapoints` keeps a random subset (drawn with `subset_rng`) for
    quick runs.
    """

    def __init__(self, directory: str | Path, kind: str, part: str, *, max_datapoints: int | None = None,
                 subset_rng: np.random.Generator | None = None, reader: DatasetReader | None = None):
        self.reader = reader or DatasetReader(directory)
        self.kind, self.part = kind, part
        indices = np.unique(read_split(directory, kind, part))
        if max_datapoints is not None and len(indices) > max_datapoints:
            rng = subset_rng or np.random.default_rng(0)
            indices = np.sort(rng.choice(indices, size=max_datapoints, replace=False))
        dps = self.reader.datapoints_per_shard
        if self.reader.num_shards == 0 or dps is None:
            raise InputError(f"dataset '{self.reader.directory}': no complete shards")
        shard_of = indices // dps
        available = set(self.reader.shard_indices)
        self._local: dict[int, np.ndarray] = {}
        for shard in np.unique(shard_of).tolist():
            lo, hi = np.searchsorted(shard_of, [shard, shard + 1])
            local = indices[lo:hi] - shard * dps
            if shard not in available or local[-1] >= self.reader.shard_size(shard):
                raise InputError(f"split '{kind}/{part}' of '{self.reader.directory}': refers to datapoints of "
                                 f"shard {shard}, which is missing or smaller (dataset incomplete?)")
            self._local[shard] = local.astype(np.int64)
        self.num_datapoints = int(len(indices))

    @property
    def shards(self) -> list[int]:
        """Shards holding at least one datapoint of the split, ascending."""
        return sorted(self._local)

    def load_shard(self, shard: int) -> Batch:
        """The split's datapoints of one shard, in index order."""
        arrays = self.reader.shard(shard, fields=[IMAGE_FIELD, POSE_FIELD, METRIC_FIELD])
        local = self._local[shard]
        return Batch(arrays[IMAGE_FIELD][local, ..., 0], arrays[POSE_FIELD][local][:, list(POSE_COLUMNS)],
                     arrays[METRIC_FIELD][local])

    def _pools(self, shards: list[int], pool_size: int) -> Iterator[Batch]:
        groups = [shards[i:i + pool_size] for i in range(0, len(shards), pool_size)]
        return _load_ahead(lambda group: _concat([self.load_shard(s) for s in group]), groups)

    def batches(self, batch_size: int, rng: np.random.Generator | None = None, shuffle_shards: int = 4
                ) -> Iterator[Batch]:
        """One pass over the split in batches of `batch_size` (the last may be smaller).

        With `rng`: shards in random order, datapoints shuffled within pools of `shuffle_shards`
        shards (leftovers carried into the next pool); without: index order, for evaluation.
        """
        shards = self.shards
        if rng is not None:
            shards = [shards[i] for i in rng.permutation(len(shards))]
        carry: Batch | None = None
        for pool in self._pools(shards, max(1, shuffle_shards) if rng is not None else 1):
            if carry is not None:
                pool = _concat([carry, pool])
            order = rng.permutation(len(pool)) if rng is not None else np.arange(len(pool))
            full = len(pool) // batch_size * batch_size
            for start in range(0, full, batch_size):
                yield _take(pool, order[start:start + batch_size])
            carry = _take(pool, order[full:]) if full < len(pool) else None
        if carry is not None:
            yield carry

    def compute_stats(self) -> NormStats:
        """Normalisation statistics of this split in one streaming pass over its shards."""
        image, pose = _Moments(), _Moments()
        for batch in self._pools(self.shards, 1):
            image.add(batch.images.reshape(-1, 1))
            pose.add(batch.poses)
        if pose.n == 0:
            raise InputError(f"split '{self.kind}/{self.part}' of '{self.reader.directory}': no datapoints")
        return NormStats(float(image.mean[0]), float(image.std()[0]), tuple(float(x) for x in pose.mean),
                         tuple(float(x) for x in pose.std()), count=pose.n)


def _concat(batches: list[Batch]) -> Batch:
    if len(batches) == 1:
        return batches[0]
    return Batch(*(np.concatenate([getattr(b, name) for b in batches]) for name in ("images", "poses", "metric")))


def _take(batch: Batch, index: np.ndarray) -> Batch:
    return Batch(batch.images[index], batch.poses[index], batch.metric[index])


def to_tensors(batch: Batch, device: torch.device | str = "cpu") -> tuple[torch.Tensor, torch.Tensor]:
    """Images (B, 1, 32, 32) and poses (B, 2) float32 tensors on `device`, still in physical units."""
    images = torch.from_numpy(np.ascontiguousarray(batch.images, dtype=np.float32))[:, None]
    poses = torch.from_numpy(np.ascontiguousarray(batch.poses, dtype=np.float32))
    return images.to(device, non_blocking=True), poses.to(device, non_blocking=True)
