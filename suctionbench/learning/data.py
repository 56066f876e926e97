"""Training data for GQ-CNNs: streaming shard loading, normalisation statistics and augmentation.

Streaming. A dataset can hold millions of thumbnails (Dex-Net 3.0: 2.8 M, 11 GB), so nothing here
loads it whole: `SplitData` keeps only the split's datapoint indices (8 bytes a datapoint) and reads
one shard at a time through `DatasetReader` (hash-checked against its manifest). An epoch visits
the shards in a random order, pools `shuffle_shards` of them at a time, shuffles the pool and cuts
it into batches; what is left over joins the next pool, so every training datapoint is seen exactly
once per epoch and memory stays at two pools whatever the dataset size (64 shards by default: a
shard holds one or two objects, so a pool mixes ~40 of them; `TrainConfig.shuffle_shards`). The next pool is read
on a background thread while the current one trains (decompression and hashing release the GIL).
All randomness comes from a `numpy.random.Generator` the caller passes in and checkpoints.

Image channels. A batch holds images (B, C, 32, 32): C = 1, the grasp thumbnail
(``depth_ims_tf_table``), for dn3 and compact; C = 2, the grasp and the context thumbnail
(``context_ims_tf_table``, `suctionbench.sensing.thumbnails.THUMBNAIL_CONTEXT`), for the context
nets. `SplitData` reads the context field only when asked for two channels, and refuses a dataset
written before the field existed with an InputError naming the dataset and the field.

Normalisation (gqcnn): one mean and standard deviation per image channel over every pixel of every
training image (for one channel gqcnn's single scalar pair, and stored as scalars as before), and a
per-dimension mean and standard deviation of the pose vector [gripper depth, approach angle], from
the training split only, in one streaming pass (per-shard moments merged with Chan et al.'s
parallel formula, so the result does not suffer from E[x^2] - E[x]^2 cancellation). The context
channel gets its own pair: it is a block mean over 3x the field of view, so it sees more table and
its spread differs from the grasp thumbnail's.

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

Both channels are cut by the same `extract_thumbnails` sampling geometry (``_sample_coordinates``)
with the same grasp pixel, the same approach angle theta and the same centre (n - 1) / 2; only
the step (3 vs 9 image pixels per thumbnail pixel) differs. Row i and column j of either channel
lie along the same image directions d and e, so a row or column flip of both channels together is
the thumbnail pair cut from the mirrored (or theta + pi) scene, and `symmetrize` flips every
channel of a sample with that sample's flags.

Noise (gqcnn's Dex-Net 3.0 recipe, `apply_depth_noise_torch`): every training image gets a Gamma
multiplicative factor and, with probability 0.5, the additive correlated field; the pose's gripper
depth is not scaled (as in gqcnn; the dataset stores the noise-free depth next to noisy thumbnails).
Noise acts on depths in metres, so it is applied before normalisation, and symmetrisation after.

With a context channel the two thumbnails come from one depth image, so the augmentation noise
must be that of one noisy image seen twice. The Gamma factor alpha scales the whole depth image (a
calibration scale error), and the context pixels are block means of that same scaled image, so the
SAME alpha multiplies both channels of a sample. The additive field is drawn, as in gqcnn, on the
grasp thumbnail's 32 x 32 grid (it decorrelates over ~4 thumbnail pixels = 12 image pixels) and
goes to channel 0 only. Added to the context channel too it would put the same error at pixel
indices that lie 3x farther from the grasp, a correlation between the channels that no sensor
makes. The consistent context field would be that image-space field averaged over 9 x 9 blocks and
sampled every 9 pixels, mostly outside the grasp thumbnail's footprint: a field the paper's noise
model does not define. Nor is it the field scaled by 1/9, the reduction an 81-pixel mean gives
white noise: a 9-pixel block spans only 3 thumbnail pixels of a field correlated over about 4, so
averaging would shrink it far less. The context channel therefore trains with the multiplicative
noise only; its stored pixels are block means of the dataset's noisy render, so generation-time
noise is in them already, averaged as a real sensor's would be.
"""

