"""The GQ-CNN suction policy of Dex-Net 3.0: the cross-entropy method over grasp pixels, scored by a
grasp-quality network (gqcnn's CrossEntropyRobustGraspingPolicy with the Dex-Net 3.0 settings of
its replication configuration; Mahler et al., ICRA 2018).

Algorithm (one `plan`)
----------------------
1. Seeds: `num_seed_samples` distinct valid pixels drawn uniformly (`base.scene_cloud`: object
   pixels whose approach, minus the normal of the 1 px Gaussian-smoothed depth image, lies within
   60 deg of the optical axis and 80 deg of straight down).
2. Scoring a set of pixels: the grasp point is the depth pixel deprojected, the approach minus the
   smoothed normal there; the 32 x 32 thumbnail is cut from the raw depth image around the pixel
   (or its block means, for a model trained on those: `grasp_thumbnail`) and turned to the
   approach's image direction (`extract_thumbnails`), and the pose vector is
   [gripper depth, angle between the approach and the table's downward normal] (`pose_vector`,
   with the table normal brought into the camera frame by the camera pose). One batched
   `model.predict(thumbnails, poses)` gives each grasp's success probability. A model with
   ``image_channels == 2`` (the context nets) also gets each grasp's context thumbnail
   (`extract_context_thumbnails`, same pixel and angle, 288 px crop of 9 x 9 block means, the
   image filtered once per plan) as channel 1: thumbnails (N, 2, 32, 32), as in training.
3. `num_iters` times: take the top `elite_fraction` of the current set (ceil, at least 1), fit a
   Gaussian mixture with ceil(`gmm_component_frac` x elites) components to their pixel centres
   (u, v), the only features, standardised by the elites' mean and standard deviation (a zero
   standard deviation counts as 1) with `gmm_reg_covar` added to every covariance's diagonal in
   those units, as gqcnn does with scikit-learn; draw `num_gmm_samples` pixels from it (rounded to
   the nearest pixel, redrawn while they miss the valid pixels), and score them (step 2): depth and
   approach are always re-read from the image at the new pixel.
4. Return the best grasp seen in any round (gqcnn returns the best of the last round; keeping the
   best seen can only raise the result, and equals gqcnn's whenever the last round holds it).

Other departures from gqcnn, all small: mixture samples are rounded to the nearest pixel (gqcnn
truncates, a half-pixel bias), samples off the valid pixels are redrawn rather than dropped (every
round scores its full 50), resampled pixels must pass the seed sampler's angle limits (gqcnn
checks only the mask and the approach angle), and a zero elite standard deviation counts as 1 px
rather than 1e-6 (either way the samples round to the elites' common pixel).

The mixture is fitted by a small EM in numpy (`fit_gmm`, no scikit-learn): centres start at
distinct elites chosen with the policy's generator, one hard assignment to the nearest centre gives
the first parameters, then EM runs to scikit-learn's defaults (100 iterations, tolerance 1e-3 on
the mean log-likelihood). Every random draw comes from the generator passed to `plan`, so planning
is deterministic.

The network is anything with `predict(images (N, 32, 32) float32 metres, poses (N, P) float32)
-> (N,) probabilities` (duck typing), or, if its `image_channels` attribute is 2, with images
(N, 2, 32, 32) = (grasp, context); `make_policy("gqcnn")` loads one with
`suctionbench.learning.checkpoint.load_model`, from the shipped default model unless a model or a
model directory is given.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import numpy as np

from suctionbench.errors import InputError
from suctionbench.policies.base import (
    ADV_VARIANTS,
    GraspAction,
    Observation,
    SamplerConfig,
    SceneCloud,
    configured,
    scene_cloud,
)
from suctionbench.policies.plugins import builtin_name
from suctionbench.resources import asset_path
from suctionbench.sensing.object_context import ObjectShape, object_context
from suctionbench.sensing.thumbnails import (
    THUMBNAIL_CONTEXT,
    THUMBNAIL_GQCNN,
    ThumbnailConfig,
    extract_thumbnails,
    pose_vector,
    project_grasps,
    sampled_image,
)

DEFAULT_MODEL = ("models", "gqcnn-sensor48-wide-2m8-e4")
"""Path parts, under assets/, of the model `make_policy("gqcnn")` loads when given none."""

ADV_MODEL = ("models", "gqcnn-adv")
"""Path parts, under assets/, of the model trained only on the adversarial set's objects: the
paper's "GQ-CNN (ADV)" row, `make_policy("gqcnn-adv")` (and the other `ADV_VARIANTS`)."""

