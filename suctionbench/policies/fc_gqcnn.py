"""The dense suction policy: a GQ-CNN scored at every valid pixel at once (FC-GQ-CNN, beyond Dex-Net
3.0; Dex-Net 4.0's fully convolutional GQ-CNN, Satish et al., RA-L 2019).

Algorithm (one `plan`)
----------------------
1. The valid pixels of the observation (`base.scene_cloud`, as the CEM policy's seeds): each one a
   grasp, its approach minus the smoothed normal there, its pose vector [gripper depth, approach
   angle] and the image angle of its approach (`thumbnails.project_grasps`).
2. The thumbnail network sees each grasp in a crop turned to that image angle. A dense pass needs
   one image per angle, so the angles are binned into `rotations` bins (16: at most 11.25 deg
   from the exact turn) and, per bin, the depth image is resampled on a lattice of the thumbnail's
   pitch (3 pixels for gqcnn's 96-pixel crop; bilinear point samples as `extract_thumbnails`
   takes them, by `thumbnails.affine_sample`) turned to the bin's angle, covering that bin's
   pixels. Every 32 x 32 window of the lattice is then the thumbnail of the grasp at its centre,
   and `learning.dense.DenseGQCNN` scores them: its trunk once over all bins' lattices, stacked
   into one batch of a common shape (`lattice_batch`: one call per stream instead of 16 small
   ones), its head at the window nearest each pixel. Windows
   are scored `window_pitch` (3) pixels apart at the finest: a finer thumbnail (a 48-pixel crop's
   1.5-pixel pitch) scores every second window of its lattice (`lattice_stride`; the trunk's first
   pool keeps its stride), so a pixel's window is at most 2.1 pixels off, the half-diagonal of
   3 pixels, whatever the crop. About 9 neighbouring pixels share a window, so its fully
   connected features and their share of the merge's first layer are computed once per window;
   only the pose stream and the rest of the merge run per pixel (`DenseGQCNN.merge`).
3. The quality map is q at every valid pixel (NaN elsewhere). The `refine` best pixels are scored
   again exactly (their own thumbnails at their own angles, `GQCNNPolicy.score`), and the best of
   those is the grasp, so the reported q is the network's own for the grasp executed (with
   `refine` 0, the dense map's best and its dense q).

A context network (two image streams) gets a second lattice per bin, of the context thumbnail's
9-pixel pitch, resampled from the box-filtered image (`thumbnails.sampled_image`) as its context
thumbnails are; each pixel reads its nearest window of each lattice (the context window at most
6.4 pixels off, under a context thumbnail pixel).

The model is a trained VALID-padded GQ-CNN (`compact`, `context`, `context-wide`; `load_model`),
the same the CEM policy reads; `make_fc_gqcnn_policy()` loads the shipped one.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.errors import InputError
from suctionbench.policies.base import GraspAction, Observation, SamplerConfig, configured, scene_cloud
from suctionbench.policies.gqcnn import (
    CEMConfig,
    GQCNNPolicy,
    LazyModel,
    adv_model,
    grasp_thumbnail,
    network_poses,
    pose_dim,
    resolve_model,
    seen_object,
)
from suctionbench.sensing.thumbnails import (
    THUMBNAIL_CONTEXT,
    THUMBNAIL_GQCNN,
    ThumbnailConfig,
    affine_sample,
    project_grasps,
    thumbnail_axes,
)


@dataclass(frozen=True)
class DenseConfig:
    """Settings of the dense policy."""

    rotations: int = 16
    """Bins of the approach's image angle, one resampled image each (16: within 11.25 deg)."""

    refine: int = 8
    """Best pixels of the dense map scored again exactly (own thumbnail and angle); 0: none."""

    sampler: SamplerConfig = field(default_factory=SamplerConfig)
    """Which pixels are grasps (the CEM policy's seed sampler)."""

    thumbnail: ThumbnailConfig = THUMBNAIL_GQCNN
    """The thumbnail for a model that states none (its crop and size set the lattice's pitch); a
    trained model reads the one its dataset was cut with (`gqcnn.grasp_thumbnail`)."""

    context_thumbnail: ThumbnailConfig = THUMBNAIL_CONTEXT
    """The context thumbnail a two-stream (context) network was trained on: its own lattice, 3x
    coarser, sampled from the box-filtered image (`thumbnails.sampled_image`)."""

    window_pitch: float = 3.0
    """Image pixels between neighbouring windows of a lattice, at least: a stream whose thumbnail
    pitch is finer scores only every `stride`-th window along each axis (`lattice_stride`), its
    trunk that much cheaper (`DenseStream.trunk`); each pixel reads its nearest scored window, at
    most half the diagonal of that pitch off, and `refine` rescores the best exactly. 3.0: the
    96 px grasp thumbnail's own pitch, so a 48 px model's windows are as dense as a 96 px one's."""

    quality_sigma: float = 0.0
    """Standard deviation (pixels) of a Gaussian that smooths the quality map before its best pixels
    are taken, pixels that are no grasp counting as q = 0 (GG-CNN's filtered map, Morrison et al.,
    RSS 2018): a pixel ranks by its neighbourhood, so a lone spike of q and a grasp at the rim of
    a good region rank below the middle of one. 0: the raw map."""

    def __post_init__(self) -> None:
        if not (isinstance(self.quality_sigma, int | float) and math.isfinite(self.quality_sigma)
                and 0.0 <= self.quality_sigma <= 20.0):
            raise InputError(f"dense policy: quality_sigma = {self.quality_sigma!r} must be in [0, 20] pixels")
        if not (isinstance(self.rotations, int) and self.rotations >= 1):
            raise InputError(f"dense policy: rotations = {self.rotations!r} must be an integer >= 1")
        if not (isinstance(self.refine, int) and self.refine >= 0):
            raise InputError(f"dense policy: refine = {self.refine!r} must be an integer >= 0")
        if not (isinstance(self.window_pitch, int | float) and math.isfinite(self.window_pitch)
                and self.window_pitch > 0):
            raise InputError(f"dense policy: window_pitch = {self.window_pitch!r} must be a number > 0 (pixels)")