from __future__ import annotations

import contextlib
import copy
import fnmatch
import math
import queue
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch

from suctionbench.dataset.storage import DatasetReader, read_card, read_split
from suctionbench.errors import InputError
from suctionbench.sensing.noise import DepthNoiseConfig, apply_depth_noise_torch
from suctionbench.sensing.thumbnails import ThumbnailConfig

IMAGE_FIELD = "depth_ims_tf_table"
"""Dataset field with the depth thumbnails (n, 32, 32, 1), metres."""

CONTEXT_FIELD = "context_ims_tf_table"
"""Dataset field with the context thumbnails (n, 32, 32, 1), metres: image channel 1 of the context nets."""

IMAGE_FIELDS = (IMAGE_FIELD, CONTEXT_FIELD)
"""Dataset field of each image channel, in channel order."""

POSE_FIELD = "hand_poses"
"""Dataset field with the pose vectors (n, 7); `POSE_COLUMNS` are the network's input."""

OBJECT_CONTEXT_FIELD = "object_context"
"""Dataset field with the object context (n, 6), metres: appended to the pose vector of the nets
that read it (`suctionbench.learning.models.pose_dim_of`)."""

METRIC_FIELD = "robust_suction_wrench_resistance"
"""Dataset field thresholded into the label."""

OBJECT_FIELD = "object_labels"
"""Dataset field with each datapoint's object (index into the card's object list)."""

POSE_COLUMNS = (2, 3)
"""Columns of ``hand_poses`` the network reads: gripper depth (m), approach angle (rad)."""

DEFAULT_LABEL_THRESHOLD = 0.2
"""Label = metric > this when the dataset card does not say (gqcnn's ``metric_thresh`` for Dex-Net 3.0)."""

MIN_STD = 1e-8
"""A standard deviation below this (a constant input, e.g. every approach vertical) is replaced by 1,
so normalisation only centres that input instead of dividing by ~0."""


@dataclass(frozen=True)
class Batch:
    """A batch as stored: images (B, C, 32, 32) float32 metres (channel 0 the grasp thumbnail, 1 the
    context thumbnail if read), poses (B, 2) float32 unsigned (B, 8 with the object context),
    metric (B,)."""

    images: np.ndarray
    poses: np.ndarray
    metric: np.ndarray

    def __len__(self) -> int:
        return len(self.metric)


def _channel_values(value: Any) -> float | tuple[float, ...]:
    """A scalar (one channel) or a tuple of floats, one per channel; a one-element sequence is a scalar."""
    if isinstance(value, list | tuple | np.ndarray):
        values = tuple(float(x) for x in np.asarray(value, dtype=float).reshape(-1))
        if not values:
            raise ValueError("no image channel")
        return values[0] if len(values) == 1 else values
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise TypeError(f"not a number or a list of numbers: {value!r}")
    return float(value)


SHUFFLE_SHARDS = 64
"""Shards pooled and shuffled together by default (`SplitData.batches`, `TrainConfig.shuffle_shards`).
A generated shard holds one or two objects' datapoints, so the pool sets how many objects a stretch
of batches mixes: with 4 shards (2-3 objects) the net chased the objects of the moment (2.8 M
datapoints, context, first epoch: running accuracy 0.864, held-out 0.771 at loss 0.63)."""