SHIPPED_MODELS = {"gqcnn": DEFAULT_MODEL, "fc-gqcnn": DEFAULT_MODEL, **dict.fromkeys(ADV_VARIANTS, ADV_MODEL)}
"""The shipped model each built-in GQ-CNN policy loads when given none."""


def model_used(policy: str, model: str | Path | None = None, policy_args: dict | None = None) -> str | None:
    """The model the policy spec `policy` plans with, as run logs record it: the directory it was
    given (a ``model`` policy option before `model`), else a built-in policy's shipped model as
    `assets/models/NAME`; None for a policy that reads no model. The default changes between
    releases, so a run must name the one it used."""
    name = builtin_name(policy)
    if name not in SHIPPED_MODELS:
        return None
    model = (policy_args or {}).get("model", model)
    return str(model) if model else "assets/" + "/".join(SHIPPED_MODELS[name])


@runtime_checkable
class GraspQualityModel(Protocol):
    """What the policy needs of a GQ-CNN: batched success probabilities. An optional
    ``image_channels`` attribute (default 1) of 2 asks for the context thumbnail as channel 1."""

    def predict(self, images: np.ndarray, poses: np.ndarray) -> np.ndarray: ...


def image_channels(model: Any) -> int:
    """Image channels `model` reads: its ``image_channels`` attribute, 1 if it has none."""
    return int(getattr(model, "image_channels", 1))


def grasp_thumbnail(model: Any, fallback: ThumbnailConfig) -> ThumbnailConfig:
    """The grasp thumbnail geometry and sampling `model` reads: its ``thumbnail`` attribute (a
    trained model states the one its dataset was cut with), `fallback` (the policy config's) if it
    states none."""
    stated = getattr(model, "thumbnail", None)
    return stated if isinstance(stated, ThumbnailConfig) else fallback


def pose_dim(model: Any) -> int:
    """Length of the pose vector `model` reads: its ``pose_dim`` attribute, 2 if it has none (8: the
    pose vector and the object context, `suctionbench.sensing.object_context`)."""
    return int(getattr(model, "pose_dim", 2))


def seen_object(observation: Observation, cloud: SceneCloud, table_height: float) -> ObjectShape | None:
    """The object the cloud segments, as the object context reads it (world frame, the table at
    `table_height`): computed once per plan and shared by its `network_poses` calls."""
    rotation, origin = observation.camera_pose[:3, :3], observation.camera_pose[:3, 3]
    return ObjectShape.of(cloud.object_points @ rotation.T + origin, table_height)


def network_poses(model: Any, observation: Observation, cloud: SceneCloud, depths: np.ndarray, points: np.ndarray,
                  approaches: np.ndarray, table_height: float, shape: ObjectShape | None = None) -> np.ndarray:
    """The pose vectors (N, 2) of grasps at camera-frame `points` along `approaches` at gripper
    `depths`, and, for a model that reads it, the object context (N, 6) of each, appended: where
    it lies on the object the cloud segments, in metres (world frame, the table at `table_height`;
    `shape`: that object's `seen_object`, computed here if not given)."""
    poses = pose_vector(depths, approaches, cloud.table_normal)
    if pose_dim(model) == 2:
        return poses
    if shape is None:
        shape = seen_object(observation, cloud, table_height)
    rotation, origin = observation.camera_pose[:3, :3], observation.camera_pose[:3, 3]
    context = object_context(shape, points @ rotation.T + origin, approaches @ rotation.T, table_height)
    return np.concatenate([poses, context], axis=1)


