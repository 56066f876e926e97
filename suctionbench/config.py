"""Typed, frozen configuration for the suction model, with named presets and TOML round-trips.

Every physical parameter that matters lives here (SI units), not inside functions. The same
`CupConfig` describes the cup for the analytic labeller and for the simulated cup, so the two
describe the same hardware while computing independently.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

from suctionbench.errors import InputError


@dataclass(frozen=True)
class CupConfig:
    """A single circular suction cup, as modelled in Dex-Net 3.0 (section "Compliant Suction Contact Model")."""

    name: str = "default"
    """Preset name, recorded in labels, datasets and model cards."""

    n_vertices: int = 8
    """Number n of perimeter vertices of the quasi-static spring model (the paper's figure uses 8)."""

    radius: float = 0.0075
    """Cup radius r in metres: the 15 mm diameter silicone cup of the paper's experiments."""

    height: float = 0.015
    """Height h of the undeformed spring cone in metres (the paper leaves it unstated; a 15 mm
    single-bellow cup is about as tall as it is wide). Sets the rest length sqrt(r^2 + h^2) of the
    cone springs and so the approach-angle tolerance (about 14 degrees on a flat face at 10 %)."""

    stretch_limit: float = 0.10
    """Largest allowed relative change in length of any spring, |L - L0| / L0 (Provot 1995, used by
    the paper's appendix on seal formation)."""

    vacuum_force: float = 50e3 * math.pi * 0.0075**2
    """Constant vacuum force V in newtons pulling the object into the cup. Default: 50 kPa of
    vacuum over the cup area pi r^2 = 8.84 N, consistent with the real system's ~0.9 kg payload."""

    kappa: float = 50e3 * math.pi * 0.0075**2 / (2 * math.pi)
    """Material limit kappa (N per radian of ring) bounding the tilt amplitudes p_x, p_y of the ring
    pressure p(theta) = p0 + p_x cos(theta) + p_y sin(theta); elastic torques obey
    sqrt(2)|tau_x|, sqrt(2)|tau_y| <= pi r kappa. Default: V / (2 pi), the largest tilt amplitude
    that keeps every point of the lip in compression (p(theta) >= 0) under the vacuum preload
    alone (p0 = V / 2 pi), so the lip does not peel off."""

    friction: float = 0.5
    """Nominal Coulomb friction coefficient mu between cup and object (the mean of the paper's
    truncated-normal friction distribution)."""

    def __post_init__(self) -> None:
        checks = {
            "n_vertices": self.n_vertices >= 3,
            "radius": 0.0 < self.radius < 1.0,
            "height": 0.0 < self.height < 1.0,
            "stretch_limit": 0.0 < self.stretch_limit < 10.0,
            "vacuum_force": self.vacuum_force > 0.0,
            "kappa": self.kappa > 0.0,
            "friction": 0.0 <= self.friction <= 10.0,
        }
        for key, ok in checks.items():
            value = getattr(self, key)
            if not ok or (isinstance(value, float) and not math.isfinite(value)):
                raise InputError(f"cup config: {key} = {value!r} is out of range")

    @property
    def payload_kg(self) -> float:
        """Largest mass the vacuum alone can hold against gravity (V / g)."""
        return self.vacuum_force / STANDARD_GRAVITY


STANDARD_GRAVITY = 9.80665
"""Standard gravity in m/s^2."""

CUP_DEFAULT = CupConfig()
"""Physically grounded cup: V = 50 kPa x pi r^2, kappa = V / (2 pi)."""

CUP_PAPER = CupConfig(name="paper", vacuum_force=250.0, kappa=0.005)
"""The paper's literal values, V = 250 N and kappa = 0.005 (units as the paper states them)."""


CUP_PRESETS: dict[str, CupConfig] = {"default": CUP_DEFAULT, "paper": CUP_PAPER}


@dataclass(frozen=True)
class SealConfig:
    """Discretisation of the seal model (how densely the surface is probed), not physics."""

    edge_samples: int = 3
    """Surface points probed along each perimeter spring between its two vertices; the spring's
    deformed length is the length of the polyline through them (its path on the surface)."""

    interior_fractions: tuple[float, ...] = (0.5, 0.8)
    """Radial fractions of the contact ring at which the surface inside the ring is probed for
    holes and cone-face collisions (the axis itself is always probed). The outer ring is probed at
    every perimeter sample's bearing, the inner ones at the vertex bearings. Kept inside 0.8 r
    because the planar cone faces cut below a convex surface next to the lip, where the real
    membrane conforms (on a sphere just above the stretch-limit radius the face dips ~0.1 mm
    below the surface at 0.9 r but stays above it at 0.8 r)."""

    collision_tolerance: float = 2e-4
    """Depth in metres by which the surface may rise above a cone face before it counts as a
    collision: absorbs mesh tessellation and single-precision ray-cast error."""


@dataclass(frozen=True)
class PerturbationConfig:
    """The paper's environment model for robust wrench resistance ("Details of Distributions").

    The paper writes N(0, s I) without saying whether s is a variance; every value here is a
    standard deviation in SI units (FACTS.md section 2).
    """

    num_samples: int = 50
    """Monte-Carlo samples J per grasp; the label is the fraction of samples that seal and resist.
    At 50 samples the standard error of a label near 0.5 is 0.07."""

    grasp_point_std: float = 0.001
    """Std (m) of the isotropic Gaussian perturbation of the suction target point."""

    approach_rotation_std: float = 0.1
    """Std (rad) of the Lie-algebra rotation perturbing the approach direction (and ring phase)."""

    object_translation_std: float = 0.001
    """Std (m) of the translational part of the object-pose perturbation."""

    object_rotation_std: float = 0.1
    """Std (rad) of the rotational part of the object-pose perturbation, about the centre of mass."""

    com_std: float = 0.0025
    """Std (m) of the isotropic perturbation of the centre of mass."""

    friction_std: float = 0.1
    """Std of the friction coefficient, a normal about the cup's nominal friction truncated to
    [friction_min, friction_max]."""

    friction_min: float = 0.0
    """Lower truncation bound of the friction distribution."""

    friction_max: float = 1.0
    """Upper truncation bound of the friction distribution."""

    force_noise_std: float = 0.01
    """Std (N) of the isotropic Gaussian noise added to the gravity force."""

    def __post_init__(self) -> None:
        if self.num_samples < 1:
            raise InputError(f"perturbation config: num_samples = {self.num_samples} must be >= 1")
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if f.name != "num_samples" and (not math.isfinite(value) or value < 0):
                raise InputError(f"perturbation config: {f.name} = {value!r} must be finite and >= 0")


@dataclass(frozen=True)
class MetricConfig:
    """Parameters of the baseline (heuristic) metrics."""

    planarity_rms_max: float = 0.001
    """A patch is 'sufficiently planar' for PC3D when the RMS deviation (m) of the surface inside
    the cup disc from the approach plane through the target is at most this."""

    centroid_length: float = 0.05
    """Length scale L (m) of the centroid score 1 / (1 + d / L), d the distance from the target to
    the centre of mass; the score is 0.5 at d = L."""


@dataclass(frozen=True)
class LabelConfig:
    """Everything that defines a robust suction label, bundled for datasets and model cards."""

    cup: CupConfig = field(default_factory=lambda: CUP_DEFAULT)
    """The suction cup."""

    seal: SealConfig = field(default_factory=SealConfig)
    """Seal-model discretisation."""

    perturbation: PerturbationConfig = field(default_factory=PerturbationConfig)
    """Environment model for the robust metric."""

    metric: MetricConfig = field(default_factory=MetricConfig)
    """Baseline-metric parameters."""


def cup_preset(name: str) -> CupConfig:
    """Return a named cup preset, or raise InputError naming the known presets."""
    try:
        return CUP_PRESETS[name.lower()]
    except KeyError:
        known = ", ".join(sorted(CUP_PRESETS))
        raise InputError(f"cup preset '{name}' is unknown (known: {known})") from None


def to_dict(config: Any) -> dict[str, Any]:
    """Nested plain-dict form of a config dataclass (tuples become lists), ready for JSON/TOML."""

    def plain(value: Any) -> Any:
        if isinstance(value, tuple):
            return [plain(v) for v in value]
        return value

    out: dict[str, Any] = {}
    for f in dataclasses.fields(config):
        value = getattr(config, f.name)
        out[f.name] = to_dict(value) if dataclasses.is_dataclass(value) else plain(value)
    return out
