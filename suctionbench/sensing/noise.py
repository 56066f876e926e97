"""The Dex-Net depth-image noise model y = alpha * y_hat + eps (Dex-Net 2.0 / 3.0, "Observations").

alpha is one multiplicative factor per image, Gamma-distributed with mean 1 (a ~3 % scale error, as
from a depth-calibration error), and eps is a spatially correlated Gaussian field (a smooth, wavy
surface error of a few millimetres). Noise is applied only where the sensor returned a depth
(pixels > 0): "no return" stays 0.

The correlated field
--------------------
The paper calls eps "Gaussian Process noise with sigma = 0.005 and kernel bandwidth sqrt(2) px".
gqcnn (the public training code) does not sample a GP: it draws independent N(0, sigma^2) values
on a coarse grid of 1/`gp_rescale_factor` the image size and resizes it bicubically to the image.
This module does the same, with the paper's kernel made precise:

1. Coarse samples sit every r = `gp_rescale_factor` image pixels, pixel-centre aligned as in an
   image resize by r: coarse sample k lies at image coordinate (k + 0.5) r - 0.5 (so coarse sample
   0 is the centre of the first r x r block). The coarse grid covers the image plus two samples on
   every side, so every pixel has the cubic kernel's full 4 x 4 support and the field has no
   border artefacts (PIL's resize, used by gqcnn, instead renormalises the kernel at the border).
2. The coarse samples are a GP sample with marginal N(0, sigma^2) and the squared-exponential
   kernel k(d) = sigma^2 exp(-d^2 / (2 l^2)), d the distance in *image* pixels and
   l = `gp_bandwidth_px`. The kernel is separable in rows and columns, so the coarse field is
   L_y Z L_x^T with Z white and L L^T the 1-D kernel matrices. At the paper's values
   (l = sqrt(2) px, r = 4 px) neighbouring coarse samples correlate by exp(-r^2 / (2 l^2)) =
   exp(-4) = 1.8 %, i.e. they are practically gqcnn's independent draws; l = 0 gives exactly
   gqcnn's white coarse grid.
3. The coarse field is interpolated to every image pixel with the bicubic convolution kernel of
   Keys (a = -0.5), the kernel of PIL's BICUBIC resize that gqcnn's `imresize(..., 'bicubic')`
   calls. (Not scipy.ndimage.zoom(order=3), which is a B-spline with a different spectrum and
   ties output size to a corner-aligned grid.)

Steps 2 and 3 are linear, so the field is exactly sigma * M_y Z M_x^T with fixed matrices
M = A L (A the interpolation weights): one pair of small matrix products per image, the same
operator in numpy and torch, and an exactly known covariance.

What the two length parameters mean. The field's correlation length is set by
`gp_rescale_factor`: interpolation makes it smooth below r pixels and nearly uncorrelated beyond
r (autocorrelation along a row or column at the defaults, pooled over the image and computed
exactly from M: 0.92 at 1 px, 0.70 at 2 px, 0.17 at 4 px, -0.04 at 8 px; it falls to 1/2 at
2.7 px = 0.68 r, and for l << r this half-width scales linearly with r). `gp_bandwidth_px`
only correlates the coarse samples; it starts to lengthen the field's correlation once it is
comparable with r, and for l >> r the field approaches an SE-kernel GP of bandwidth l. The paper's
sqrt(2) px therefore leaves gqcnn's behaviour in place.

Variance. Interpolation averages independent samples, so between coarse nodes the variance
drops: at a pixel with fractional coarse offsets (t_u, t_v) the variance is
sigma^2 S(t_u) S(t_v), where S(t) is the sum of the squared Keys weights (1 at a node, 0.69 to
0.94 at the four pixel phases of r = 4). The root-mean-square standard deviation over the image
is sqrt(mean S(t_u) x mean S(t_v)) = mean S = 0.814 sigma for white coarse samples and r = 4 (the
mean over phases tends to the integral of the squared kernel, 0.814, so it barely depends on r;
0.819 at l = sqrt(2), where the 1.8 % coarse correlation adds a little): the field's pixel std is
~4.1 mm, not 5 mm. `gp_field_std` returns the exact value for any config.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from suctionbench.errors import InputError

if TYPE_CHECKING:
    import torch


@dataclass(frozen=True)
class DepthNoiseConfig:
    """Parameters of the depth noise model y = alpha * y_hat + eps (defaults: the paper's)."""

    gamma_shape: float = 1000.0
    """Shape k of the multiplicative factor alpha ~ Gamma(k, theta). Paper: 1000. alpha has mean
    k theta and standard deviation sqrt(k) theta (1 and 0.0316 at the defaults)."""

    gamma_scale: float = 0.001
    """Scale theta of alpha ~ Gamma(k, theta). Paper: 0.001 = 1 / k, so that alpha has mean 1."""

    gp_sigma: float = 0.005
    """Marginal standard deviation (m) of the coarse samples of the additive field eps. Paper:
    0.005. Bicubic interpolation lowers the image-average std to ~0.81 x this (see the module
    docstring and `gp_field_std`)."""

    gp_bandwidth_px: float = math.sqrt(2.0)
    """Bandwidth l (image pixels) of the squared-exponential kernel exp(-d^2 / (2 l^2)) that
    correlates the coarse samples. Paper: sqrt(2) px. With l << `gp_rescale_factor` the coarse
    samples are practically independent (gqcnn's white grid; 0 gives it exactly) and the field's
    correlation length is set by the rescale factor; l only lengthens it once l is comparable
    with the coarse spacing."""

    gp_rescale_factor: float = 4.0
    """Spacing r (image pixels) of the coarse grid that is interpolated bicubically to the image,
    gqcnn's `gaussian_process_scaling_factor` (4.0 for Dex-Net 3.0). The field is smooth over less
    than r pixels and decorrelates beyond r (autocorrelation 1/2 at ~0.68 r)."""

    def __post_init__(self) -> None:
        checks = {
            "gamma_shape": self.gamma_shape > 0,
            "gamma_scale": self.gamma_scale > 0,
            "gp_sigma": self.gp_sigma >= 0,
            "gp_bandwidth_px": self.gp_bandwidth_px >= 0,
            "gp_rescale_factor": self.gp_rescale_factor >= 1,
        }
        for key, ok in checks.items():
            value = getattr(self, key)
            if not (isinstance(value, int | float) and math.isfinite(value) and ok):
                need = ">= 1" if key == "gp_rescale_factor" else ">= 0" if key.startswith("gp_") else "> 0"
                raise InputError(f"depth noise config: {key} = {value!r} must be a finite number {need}")


DEPTH_NOISE_PAPER = DepthNoiseConfig()
"""The paper's noise model: alpha ~ Gamma(1000, 0.001), sigma 5 mm, l = sqrt(2) px, r = 4 (gqcnn)."""


# --------------------------------------------------------------------------------------------------
# numpy
# --------------------------------------------------------------------------------------------------


def sample_gamma(rng: np.random.Generator, config: DepthNoiseConfig = DEPTH_NOISE_PAPER, size=None):
    """Draw the multiplicative factor alpha ~ Gamma(gamma_shape, gamma_scale): a float, or an
    array of shape `size`."""
    value = rng.gamma(config.gamma_shape, config.gamma_scale, size=size)
    return float(value) if size is None else value


def _keys_cubic(x: np.ndarray, a: float = -0.5) -> np.ndarray:
    """Keys' cubic convolution kernel (a = -0.5: PIL's BICUBIC); interpolating, support (-2, 2)."""
    x = np.abs(x)
    near = ((a + 2.0) * x - (a + 3.0)) * x * x + 1.0
    far = ((a * x - 5.0 * a) * x + 8.0 * a) * x - 4.0 * a
    return np.where(x <= 1.0, near, np.where(x < 2.0, far, 0.0))


@lru_cache(maxsize=64)
def _gp_operator(n: int, rescale: float, bandwidth: float) -> np.ndarray:
    """The (n, m) matrix M = A L along one image axis of n pixels (see the module docstring):
    coarse white noise z (m,) becomes the field sigma * M z along that axis. Read-only, cached."""
    m = math.ceil(n / rescale) + 4  # coarse samples k = -2 .. ceil(n / r) + 1
    k = np.arange(m) - 2.0
    coarse = (np.arange(n) + 0.5) / rescale - 0.5  # pixel i in coarse coordinates
    interp = _keys_cubic(coarse[:, None] - k[None, :])  # (n, m); rows sum to 1
    if bandwidth > 0:
        dist = (k[:, None] - k[None, :]) * rescale  # image pixels
        kernel = np.exp(-0.5 * (dist / bandwidth) ** 2)
        # Symmetric square root via eigh: robust when the kernel matrix is nearly singular (l >> r),
        # where a Cholesky factorisation would need jitter.
        vals, vecs = np.linalg.eigh(kernel)
        interp = interp @ (vecs * np.sqrt(np.clip(vals, 0.0, None))) @ vecs.T
    interp.setflags(write=False)
    return interp


def _operators(height: int, width: int, config: DepthNoiseConfig) -> tuple[np.ndarray, np.ndarray]:
    if height < 1 or width < 1:
        raise ValueError(f"image size must be positive, got {height} x {width}")
    r, ell = float(config.gp_rescale_factor), float(config.gp_bandwidth_px)
    return _gp_operator(int(height), r, ell), _gp_operator(int(width), r, ell)


def sample_gp_field(
    rng: np.random.Generator, height: int, width: int, config: DepthNoiseConfig = DEPTH_NOISE_PAPER
) -> np.ndarray:
    """One additive noise field eps, float32 (height, width) in metres.

    Draws the coarse white noise in one call (shape (ceil(H / r) + 4, ceil(W / r) + 4)), so the
    field is a deterministic function of the generator state.
    """
    m_y, m_x = _operators(height, width, config)
    z = rng.standard_normal((m_y.shape[1], m_x.shape[1]))
    return (config.gp_sigma * (m_y @ z @ m_x.T)).astype(np.float32)


def gp_field_std(height: int, width: int, config: DepthNoiseConfig = DEPTH_NOISE_PAPER) -> float:
    """Exact root-mean-square (over the image's pixels) standard deviation of `sample_gp_field`.

    The pixel variance is sigma^2 |M_y[i]|^2 |M_x[j]|^2 (the field is sigma M_y Z M_x^T with white
    Z); this averages it over the image: 0.819 sigma at the defaults (0.814 sigma for l = 0).
    """
    m_y, m_x = _operators(height, width, config)
    return float(config.gp_sigma * math.sqrt(np.mean(np.sum(m_y**2, axis=1)) * np.mean(np.sum(m_x**2, axis=1))))


def apply_depth_noise(
    depth: np.ndarray, rng: np.random.Generator, config: DepthNoiseConfig = DEPTH_NOISE_PAPER
) -> np.ndarray:
    """A noisy copy (float32) of a depth image (H, W) in metres: alpha * depth + eps where
    depth > 0, 0 elsewhere.

    Draws alpha, then the field (in that order). A pixel the noise would push to depth <= 0 (only
    possible for depths within centimetres of the camera, outside every sensor's range) becomes 0,
    "no return", because a non-positive depth has no meaning downstream.
    """
    depth = np.asarray(depth)
    if depth.ndim != 2:
        raise ValueError(f"depth image must have shape (H, W), got {depth.shape}")
    alpha = sample_gamma(rng, config)
    field = sample_gp_field(rng, depth.shape[0], depth.shape[1], config)
    noisy = alpha * depth.astype(np.float32) + field
    return np.where((depth > 0) & (noisy > 0), noisy, np.float32(0.0)).astype(np.float32)


# --------------------------------------------------------------------------------------------------
# torch (training augmentation)
# --------------------------------------------------------------------------------------------------


def sample_gamma_torch(
    n: int, generator: torch.Generator, config: DepthNoiseConfig = DEPTH_NOISE_PAPER, *, dtype=None
) -> torch.Tensor:
    """n draws of alpha ~ Gamma(gamma_shape, gamma_scale) on the generator's device.

    torch's own Gamma sampler takes no generator, so this is Marsaglia & Tsang's exact rejection
    method (2000), vectorised: every round draws a normal and a uniform for each still-unaccepted
    sample (acceptance > 99 % per round for shape >= 1; shapes below 1 use the boost
    Gamma(k) = Gamma(k + 1) U^(1/k)). Deterministic given the generator state.
    """
    import torch

    shape = float(config.gamma_shape)
    boost = shape < 1.0
    d = (shape + 1.0 if boost else shape) - 1.0 / 3.0
    c = 1.0 / math.sqrt(9.0 * d)
    device = generator.device
    out = torch.empty(n, dtype=torch.float64, device=device)
    pending = torch.arange(n, device=device)
    while pending.numel():
        x = torch.randn(pending.numel(), generator=generator, dtype=torch.float64, device=device)
        u = torch.rand(pending.numel(), generator=generator, dtype=torch.float64, device=device)
        v = (1.0 + c * x) ** 3
        ok = (v > 0) & (torch.log(u) < 0.5 * x * x + d - d * v + d * torch.log(v.clamp_min(1e-300)))
        out[pending[ok]] = d * v[ok]
        pending = pending[~ok]
    if boost:
        u = torch.rand(n, generator=generator, dtype=torch.float64, device=device)
        out = out * u ** (1.0 / shape)
    out = out * config.gamma_scale
    return out if dtype is None else out.to(dtype)


def apply_depth_noise_torch(
    images: torch.Tensor,
    generator: torch.Generator,
    config: DepthNoiseConfig = DEPTH_NOISE_PAPER,
    prob: float = 1.0,
    *,
    gp_prob: float = 1.0,
    field_channels: int | None = None,
) -> torch.Tensor:
    """Batched noise for training augmentation: a new tensor like `images` (B, C, H, W), depth in
    metres, with its own alpha and field per sample.

    Each sample is noised with probability `prob`; a noised sample gets alpha * y (one alpha for
    all its channels) and, with probability `gp_prob`, also the field, added to its first
    `field_channels` channels (None: all of them, the same field). Only pixels > 0 change, and,
    as in `apply_depth_noise`, a pixel pushed to <= 0 becomes 0. gqcnn's Dex-Net 3.0 recipe is
    `prob=1.0, gp_prob=0.5` (Gamma noise on every image, the GP field on half of them).

    Every call draws the same amount from the generator whatever is selected (uniforms for the
    two choices, B alphas, B coarse noise grids, in that order), so results are deterministic and
    the stream stays aligned. Draws happen on the generator's device; the result is on the
    images' device.
    """
    import torch

    if images.ndim != 4:
        raise ValueError(f"images must have shape (B, C, H, W), got {tuple(images.shape)}")
    if not (0.0 <= prob <= 1.0 and 0.0 <= gp_prob <= 1.0):
        raise ValueError(f"prob = {prob} and gp_prob = {gp_prob} must lie in [0, 1]")
    b, _, h, w = images.shape
    gdev = generator.device
    apply = torch.rand(b, generator=generator, device=gdev) < prob
    add_gp = apply & (torch.rand(b, generator=generator, device=gdev) < gp_prob)
    alpha = sample_gamma_torch(b, generator, config)
    m_y, m_x = _operators(h, w, config)
    z = torch.randn(b, m_y.shape[1], m_x.shape[1], generator=generator, dtype=torch.float64, device=gdev)

    dev, dtype = images.device, images.dtype
    alpha = torch.where(apply, alpha, torch.ones_like(alpha)).to(device=dev, dtype=dtype)
    t_y = torch.from_numpy(np.array(m_y)).to(device=dev, dtype=dtype)
    t_x = torch.from_numpy(np.array(m_x)).to(device=dev, dtype=dtype)
    field = t_y @ z.to(device=dev, dtype=dtype) @ t_x.T  # (B, H, W)
    field = field * (config.gp_sigma * add_gp.to(device=dev, dtype=dtype))[:, None, None]
    field = field[:, None] if field_channels is None else \
        field[:, None] * (torch.arange(images.shape[1], device=dev) < field_channels).to(dtype)[None, :, None, None]
    noisy = alpha[:, None, None, None] * images + field
    valid = images > 0
    return torch.where(valid & (noisy > 0), noisy, torch.where(valid, torch.zeros_like(images), images))


@dataclass(frozen=True)
class AxialNoiseConfig:
    """Per-pixel axial noise of a structured-light sensor (Nguyen et al. 2012, for PrimeSense
    technology): sigma(z) = base + quadratic (z - offset)^2. This is the simulated camera the
    robot looks through; the Dex-Net model above (with its ~3 % global scale factor) is the
    training-data augmentation, deliberately harsher than a calibrated sensor."""

    base: float = 0.0012
    """Noise std (m) at the sensor's best distance."""

    quadratic: float = 0.0019
    """Growth of the std (m per m^2) with the squared distance beyond `offset`."""

    offset: float = 0.4
    """Distance (m) of the smallest noise."""


def apply_axial_noise(
    depth: np.ndarray, rng: np.random.Generator, config: AxialNoiseConfig | None = None
) -> np.ndarray:
    """Independent Gaussian axial noise per pixel with depth-dependent std (zeros stay zero)."""
    config = config or AxialNoiseConfig()
    depth = np.asarray(depth, dtype=np.float32)
    sigma = config.base + config.quadratic * (depth - config.offset) ** 2
    noisy = depth + (sigma * rng.standard_normal(depth.shape)).astype(np.float32)
    return np.where(depth > 0, np.maximum(noisy, 0.0), 0.0).astype(np.float32)


NOISE_MODELS = ("paper", "sensor", "none")
"""Noise a dataset's images get (`dataset.generate.GenerationConfig.noise_model`): the paper's
model (`apply_depth_noise`, the training augmentation), the simulated sensor's
(`apply_axial_noise`, what the benchmark's robot sees), or none (an ideal sensor: how much of a
network's error the sensor's noise causes)."""

NO_AXIAL_NOISE = AxialNoiseConfig(base=0.0, quadratic=0.0)
"""The sensor model at zero std: "none" draws what "sensor" draws and adds nothing, so a dataset
without noise is its sensor-noise twin (same scenes, grasps and labels) but for the images."""


def check_noise_model(name: str) -> None:
    """InputError naming `--noise` unless `name` is one of NOISE_MODELS."""
    if name not in NOISE_MODELS:
        raise InputError(f"--noise '{name}': unknown (known: {', '.join(NOISE_MODELS)})")


def noisy_image(depth: np.ndarray, rng: np.random.Generator, model: str,
                paper: DepthNoiseConfig = DEPTH_NOISE_PAPER) -> np.ndarray:
    """A noisy copy of a rendered depth image under noise model `model` (NOISE_MODELS; "paper"
    with the parameters `paper`), drawn from `rng` ("none": the depth itself, after the draws
    "sensor" makes)."""
    check_noise_model(model)
    if model == "paper":
        return apply_depth_noise(depth, rng, paper)
    return apply_axial_noise(depth, rng, NO_AXIAL_NOISE if model == "none" else None)