# --------------------------------------------------------------------------------------------------
# Configuration
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CEMConfig:
    """Cross-entropy method settings (gqcnn's Dex-Net 3.0 suction policy)."""

    num_seed_samples: int = 250
    """Pixels drawn uniformly for the first round. gqcnn: 250."""

    num_iters: int = 3
    """Refit-and-resample rounds after the seeds. gqcnn: 3."""

    num_gmm_samples: int = 50
    """Pixels drawn from the mixture in each round. gqcnn: 50."""

    elite_fraction: float = 0.25
    """Fraction of the current round's grasps, the best by predicted quality, that the mixture is
    fitted to (gqcnn's `gmm_refit_p`): ceil(0.25 x 250) = 63 elites of the seeds, 13 later."""

    gmm_component_frac: float = 0.4
    """Mixture components per elite: ceil(0.4 x elites) (gqcnn: 0.4), i.e. 26 and then 6."""

    gmm_reg_covar: float = 0.01
    """Added to the diagonal of every component covariance, in units of the elites' standard
    deviation (gqcnn passes it to scikit-learn as `reg_covar`, on standardised features): keeps
    components from collapsing onto single elites. gqcnn: 0.01."""

    gmm_max_iter: int = 100
    """EM iterations at most per fit (scikit-learn's default, which gqcnn keeps)."""

    gmm_tol: float = 1e-3
    """EM stops when the mean log-likelihood changes by less than this (scikit-learn's default)."""

    max_resample_rounds: int = 10
    """Mixture samples are drawn in batches of twice the shortfall and those off the valid pixels
    dropped; after this many batches a round goes on with the samples it has."""

    sampler: SamplerConfig = field(default_factory=SamplerConfig)
    """Valid grasp pixels and normal estimation: 60 deg to the optical axis (gqcnn: 30), 80 deg to
    straight down, 1 px depth smoothing (gqcnn's Dex-Net 3.0 configuration)."""

    thumbnail: ThumbnailConfig = THUMBNAIL_GQCNN
    """Thumbnail geometry and sampling for a model that states none (96 px crop scaled to 32 x 32,
    point samples); a trained model reads the one its dataset was cut with (`grasp_thumbnail`)."""

    context_thumbnail: ThumbnailConfig = THUMBNAIL_CONTEXT
    """Context thumbnail geometry, used only for a model with two image channels (288 px crop,
    9 x 9 block means, 32 x 32: what ``suctionbench generate`` stores)."""

    def __post_init__(self) -> None:
        for key in ("num_seed_samples", "num_gmm_samples", "gmm_max_iter", "max_resample_rounds"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
                raise InputError(f"CEM config: {key} = {value!r} must be a positive integer")
        if isinstance(self.num_iters, bool) or not isinstance(self.num_iters, int | np.integer) or self.num_iters < 0:
            raise InputError(f"CEM config: num_iters = {self.num_iters!r} must be a non-negative integer")
        for key in ("elite_fraction", "gmm_component_frac"):
            value = getattr(self, key)
            if not (isinstance(value, int | float) and 0.0 < value <= 1.0):
                raise InputError(f"CEM config: {key} = {value!r} must be in (0, 1]")
        for key in ("gmm_reg_covar", "gmm_tol"):
            value = getattr(self, key)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise InputError(f"CEM config: {key} = {value!r} must be a positive number")
        if not isinstance(self.sampler, SamplerConfig):
            raise InputError(f"CEM config: sampler = {self.sampler!r} must be a SamplerConfig")
        for key in ("thumbnail", "context_thumbnail"):
            if not isinstance(getattr(self, key), ThumbnailConfig):
                raise InputError(f"CEM config: {key} = {getattr(self, key)!r} must be a ThumbnailConfig")

    def elite_count(self, population: int) -> int:
        """Elites kept from a round of `population` grasps: max(ceil(fraction x population), 1)."""
        return max(math.ceil(self.elite_fraction * population), 1)

    def component_count(self, elites: int) -> int:
        """Mixture components for `elites` elites: max(ceil(frac x elites), 1)."""
        return max(math.ceil(self.gmm_component_frac * elites), 1)


# --------------------------------------------------------------------------------------------------
# Gaussian mixture (weighted EM, numpy)
# --------------------------------------------------------------------------------------------------


@dataclass
class GaussianMixture:
    """A full-covariance Gaussian mixture in D dimensions."""

    weights: np.ndarray
    """Component weights (K,), summing to 1."""

    means: np.ndarray
    """Component means (K, D)."""

    covariances: np.ndarray
    """Component covariances (K, D, D), symmetric positive definite."""

    def log_likelihood(self, x: np.ndarray) -> np.ndarray:
        """log p(x_i, component k) (N, K) = log w_k + log N(x_i; mu_k, Sigma_k)."""
        chol = np.linalg.cholesky(self.covariances)  # (K, D, D)
        diff = np.asarray(x, dtype=float)[None, :, :] - self.means[:, None, :]  # (K, N, D)
        solved = np.linalg.solve(chol, diff.transpose(0, 2, 1))  # L^-1 (x - mu), (K, D, N)
        mahalanobis = np.einsum("kdn,kdn->kn", solved, solved)
        log_det = 2.0 * np.log(np.diagonal(chol, axis1=1, axis2=2)).sum(axis=1)
        dim = self.means.shape[1]
        log_pdf = -0.5 * (mahalanobis + log_det[:, None] + dim * math.log(2.0 * math.pi))
        return (log_pdf + np.log(self.weights)[:, None]).T

    def sample(self, count: int, rng: np.random.Generator) -> np.ndarray:
        """`count` points (count, D): a component by weight, then a Gaussian draw from it."""
        component = rng.choice(len(self.weights), size=count, p=self.weights)
        noise = rng.standard_normal((count, self.means.shape[1]))
        chol = np.linalg.cholesky(self.covariances)
        return self.means[component] + np.einsum("nij,nj->ni", chol[component], noise)


def _m_step(x: np.ndarray, resp: np.ndarray, reg_covar: float) -> GaussianMixture:
    """Mixture parameters maximising the expected log-likelihood for responsibilities (N, K)."""
    counts = resp.sum(axis=0) + 10.0 * np.finfo(float).eps  # as scikit-learn: no empty component
    means = resp.T @ x / counts[:, None]
    diff = x[None, :, :] - means[:, None, :]
    covariances = np.einsum("nk,kni,knj->kij", resp, diff, diff) / counts[:, None, None]
    covariances += reg_covar * np.eye(x.shape[1])
    return GaussianMixture(counts / counts.sum(), means, covariances)


def fit_gmm(
    x: np.ndarray,
    n_components: int,
    rng: np.random.Generator,
    *,
    reg_covar: float = 0.01,
    max_iter: int = 100,
    tol: float = 1e-3,
) -> GaussianMixture:
    """Fit a full-covariance Gaussian mixture to points (N, D) by EM (see the module docstring).

    Components are capped at N. Initial centres: distinct points chosen by `rng`; each point is
    assigned to its nearest centre for the first M-step. Deterministic given the generator state.
    """
    x = np.asarray(x, dtype=float)
    if x.ndim != 2 or len(x) == 0:
        raise ValueError(f"fit_gmm needs points (N, D) with N > 0, got shape {x.shape}")
    k = max(1, min(int(n_components), len(x)))
    centres = x[rng.choice(len(x), size=k, replace=False)]
    nearest = np.argmin(((x[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2), axis=1)
    gmm = _m_step(x, np.eye(k)[nearest], reg_covar)
    previous = -np.inf
    for _ in range(max_iter):
        joint = gmm.log_likelihood(x)
        top = joint.max(axis=1, keepdims=True)
        log_norm = top[:, 0] + np.log(np.exp(joint - top).sum(axis=1))
        gmm = _m_step(x, np.exp(joint - log_norm[:, None]), reg_covar)
        mean_ll = float(log_norm.mean())
        if abs(mean_ll - previous) < tol:
            break
        previous = mean_ll
    return gmm


# --------------------------------------------------------------------------------------------------
# Models
# --------------------------------------------------------------------------------------------------


def default_model_dir() -> Path:
    """Directory of the shipped default GQ-CNN (assets/models/..., `DEFAULT_MODEL`)."""
    return asset_path(*DEFAULT_MODEL)


class LazyModel:
    """A model directory loaded on the first `predict` (loading imports torch)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        if not self.path.exists():
            raise InputError(f"GQ-CNN model '{self.path}' does not exist; pass model=PATH to a trained model")
        self._model: GraspQualityModel | None = None

    def load(self) -> GraspQualityModel:
        if self._model is None:
            from suctionbench.learning.checkpoint import load_model

            self._model = load_model(self.path)
        return self._model

    def predict(self, images: np.ndarray, poses: np.ndarray) -> np.ndarray:
        return self.load().predict(images, poses)

    @property
    def image_channels(self) -> int:
        """The loaded model's image channels (loads it)."""
        return image_channels(self.load())

    @property
    def pose_dim(self) -> int:
        """The loaded model's pose vector length (loads it)."""
        return pose_dim(self.load())

    @property
    def thumbnail(self) -> ThumbnailConfig | None:
        """The grasp thumbnail the loaded model was trained on (loads it)."""
        return getattr(self.load(), "thumbnail", None)

    def __repr__(self) -> str:
        return f"LazyModel('{self.path}')"


# --------------------------------------------------------------------------------------------------
# Policy
# --------------------------------------------------------------------------------------------------


class GQCNNPolicy:
    """Cross-entropy-method suction policy scored by a GQ-CNN (see the module docstring).

    The returned grasp's candidates hold every scored grasp: `pixels`, `points`, `approaches`, `q`,
    `poses` (N, P) pose vectors (`network_poses`) and `iteration` (N,) (0 for the seeds, then 1..num_iters). `info`
    has `plan_time`, `relaxed`, `evaluations`, `round_best_q` (best q of each round) and `chosen`.
    """

    name = "gqcnn"

    def __init__(self, model: GraspQualityModel, config: CEMConfig | None = None, **overrides: Any) -> None:
        if not callable(getattr(model, "predict", None)):
            raise InputError(f"GQ-CNN policy: model {model!r} has no predict(images, poses) method")
        self.model = model
        self.config = configured(config or CEMConfig(), overrides)

    def __repr__(self) -> str:
        return f"GQCNNPolicy({self.model!r}, {self.config})"

    def images(self, observation: Observation) -> list[tuple[ThumbnailConfig, np.ndarray]]:
        """Per image channel the model reads, its thumbnail config and the image it samples
        (`sampled_image`: block means filtered once per plan, not once per round)."""
        cfg = self.config
        views = [grasp_thumbnail(self.model, cfg.thumbnail)]
        if image_channels(self.model) == 2:
            views.append(cfg.context_thumbnail)
        return [(view, sampled_image(observation.depth, view)) for view in views]

    def score(
        self, observation: Observation, cloud: SceneCloud, rows: np.ndarray, cols: np.ndarray,
        images: list[tuple[ThumbnailConfig, np.ndarray]] | None = None, shape: ObjectShape | None = None,
    ) -> dict[str, np.ndarray]:
        """Grasps at pixels (rows, cols) with their pose vectors and predicted quality.

        Thumbnails (N, 32, 32) for a one-channel model; for a two-channel one (N, 2, 32, 32), the
        grasp thumbnail and the context thumbnail of the same grasp, cut from `images` (`images`,
        computed here if not given: `plan` computes them once). For a model that reads the object
        context, `shape` is the `seen_object` (likewise once per plan).
        """
        pixels, points, approaches = cloud.grasps_at(rows, cols)
        _, depths, angles = project_grasps(points, approaches, cloud.intrinsics)
        views = self.images(observation) if images is None else images
        channels = [extract_thumbnails(image, pixels, angles, view) for view, image in views]
        thumbnails = channels[0] if len(channels) == 1 else np.stack(channels, axis=1)
        poses = network_poses(self.model, observation, cloud, depths, points, approaches,
                              self.config.sampler.table_height, shape)
        q = np.asarray(self.model.predict(thumbnails, poses), dtype=float).reshape(-1)
        if q.shape != (len(rows),):
            raise RuntimeError(f"GQ-CNN model returned {q.shape} qualities for {len(rows)} grasps")
        q = np.where(np.isfinite(q), q, -np.inf)
        return {"pixels": pixels, "points": points, "approaches": approaches, "q": q, "poses": poses}

    def _resample(
        self, gmm: GaussianMixture, mean: np.ndarray, std: np.ndarray, cloud: SceneCloud, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        """(rows, cols) of `num_gmm_samples` mixture samples that land on valid pixels."""
        height, width = cloud.valid.shape
        wanted = self.config.num_gmm_samples
        rows, cols = np.empty(0, dtype=np.intp), np.empty(0, dtype=np.intp)
        for _ in range(self.config.max_resample_rounds):
            uv = np.rint(gmm.sample(2 * (wanted - len(rows)), rng) * std + mean)
            inside = (uv[:, 0] >= 0) & (uv[:, 0] < width) & (uv[:, 1] >= 0) & (uv[:, 1] < height)
            c, r = uv[inside, 0].astype(np.intp), uv[inside, 1].astype(np.intp)
            keep = cloud.valid[r, c]
            rows, cols = np.concatenate([rows, r[keep]]), np.concatenate([cols, c[keep]])
            if len(rows) >= wanted:
                break
        return rows[:wanted], cols[:wanted]

    def plan(self, observation: Observation, rng: np.random.Generator) -> GraspAction:
        start = time.perf_counter()
        cfg = self.config
        cloud = scene_cloud(observation, cfg.sampler)
        images = self.images(observation)
        shape = seen_object(observation, cloud, cfg.sampler.table_height) if pose_dim(self.model) > 2 else None
        rows, cols = cloud.sample(cfg.num_seed_samples, rng)
        rounds = [self.score(observation, cloud, rows, cols, images, shape)]
        for _ in range(cfg.num_iters):
            q = rounds[-1]["q"]
            elite = np.argsort(-q, kind="stable")[: cfg.elite_count(len(q))]
            features = np.column_stack([cols[elite], rows[elite]]).astype(float)  # pixel centres (u, v)
            mean, std = features.mean(axis=0), features.std(axis=0)
            std[std == 0] = 1.0
            gmm = fit_gmm((features - mean) / std, cfg.component_count(len(elite)), rng,
                          reg_covar=cfg.gmm_reg_covar, max_iter=cfg.gmm_max_iter, tol=cfg.gmm_tol)
            rows, cols = self._resample(gmm, mean, std, cloud, rng)
            if len(rows) == 0:
                break
            rounds.append(self.score(observation, cloud, rows, cols, images, shape))
        candidates = {key: np.concatenate([r[key] for r in rounds]) for key in rounds[0]}
        candidates["iteration"] = np.concatenate([np.full(len(r["q"]), i) for i, r in enumerate(rounds)])
        best = int(np.argmax(candidates["q"]))
        return GraspAction(
            point=candidates["points"][best].copy(), approach=candidates["approaches"][best].copy(),
            pixel=candidates["pixels"][best].copy(), q=float(candidates["q"][best]),
            camera_pose=observation.camera_pose.copy(), policy=self.name, candidates=candidates,
            info={
                "plan_time": time.perf_counter() - start, "relaxed": cloud.relaxed, "chosen": best,
                "evaluations": len(candidates["q"]), "round_best_q": [float(r["q"].max()) for r in rounds],
            },
        )


def make_gqcnn_policy(
    model: GraspQualityModel | str | Path | None = None, config: CEMConfig | None = None, **overrides: Any
) -> GQCNNPolicy:
    """Registry factory for "gqcnn": `model` is a model object (anything with `predict`), a model
    directory (loaded on first use), or None for the shipped default (`default_model_dir`).
    A missing directory raises InputError."""
    return GQCNNPolicy(resolve_model(model), config, **overrides)


def make_gqcnn_adv_policy(config: CEMConfig | None = None, **overrides: Any) -> GQCNNPolicy:
    """Registry factory for "gqcnn-adv" (Dex-Net 3.0's "GQ-CNN (ADV)"): the CEM policy with the
    shipped model trained only on datapoints of the adversarial set's objects (`ADV_MODEL`)."""
    return GQCNNPolicy(adv_model(), config, **overrides)


def adv_model() -> LazyModel:
    """The shipped GQ-CNN (ADV) model (`ADV_MODEL`), loaded on first use; InputError if it is not
    installed."""
    return shipped_model(asset_path(*ADV_MODEL), "adversarial-trained model")


def resolve_model(model: GraspQualityModel | str | Path | None) -> GraspQualityModel:
    """The model a GQ-CNN policy factory was given: a model object as it is, a model directory
    loaded on first use (`LazyModel`), or None for the shipped default (InputError if it is not
    installed)."""
    if model is None:
        return shipped_model(default_model_dir(), "default model")
    return LazyModel(model) if isinstance(model, str | Path) else model


def shipped_model(path: Path, what: str) -> LazyModel:
    """The model shipped at `path` under assets/ (`default_model_dir`, `ADV_MODEL`; `what` names it
    in the error), loaded on first use; InputError if it is not installed."""
    if not path.exists():
        raise InputError(f"GQ-CNN policy: no model given and the {what} '{path}' is not installed; pass "
                         "model=PATH (--model DIR for gqcnn and fc-gqcnn) to a trained model directory")
    return LazyModel(path)