@dataclass(frozen=True)
class NormStats:
    """Input normalisation of a GQ-CNN: x_normalised = (x - mean) / std, per image channel.

    `image_mean` and `image_std` are scalars for one image channel (as gqcnn, and every model
    trained before the context nets) and tuples with one value per channel otherwise; a
    one-element sequence becomes a scalar, so equal statistics compare equal however they were given.
    """

    image_mean: float | tuple[float, ...]
    """Mean depth (m) over all pixels of all training thumbnails, per image channel."""

    image_std: float | tuple[float, ...]
    """Standard deviation (m) of those pixels, per image channel."""

    pose_mean: tuple[float, ...]
    """Mean of [gripper depth (m), approach angle (rad)] over the training datapoints, then of each
    object-context feature for the nets that read it."""

    pose_std: tuple[float, ...]
    """Standard deviation of each pose dimension (1 where the input is constant, see `MIN_STD`)."""

    count: int = 0
    """Number of datapoints the statistics come from."""

    def __post_init__(self) -> None:
        mean, std = _channel_values(self.image_mean), _channel_values(self.image_std)
        if isinstance(mean, tuple) != isinstance(std, tuple) or (isinstance(mean, tuple) and len(mean) != len(std)):
            raise ValueError(f"image_mean {self.image_mean!r} and image_std {self.image_std!r}: different "
                             "numbers of channels")
        object.__setattr__(self, "image_mean", mean)
        object.__setattr__(self, "image_std", std)

    @property
    def image_channels(self) -> int:
        """Image channels the statistics normalise (1 for scalars)."""
        return len(self.image_mean) if isinstance(self.image_mean, tuple) else 1

    def to_dict(self) -> dict[str, Any]:
        """Plain values for a model card: scalar image mean and std for one channel (the form every
        model card has used), lists for more."""
        def form(value: float | tuple[float, ...]) -> float | list[float]:
            return list(value) if isinstance(value, tuple) else value

        return {"image_mean": form(self.image_mean), "image_std": form(self.image_std),
                "pose_mean": list(self.pose_mean), "pose_std": list(self.pose_std), "count": self.count}

    @classmethod
    def from_dict(cls, data: Any, source: str = "normalisation") -> NormStats:
        """Inverse of `to_dict` (image mean and std: scalars, or lists of one value per channel);
        InputError naming `source` if a value is missing or not a usable number."""
        try:
            stats = cls(data["image_mean"], data["image_std"],
                        tuple(float(x) for x in data["pose_mean"]), tuple(float(x) for x in data["pose_std"]),
                        int(data.get("count", 0)))
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(f"{source}: malformed normalisation statistics ({exc!r})") from None
        image_mean, image_std = np.atleast_1d(stats.image_mean).tolist(), np.atleast_1d(stats.image_std).tolist()
        values = [*image_mean, *image_std, *stats.pose_mean, *stats.pose_std]
        if len(stats.pose_mean) < 2 or len(stats.pose_std) != len(stats.pose_mean) \
                or not all(map(math.isfinite, values)) \
                or min(*image_std, *stats.pose_std) <= 0:
            raise InputError(f"{source}: normalisation statistics must be finite with positive stds, got {data}")
        return stats

    def normalise(self, images: torch.Tensor, poses: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Network inputs from images (B, C, H, W) in metres, C = `image_channels`, and poses (B, P)
        (P = 2, or 8 with the object context)."""
        if images.ndim != 4 or images.shape[1] != self.image_channels:
            raise ValueError(f"images {tuple(images.shape)}: expected (B, {self.image_channels}, H, W) for "
                             f"normalisation statistics of {self.image_channels} channel(s)")
        image_mean = torch.tensor(self.image_mean, dtype=images.dtype, device=images.device).reshape(1, -1, 1, 1)
        image_std = torch.tensor(self.image_std, dtype=images.dtype, device=images.device).reshape(1, -1, 1, 1)
        return (images - image_mean) / image_std, self.normalise_poses(poses)

    def normalise_poses(self, poses: torch.Tensor) -> torch.Tensor:
        """The pose stream's input from poses (B, P): each dimension standardised."""
        mean = torch.tensor(self.pose_mean, dtype=poses.dtype, device=poses.device)
        std = torch.tensor(self.pose_std, dtype=poses.dtype, device=poses.device)
        return (poses - mean) / std

    def channel(self, index: int) -> tuple[float, float]:
        """Mean and standard deviation of image channel `index` (0: the grasp thumbnail), for
        inputs normalised one channel at a time (the dense GQ-CNN's lattices)."""
        return float(np.atleast_1d(self.image_mean)[index]), float(np.atleast_1d(self.image_std)[index])


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

AUGMENT_FLIPS = AugmentConfig(noise=False)
"""Symmetrisation only: for images that already carry the noise the network will see (`generate
--noise sensor`), where the paper's noise on top would hide what the sensor shows."""

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
    """Augmented copies of images (B, C, H, W) in metres and poses (B, P) [depth, angle, then any object context].

    Channel 0 is the grasp thumbnail, channel 1 (if any) the context thumbnail of the same image:
    one Gamma factor per sample scales both, the additive field goes to channel 0 only, and the
    flips act on both channels alike (module docstring, "Both channels..." and "With a context
    channel..."). Draws from `generator` (on its device) in a fixed order whatever is enabled per
    sample and however many channels there are, so a run is reproducible from the generator state.
    """
    if config.noise:
        images = apply_depth_noise_torch(images, generator, config.depth_noise, prob=1.0, gp_prob=config.gp_prob,
                                         field_channels=1)  # the grasp thumbnail's field only
    if config.symmetrize:
        flips = torch.rand(2, len(images), generator=generator, device=generator.device) < 0.5
        images, angles = symmetrize(images, poses[:, 1], flips[0], flips[1])
        poses = torch.cat([poses[:, :1], angles[:, None], poses[:, 2:]], dim=1)  # the object context: mirror-free
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


def dataset_settings(card: dict[str, Any]) -> dict[str, Any]:
    """The generation settings a dataset card records (``card["config"]``; {} if it has none)."""
    config = card.get("config")
    return config if isinstance(config, dict) else {}


def dataset_noise_model(card: dict[str, Any]) -> str:
    """The image noise of the dataset (`sensing.noise.NOISE_MODELS`); "paper" for datasets from
    before the choice existed."""
    return dataset_settings(card).get("noise_model", "paper")


def dataset_thumbnail(card: dict[str, Any], source: str) -> ThumbnailConfig:
    """How the dataset cut its grasp thumbnails (`ThumbnailConfig.recorded`: gqcnn's for datasets
    from before the choice existed); InputError naming `source` if it is not a config."""
    return ThumbnailConfig.recorded(dataset_settings(card).get("thumbnail"), source)


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


def _of_random_objects(indices: np.ndarray, objects_of: np.ndarray, count: int,
                       rng: np.random.Generator) -> np.ndarray:
    """The `indices` whose object (`objects_of`, aligned with them) is one of `count` drawn from
    those they hold (all of them when they hold no more)."""
    objects = np.unique(objects_of)
    if len(objects) <= count:
        return indices
    return indices[np.isin(objects_of, rng.choice(objects, size=count, replace=False))]


def _matching_objects(objects_of: np.ndarray, keys: list[str], pattern: str, source: str) -> np.ndarray:
    """Mask of the datapoints whose object's key (`keys[objects_of]`, e.g. 'train/train_00001_household')
    matches the shell-style `pattern` (`fnmatch`); InputError naming `source` when none does."""
    ids = np.unique(objects_of)
    if len(ids) and int(ids.max()) >= len(keys):
        raise InputError(f"{source}: object ids beyond its card's {len(keys)} objects")
    chosen = [i for i in ids.tolist() if fnmatch.fnmatchcase(str(keys[i]), pattern)]
    if not chosen:
        raise InputError(f"--train-objects '{pattern}': matches none of the {len(ids)} objects of {source} "
                         f"(keys look like '{keys[int(ids[0])] if len(ids) else ''}')")
    return np.isin(objects_of, chosen)


class SplitData:
    """One side of a dataset split (e.g. image-wise train), read shard by shard.

    Holds the dataset reader and, per shard, the local indices of the split's datapoints in it;
    `batches` streams them. `max_datapoints` keeps a random subset (drawn with `subset_rng`) for
    quick runs; `max_objects` first keeps only the datapoints of that many of the split's objects
    (drawn with the same generator): a learning curve over object diversity at a fixed datapoint
    count, which the object-wise held-out accuracy depends on. `objects_matching` (a shell pattern
    of object keys, e.g. '*household*') keeps only those objects' datapoints, before either.
    `image_channels` 2 also reads the context thumbnails (InputError if the dataset's shards of
    the split do not store them).
    `load_threads` threads read a pool's shards at once (hashing and decompression release the
    GIL): a GPU trains faster than one thread reads; the pool's order, hence every batch, is the
    same for any count.
    """

    def __init__(self, directory: str | Path, kind: str, part: str, *, max_datapoints: int | None = None,
                 subset_rng: np.random.Generator | None = None, reader: DatasetReader | None = None,
                 image_channels: int = 1, object_context: bool = False, load_threads: int = 1,
                 max_objects: int | None = None, objects_matching: str | None = None):
        if image_channels not in (1, 2):
            raise InputError(f"image_channels {image_channels!r}: must be 1 (grasp thumbnail) or 2 (grasp, context)")
        self.reader = reader or DatasetReader(directory)
        self.kind, self.part = kind, part
        self.image_fields = IMAGE_FIELDS[:image_channels]
        self.object_context = bool(object_context)
        indices = np.unique(read_split(directory, kind, part))
        rng = subset_rng or np.random.default_rng(0)
        if self.reader.num_shards == 0 or self.reader.datapoints_per_shard is None:
            raise InputError(f"dataset '{self.reader.directory}': no complete shards")
        if objects_matching is not None or max_objects is not None:
            self._local = self._by_shard(indices)  # so `values` reads the split's objects, once
            objects_of = self.values(OBJECT_FIELD)
            if objects_matching is not None:
                keys = read_card(self.reader.directory).get("objects") or []
                keep = _matching_objects(objects_of, keys, objects_matching,
                                         f"the {kind}/{part} split of '{self.reader.directory}'")
                indices, objects_of = indices[keep], objects_of[keep]
            if max_objects is not None:
                indices = _of_random_objects(indices, objects_of, max_objects, rng)
        if max_datapoints is not None and len(indices) > max_datapoints:
            indices = np.sort(rng.choice(indices, size=max_datapoints, replace=False))
        self._local = self._by_shard(indices)
        self.num_datapoints = int(len(indices))
        self.load_threads = max(1, int(load_threads))
        for name in [*self.image_fields, *([OBJECT_CONTEXT_FIELD] if self.object_context else [])]:
            if not self.reader.has_field(name, self.shards):
                raise InputError(f"dataset '{self.reader.directory}': has no field '{name}' (written before "
                                 "suctionbench stored it); this network reads it: regenerate the dataset, or "
                                 "train an architecture that does not read it (dn3, compact)")

    def _by_shard(self, indices: np.ndarray) -> dict[int, np.ndarray]:
        """Ascending global `indices` as {shard: its local rows}; InputError if a shard they refer
        to is missing or smaller."""
        dps = self.reader.datapoints_per_shard
        shard_of = indices // dps
        available = set(self.reader.shard_indices)
        local_rows: dict[int, np.ndarray] = {}
        for shard in np.unique(shard_of).tolist():
            lo, hi = np.searchsorted(shard_of, [shard, shard + 1])
            local = indices[lo:hi] - shard * dps
            if shard not in available or local[-1] >= self.reader.shard_size(shard):
                raise InputError(f"split '{self.kind}/{self.part}' of '{self.reader.directory}': refers to "
                                 f"datapoints of shard {shard}, which is missing or smaller (dataset incomplete?)")
            local_rows[shard] = local.astype(np.int64)
        return local_rows

    @property
    def shards(self) -> list[int]:
        """Shards holding at least one datapoint of the split, ascending."""
        return sorted(self._local)

    def rows(self, shard: int) -> np.ndarray:
        """The split's rows of `shard` (indices within the shard, ascending): `load_shard`'s order,
        for reading other fields of the same datapoints (`reader.shard(shard, fields=...)[name][rows]`)."""
        return self._local[shard]

    def values(self, name: str) -> np.ndarray:
        """Field `name` of the split's datapoints, in index order (the order `batches` streams them
        unshuffled and `evaluate` scores them): e.g. their image ids or seal flags beside the scores."""
        parts = [self.reader.shard(shard, fields=[name])[name][self.rows(shard)] for shard in self.shards]
        return np.concatenate(parts) if parts else np.zeros(0)

    def subset(self, count: int, rng: np.random.Generator) -> SplitData:
        """At most `count` of this split's datapoints, sharing its reader: its datapoints in whole
        shards taken in a random order (drawn with `rng`), the last one cut to make up the count.
        Whole shards, so scoring the subset reads few files (`train`'s fit check after every
        epoch: 20,000 of a 2.8 M-datapoint dataset's random rows would touch every shard)."""
        order = rng.permutation(self.shards)
        local, total = {}, 0
        for shard in order.tolist():
            if total >= count:
                break
            rows = self._local[shard][: count - total]
            local[shard], total = rows, total + len(rows)
        part = copy.copy(self)
        part._local, part.num_datapoints = dict(sorted(local.items())), total
        return part

    def load_shard(self, shard: int) -> Batch:
        """The split's datapoints of one shard, in index order; images (n, C, 32, 32)."""
        extra = [OBJECT_CONTEXT_FIELD] if self.object_context else []
        arrays = self.reader.shard(shard, fields=[*self.image_fields, POSE_FIELD, *extra, METRIC_FIELD])
        local = self._local[shard]
        images = np.stack([arrays[name][local, ..., 0] for name in self.image_fields], axis=1)
        poses = arrays[POSE_FIELD][local][:, list(POSE_COLUMNS)]
        if self.object_context:
            poses = np.concatenate([poses, arrays[OBJECT_CONTEXT_FIELD][local]], axis=1)
        return Batch(images, poses, arrays[METRIC_FIELD][local])

    def _pools(self, shards: list[int], pool_size: int) -> Iterator[Batch]:
        groups = [shards[i:i + pool_size] for i in range(0, len(shards), pool_size)]
        threads = self.load_threads

        def load(group: list[int]) -> Batch:
            if threads <= 1 or len(group) <= 1:
                return _concat([self.load_shard(s) for s in group])
            with ThreadPoolExecutor(max_workers=min(threads, len(group))) as pool:
                return _concat(list(pool.map(self.load_shard, group)))  # in the group's order

        return _load_ahead(load, groups)

    def batches(self, batch_size: int, rng: np.random.Generator | None = None,
                shuffle_shards: int = SHUFFLE_SHARDS) -> Iterator[Batch]:
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
        """Normalisation statistics of this split in one streaming pass over its shards (per image channel)."""
        image, pose = _Moments(), _Moments()
        channels = len(self.image_fields)
        for batch in self._pools(self.shards, 1):
            image.add(np.moveaxis(batch.images, 1, -1).reshape(-1, channels))
            pose.add(batch.poses)
        if pose.n == 0:
            raise InputError(f"split '{self.kind}/{self.part}' of '{self.reader.directory}': no datapoints")
        return NormStats(tuple(float(x) for x in image.mean), tuple(float(x) for x in image.std()),
                         tuple(float(x) for x in pose.mean), tuple(float(x) for x in pose.std()), count=pose.n)


def _concat(batches: list[Batch]) -> Batch:
    if len(batches) == 1:
        return batches[0]
    return Batch(*(np.concatenate([getattr(b, name) for b in batches]) for name in ("images", "poses", "metric")))


def _take(batch: Batch, index: np.ndarray) -> Batch:
    return Batch(batch.images[index], batch.poses[index], batch.metric[index])


def to_tensors(batch: Batch, device: torch.device | str = "cpu") -> tuple[torch.Tensor, torch.Tensor]:
    """Images (B, C, 32, 32) and poses (B, P) float32 tensors on `device`, still in physical units."""
    images = torch.from_numpy(np.ascontiguousarray(batch.images, dtype=np.float32))
    poses = torch.from_numpy(np.ascontiguousarray(batch.poses, dtype=np.float32))
    return images.to(device, non_blocking=True), poses.to(device, non_blocking=True)