def lattice_stride(config: ThumbnailConfig, window_pitch: float, max_stride: int) -> int:
    """How many lattice steps apart a stream's scored windows lie: the largest power of 2 whose
    multiple of the thumbnail's pitch (1 / config.scale image pixels) is at most `window_pitch`,
    1 at least and `max_stride` at most (the stream's pools: `DenseStream.max_stride`)."""
    stride = 1
    while 2 * stride <= max_stride and 2 * stride / config.scale <= window_pitch + 1e-9:
        stride *= 2
    return stride


@dataclass(frozen=True)
class Lattices:
    """Every bin's lattice and each pixel's window in it (`lattice_batch`): sample (a, b) of bin k's
    lattice lies at image (u, v) = origin[k] + a down[k] + b right[k]."""

    origin: np.ndarray
    """(B, 2) image (u, v) of each lattice's sample (0, 0)."""

    down: np.ndarray
    """(B, 2) image step from one lattice row to the next: the thumbnail's pitch along its row axis d."""

    right: np.ndarray
    """(B, 2) image step from one lattice column to the next: the pitch along its column axis e."""

    shape: tuple[int, int]
    """(rows, cols) of every lattice."""

    windows: np.ndarray
    """(N, 2) = (row, col) of each pixel's window (its top-left sample) in its bin's lattice."""

    def points(self) -> np.ndarray:
        """The sample points (B, rows, cols, 2) = image (u, v)."""
        a = np.arange(self.shape[0])[None, :, None, None]
        b = np.arange(self.shape[1])[None, None, :, None]
        return self.origin[:, None, None] + a * self.down[:, None, None] + b * self.right[:, None, None]

    def sample(self, image: np.ndarray) -> np.ndarray:
        """The lattices' bilinear samples (B, rows, cols) float32 of `image` (`affine_sample`)."""
        return affine_sample(image, self.origin, self.down, self.right, self.shape)


def lattice_positions(pixels: np.ndarray, angle: float, config: ThumbnailConfig = THUMBNAIL_GQCNN,
                      stride: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """For grasp pixels (N, 2) = (u, v) turned by image angle `angle`: the lattice's sample points
    (rows, cols, 2) = image (u, v), and each pixel's nearest window (N, 2) = (row, col) of its
    top-left corner. Lattice point (a, b) is o + p (b e + a d), p the thumbnail's pitch in image
    pixels (1 / config.scale) and d, e its row and column axes (`thumbnails.thumbnail_axes`), so
    window (a0, b0) is the thumbnail centred on o + p ((b0 + c) e + (a0 + c) d), c = config.centre;
    with `stride`, the nearest window whose indices are multiples of it."""
    lattices = lattice_batch(pixels, np.zeros(len(pixels), dtype=np.intp), np.array([angle]), config, stride)
    return lattices.points()[0], lattices.windows


def lattice_batch(pixels: np.ndarray, bins: np.ndarray, angles: np.ndarray,
                  config: ThumbnailConfig = THUMBNAIL_GQCNN, stride: int = 1) -> Lattices:
    """`lattice_positions` for several angles at once: pixel i is turned by angles[bins[i]] (every
    bin holds at least one pixel: the bins in use numbered densely, as `quality` passes them). Every
    bin's lattice starts at its own pixels' corner and all share one shape (rows, cols), the largest
    any bin needs (a smaller bin's lattice runs on past its pixels), so they stack into one batch;
    each pixel's window in its bin's lattice is the nearest whose indices are multiples of `stride`
    (the trunk's, `lattice_stride`)."""
    d, e = thumbnail_axes(np.asarray(angles, dtype=float))  # (B, 2) each
    pitch, size = 1.0 / config.scale, config.out_size
    along = np.einsum("ij,ij->i", pixels, d[bins]) / pitch - config.centre
    across = np.einsum("ij,ij->i", pixels, e[bins]) / pitch - config.centre
    a_min, b_min = np.full(len(angles), np.inf), np.full(len(angles), np.inf)
    np.minimum.at(a_min, bins, along)
    np.minimum.at(b_min, bins, across)
    a_min, b_min = np.floor(a_min), np.floor(b_min)
    windows = stride * np.column_stack([np.rint((along - a_min[bins]) / stride),
                                        np.rint((across - b_min[bins]) / stride)]).astype(np.intp)
    shape = (int(windows[:, 0].max()) + size, int(windows[:, 1].max()) + size)
    origin = pitch * (b_min[:, None] * e + a_min[:, None] * d)
    return Lattices(origin=origin, down=pitch * d, right=pitch * e, shape=shape, windows=windows)


def _distinct(index: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(index, return_inverse=True)`` for integers in [0, size), by marking a table of
    `size` instead of sorting (a plan's angle bins, and its windows: ~10^5 slots, ~10^4 pixels)."""
    seen = np.zeros(size, dtype=bool)
    seen[index] = True
    values = np.flatnonzero(seen)
    rank = np.cumsum(seen) - 1
    return values, rank[index]


class FCGQCNNPolicy:
    """Dense suction policy (module docstring). `info` of a plan has `plan_time`, `relaxed`,
    `evaluations` (pixels scored), `rotations` used and `quality_map` (H, W) float32, q at every
    valid pixel and NaN elsewhere."""

    name = "fc-gqcnn"

    def __init__(self, model: Any, config: DenseConfig | None = None, **overrides: Any) -> None:
        self.model = model
        self.config = configured(config or DenseConfig(), overrides)
        cfg = self.config
        self.exact = GQCNNPolicy(model, CEMConfig(thumbnail=cfg.thumbnail, context_thumbnail=cfg.context_thumbnail,
                                                  sampler=cfg.sampler))
        """Scores the refined pixels with their own thumbnails (the CEM policy's scoring)."""
        self._dense = None

    def __repr__(self) -> str:
        return f"FCGQCNNPolicy({self.model!r}, {self.config})"

    def _network(self):
        """The loaded model and its dense form (built once)."""
        model = self.model.load() if isinstance(self.model, LazyModel) else self.model
        if self._dense is None:
            from suctionbench.learning.dense import DenseGQCNN
            from suctionbench.learning.models import IMAGE_SIZE

            network = getattr(model, "network", None)
            if network is None:
                raise InputError(f"dense policy: model {model!r} has no network to convert (a trained GQ-CNN)")
            for thumbnail in (grasp_thumbnail(model, self.config.thumbnail), self.config.context_thumbnail):
                if thumbnail.out_size != IMAGE_SIZE:
                    raise InputError(f"dense policy: thumbnail size {thumbnail.out_size}, the network reads "
                                     f"{IMAGE_SIZE} x {IMAGE_SIZE}")
            self._dense = DenseGQCNN(network).eval()
        return model, self._dense

    def quality(self, observation: Observation, cloud) -> dict[str, np.ndarray]:
        """Every valid pixel's grasp and its dense q (module docstring, steps 1-2), with the context
        image and the object's shape it read (None where the model reads neither), for the refinement."""
        import torch

        model, dense = self._network()
        cfg = self.config
        rows, cols = cloud.valid_pixels.T
        pixels, points, approaches = cloud.grasps_at(rows, cols)
        _, depths, angles = project_grasps(points, approaches, cloud.intrinsics)
        shape = seen_object(observation, cloud, cfg.sampler.table_height) if pose_dim(model) > 2 else None
        poses = network_poses(model, observation, cloud, depths, points, approaches, cfg.sampler.table_height, shape)
        step = 2.0 * math.pi / cfg.rotations
        bins = np.mod(np.rint(angles / step).astype(np.intp), cfg.rotations)
        views = self.exact.images(observation)  # (thumbnail config, image it samples) per image stream
        pose_in = model.stats.normalise_poses(torch.from_numpy(poses.astype(np.float32)))
        kinds, bin_of = _distinct(bins, cfg.rotations)  # the bins in use, and each pixel's among them
        with torch.no_grad():  # every bin's lattice in one batch: one resampling and one trunk pass per stream
            features, shared = [], []
            for stream, (thumbnail, image) in enumerate(views):
                trunk = dense.streams[stream]
                stride = lattice_stride(thumbnail, cfg.window_pitch, trunk.max_stride)
                lattices = lattice_batch(pixels, bin_of, kinds * step, thumbnail, stride)
                lattice, at = lattices.sample(image), lattices.windows
                mean, std = model.stats.channel(stream)
                lattice = ((lattice - mean) / std).astype(np.float32)
                maps = trunk.trunk(torch.from_numpy(lattice)[:, None], stride)
                # ~(pitch)^2 neighbouring pixels share a window: its features are computed once
                at = at // stride  # the window's position in the strided maps
                height, width = maps.shape[2:]
                flat, share = _distinct((bin_of * height + at[:, 0]) * width + at[:, 1], len(kinds) * height * width)
                batch, rest = np.divmod(flat, height * width)
                window = torch.from_numpy(np.stack([batch, *np.divmod(rest, width)]))
                features.append(trunk.features(maps, window[0], window[1], window[2], stride))
                shared.append(torch.from_numpy(share.reshape(-1)))
            logits = dense.merge(features, pose_in, shared)
            q = torch.softmax(logits, dim=1)[:, 1].double().numpy()
        return {"rows": rows, "cols": cols, "pixels": pixels, "points": points, "approaches": approaches,
                "poses": poses, "q": q, "rotations": len(kinds),
                "images": views, "shape": shape}

    def plan(self, observation: Observation, rng: np.random.Generator) -> GraspAction:
        start = time.perf_counter()
        cfg = self.config
        cloud = scene_cloud(observation, cfg.sampler)
        dense = self.quality(observation, cloud)
        q_map = np.full(cloud.valid.shape, np.nan, dtype=np.float32)
        q_map[dense["rows"], dense["cols"]] = dense["q"]
        rank = ranking(q_map, dense["rows"], dense["cols"], cfg.quality_sigma) if cfg.quality_sigma else dense["q"]
        best = int(np.argmax(rank))
        q = float(dense["q"][best])
        if cfg.refine:
            count = min(cfg.refine, len(dense["q"]))
            top = np.argpartition(-rank, count - 1)[:count]
            exact = self.exact.score(observation, cloud, dense["rows"][top], dense["cols"][top], dense["images"],
                                     dense["shape"])  # the images and object read once per plan
            pick = int(np.argmax(exact["q"]))
            best, q = int(top[pick]), float(exact["q"][pick])
        return GraspAction(
            point=dense["points"][best].copy(), approach=dense["approaches"][best].copy(),
            pixel=dense["pixels"][best].copy(), q=q, camera_pose=observation.camera_pose.copy(),
            policy=self.name,
            candidates={key: dense[key] for key in ("pixels", "points", "approaches", "poses", "q")},
            info={"plan_time": time.perf_counter() - start, "relaxed": cloud.relaxed, "chosen": best,
                  "evaluations": len(dense["q"]), "rotations": dense["rotations"], "quality_map": q_map},
        )


def ranking(q_map: np.ndarray, rows: np.ndarray, cols: np.ndarray, sigma: float) -> np.ndarray:
    """What the grasps at (rows, cols) rank by: the quality map (H, W; NaN where no grasp) smoothed by
    a Gaussian of `sigma` pixels, no-grasp pixels counting as q = 0 (`DenseConfig.quality_sigma`)."""
    from scipy import ndimage

    smooth = ndimage.gaussian_filter(np.nan_to_num(q_map.astype(np.float64), nan=0.0), sigma, mode="constant")
    return smooth[rows, cols]


def make_fc_gqcnn_policy(model: Any | str | Path | None = None, config: DenseConfig | None = None,
                         **overrides: Any) -> FCGQCNNPolicy:
    """Registry factory for "fc-gqcnn": `model` a loaded model (`load_model`), a model directory
    (loaded on first use), or None for the shipped default (InputError if it is not installed)."""
    return FCGQCNNPolicy(resolve_model(model), config, **overrides)


def make_fc_gqcnn_adv_policy(config: DenseConfig | None = None, **overrides: Any) -> FCGQCNNPolicy:
    """Registry factory for "fc-gqcnn-adv": the dense policy with the GQ-CNN (ADV) model (trained
    only on the adversarial set's objects). Not a row of the paper, whose ADV model planned with
    CEM; over six seeds of the adversarial set it is the ADV model's better policy there."""
    return FCGQCNNPolicy(adv_model(), config, **overrides)
