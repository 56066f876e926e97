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

from suctionbench import minjerk
from suctionbench.errors import InputError


@dataclass(frozen=True)
class CupConfig:
    """One physical suction cup, shared by the analytic labeller and the simulated cup.

    Both models read the same numbers and compute independently. docs/physics.md gives the source
    and derivation of every field; derived quantities (effective area, vacuum force, bending
    stiffness, approach tolerance, leak threshold, mass cap) are properties, never second copies.
    The default is a 15 mm silicone single-bellows cup (the paper's) on a small inline ejector.
    """

    name: str = "default"
    """Preset name, recorded in labels, datasets and model cards."""

    n_vertices: int = 8
    """Number n of perimeter vertices of the labeller's quasi-static spring model (the paper's figure
    uses 8). A discretisation of the analytic model, not a property of the cup."""

    radius: float = 0.0075
    """Lip radius r in metres: the outer lip circle of the paper's 15 mm diameter cup. The contact ring
    of both models and the lever arm of the ring-pressure tilt limit."""

    inner_radius: float = 0.0055
    """Inner radius of the lip (m). Vendors compute holding force over the effective diameter, the mean
    of the lip's inner and outer diameter (13 mm here, ~75 % of the outer area)."""

    height: float = 0.015
    """Height h of the undeformed cup (m): a 15 mm single-bellows cup is about as tall as it is wide.
    Sets the rest length sqrt(r^2 + h^2) of the labeller's cone springs."""

    stretch_limit: float = 0.10
    """Largest allowed relative change in length of any spring of the labeller's model,
    |L - L0| / L0 (Provot 1995, used by the paper's appendix on seal formation)."""

    vacuum_pressure: float = 60e3
    """Vacuum (Pa below atmosphere) the ejector reaches with a perfect seal (zero flow). 60 kPa is the
    level vendors quote holding forces at (-0.6 bar)."""

    ejector_flow: float = 16.0 / 60000.0
    """Free-air suction capacity of the ejector (m^3/s, at zero vacuum): 16 l/min, a small inline
    ejector of the kind mounted at a 15 mm cup. The ejector curve is taken as linear between
    (0 flow, vacuum_pressure) and (ejector_flow, 0 vacuum)."""

    discharge_coefficient: float = 0.6
    """Discharge coefficient C_d of a leak treated as a sharp-edged orifice, Q = C_d A sqrt(2 p / rho)."""

    seal_gap: float = 3e-4
    """Local gap (m) between lip and surface that the lip's thin edge closes by itself when the vacuum
    pulls it down; only gap beyond it leaks."""

    vacuum_switch_fraction: float = 0.5
    """A seal counts as made while the equilibrium vacuum is at least this fraction of vacuum_pressure
    (the set point of an ejector's part-present switch). Defines the leak threshold area."""

    lip_travel: float = 0.002
    """Axial distance (m) each point of the soft lip can fold independently of its neighbours before
    the bellows' convolution takes over: how far the lip conforms to a curved surface. Cylinders of
    radius down to r^2 / (2 lip_travel) can be sealed."""

    lip_fold_fraction: float = 0.5
    """How far the full vacuum force V, pressing the lip evenly onto a flat face, folds it, as a
    fraction of lip_travel: sets the lip's rate, `lip_rate` = V / (fraction x lip_travel) (7960 N/m
    round the ring at 0.5). Half, because the ring-pressure model behind the tilt limit needs a lip
    that stays elastic while one side unloads and the other takes the load; a lip the vacuum folds
    flat onto its stop concentrates the load on its far edge instead. Both models read it: the
    simulated lip points' springs and the labeller's preload from the surface shape under the ring
    (contact/wrench.py, "Lip preload")."""

    stroke: float = 0.006
    """Axial travel of the bellows (m), 40 % of the cup height."""

    axial_stiffness: float = 1500.0
    """Bellows spring rate along the axis (N/m): a 15 mm single bellows compresses ~5 mm under ~7 N."""

    friction: float = 0.5
    """Nominal Coulomb friction coefficient mu between lip and object: ~0.5 for a dry silicone lip
    (Schmalz; 0.2-0.3 wet, 0.1-0.3 oily)."""

    safety_factor: float = 1.5
    """Safety factor S on the holding force against weight plus inertial load (German UVV: >= 1.5;
    Schmalz recommends 2). Sets the mass cap of the object sets."""

    peak_acceleration: float = 3.1
    """Largest acceleration (m/s^2) of the cup during the pick episode (lift and transport, measured on
    the episode's motion profile). The inertial load m a of the labeller's disturbing wrench."""

    vacuum_force_override: float | None = None
    """Constant vacuum force V (N) used instead of pressure x effective area; only for the `paper`
    preset's literal, fitted V = 250."""

    kappa: float | None = None
    """The paper's material limit kappa (sqrt(2)|tau_x|, sqrt(2)|tau_y| <= pi r kappa, a box). None (the
    physical default) uses the ring-pressure limit ||tau|| <= r (V + f_z) / 2 instead: the paper's
    own condition p(theta) >= 0 around the lip, a circle that shrinks as the load pulls the lip off."""

    seal_model: str = "lip"
    """Seal test of the labeller: "lip" (the physical lip: the bellows tilts up to the approach
    tolerance, the lip folds up to lip_travel and bridges what it cannot bend into, the leak area
    sets the vacuum; suctionbench/contact/seal.py) or "springs" (the paper's literal quasi-static
    spring model with its stretch limit, constant V; the `paper` preset)."""

    bellows_swing: bool = True
    """The bellows bends under the load's moment (bending_stiffness, up to approach_tolerance), so
    a lifted object swings towards hanging with its centre of mass below the lip and the seal
    carries only what the bellows resists (contact/swing.py, `lip_load`). False: a cup rigid
    in bending, as the paper's quasi-static model (the `paper` preset)."""

    swing_overshoot: bool = True
    """The load reaches the bellows within about one swing period (the object tips off the table,
    the transport starts), and a lightly damped swing then overshoots its equilibrium: the labeller
    judges the lip at the swing's first turning point, following the pick's motion where the
    object's inertia and support are known (contact/arrival.py), else for a load applied at once,
    the bound (contact/swing.py, `lip_load`). False: at the static equilibrium (the load applied
    slowly)."""

    bellows_loss_factor: float = 0.1
    """Loss factor eta (tan delta) of the bellows' silicone: the energy a bending cycle dissipates
    over 2 pi times the energy it stores. No cup maker states it; 0.1 is an assumed value for an
    unfilled silicone, among the least lossy elastomers (not measured for this cup, and the
    figures' sensitivity to it is not measured yet). Equivalent damping ratio
    zeta = eta / 2: the labeller's swing overshoot (`swing_overshoot_fraction`), and the simulated
    bellows' tilt damping eta k_b / omega at its swing frequency (SimCupConfig.tilt_damping)."""

    stop_stiffness: float = 0.35
    """Tilt stiffness (N m/rad) of the bellows' stop beyond approach_tolerance, where one side of
    the wall is folded solid and the silicone itself is squeezed. A wall of thickness t at mean
    radius r_m, stacked h_s high, pressed on one half-circumference with the strain
    (r_m sin(u) dtheta) / h_s: M = int_0^pi (E t / h_s)(r_m sin u)^2 r_m du dtheta
    = (pi / 2) E t r_m^3 / h_s. With a Shore 50A silicone (E = 2.46 MPa, Gent's relation), t = 1 mm,
    h_s = 3 mm (a fold and a half stacked) and r_m = 6.5 mm: 0.35 N m/rad, 11x the bellows' bending
    and 1.6x the lip's. No cup maker states the wall's geometry; t and h_s are assumed (like
    bellows_loss_factor). In series with the lip it sets how hard a swing is caught on the stop
    (contact/swing.py, `lip_load`; the simulated stop spring, sim/cup.py)."""

    def __post_init__(self) -> None:
        checks = {
            "seal_model": self.seal_model in SEAL_MODELS,
            "n_vertices": self.n_vertices >= 3,
            "radius": 0.0 < self.radius < 1.0,
            "inner_radius": 0.0 <= self.inner_radius < self.radius,
            "height": 0.0 < self.height < 1.0,
            "stretch_limit": 0.0 < self.stretch_limit < 10.0,
            "vacuum_pressure": 0.0 < self.vacuum_pressure <= 101325.0,
            "ejector_flow": self.ejector_flow > 0.0,
            "discharge_coefficient": 0.0 < self.discharge_coefficient <= 1.0,
            "seal_gap": 0.0 <= self.seal_gap < self.radius,
            "vacuum_switch_fraction": 0.0 < self.vacuum_switch_fraction < 1.0,
            "lip_travel": 0.0 < self.lip_travel < self.height,
            "lip_fold_fraction": 0.0 < self.lip_fold_fraction <= 10.0,
            "stroke": 0.0 < self.stroke < self.height,
            "axial_stiffness": self.axial_stiffness > 0.0,
            "friction": 0.0 <= self.friction <= 10.0,
            "safety_factor": self.safety_factor >= 1.0,
            "peak_acceleration": self.peak_acceleration >= 0.0,
            "bellows_loss_factor": 0.0 <= self.bellows_loss_factor < 2.0,
            "stop_stiffness": 0.0 < self.stop_stiffness < math.inf,
            "vacuum_force_override": self.vacuum_force_override is None or self.vacuum_force_override > 0.0,
            "kappa": self.kappa is None or self.kappa > 0.0,
        }
        for key, ok in checks.items():
            value = getattr(self, key)
            if not ok or (isinstance(value, float) and not math.isfinite(value)):
                raise InputError(f"cup config: {key} = {value!r} is out of range")

    @property
    def effective_radius(self) -> float:
        """Radius (m) of the effective suction area: the mean of the lip's inner and outer radius."""
        return 0.5 * (self.radius + self.inner_radius)

    @property
    def effective_area(self) -> float:
        """Area (m^2) the vacuum acts on: pi r_eff^2."""
        return math.pi * self.effective_radius**2

    @property
    def vacuum_force(self) -> float:
        """Vacuum force V (N) at full vacuum: vacuum_pressure x effective_area (7.96 N by default),
        unless the preset overrides it."""
        if self.vacuum_force_override is not None:
            return self.vacuum_force_override
        return self.vacuum_pressure * self.effective_area

    @property
    def bending_stiffness(self) -> float:
        """Tilt stiffness of the bellows (N m/rad). A thin-walled bellows of mean radius r_m whose
        wall carries the axial rate k spread evenly round its circumference resists a tilt theta
        with moment int (k / 2 pi r_m) (r_m theta cos phi) r_m cos phi r_m dphi = k r_m^2 theta / 2."""
        return 0.5 * self.axial_stiffness * self.effective_radius**2

    @property
    def lip_rate(self) -> float:
        """Axial rate K (N/m) of the whole lip ring, spread evenly round it: the full vacuum force
        folds a lip pressed evenly onto a flat face by lip_fold_fraction x lip_travel,
        K = V / (lip_fold_fraction x lip_travel) (7960 N/m by default). Per radian of lip: K / 2 pi."""
        return self.vacuum_force / (self.lip_fold_fraction * self.lip_travel)

    @property
    def lip_tilt_stiffness(self) -> float:
        """Tilt stiffness of the lip ring (N m/rad): its springs (K / 2 pi per radian at radius r)
        resist a tilt phi of the object on the lip with int (K / 2 pi)(r phi sin t) r sin t dt
        = K r^2 phi / 2 (0.22 N m/rad by default, 7x the bellows'). In series with the bellows below
        its stop, with the bellows and its squeezed stop beyond it (contact/swing.py, `lip_load`)."""
        return 0.5 * self.lip_rate * self.radius**2

    @property
    def swing_damping_ratio(self) -> float:
        """Damping ratio zeta of the bellows' swing: the silicone's loss factor / 2 (0.05)."""
        return 0.5 * self.bellows_loss_factor

    @property
    def swing_overshoot_fraction(self) -> float:
        """How much of an undamped swing's overshoot survives the bellows' damping: a step load on
        a spring-mass system of damping ratio zeta (`swing_damping_ratio`) overshoots its
        equilibrium by exp(-pi zeta / sqrt(1 - zeta^2)) of the undamped overshoot (0.855 at eta = 0.1)."""
        zeta = self.swing_damping_ratio
        return math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta * zeta))

    @property
    def approach_tolerance(self) -> float:
        """Largest angle (rad) between the approach axis and a flat surface's normal at which the lip
        still lands flat: the bellows tilts until one side has used its whole stroke while the
        opposite side is uncompressed, tan(phi) = stroke / (2 r) (21.8 deg by default)."""
        return math.atan2(self.stroke, 2.0 * self.radius)

    @property
    def min_seal_radius(self) -> float:
        """Smallest radius (m) of a cylinder the lip conforms to: the lip circle's sag on a cylinder of
        radius R is r^2 / (2 R) (small-sag approximation), at most lip_travel (14.1 mm by default)."""
        return self.radius**2 / (2.0 * self.lip_travel)

    @property
    def leak_threshold_area(self) -> float:
        """Leak area (m^2) at which the equilibrium vacuum falls to the switch point (see vacuum.py)."""
        from suctionbench.vacuum import leak_area_at_pressure

        return float(leak_area_at_pressure(self.vacuum_switch_fraction * self.vacuum_pressure, self))

    @property
    def payload_kg(self) -> float:
        """Largest mass the vacuum alone can hold against gravity (V / g), no margin."""
        return self.vacuum_force / STANDARD_GRAVITY

    @property
    def mass_cap_kg(self) -> float:
        """Heaviest object the cup may carry: V / (S (g + a_peak)), weight plus the episode's peak
        inertial load with the safety factor (0.411 kg by default)."""
        return self.vacuum_force / (self.safety_factor * (STANDARD_GRAVITY + self.peak_acceleration))

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> CupConfig:
        """Build from a plain dict (a dataset or model card), ignoring keys this version does not know
        (cards written before the physical cup stored `vacuum_force` as a field)."""
        known = {f.name for f in dataclasses.fields(cls)}
        kwargs = {k: v for k, v in data.items() if k in known}
        return cls(**kwargs)


SEAL_MODELS = ("lip", "springs")
"""The labeller's seal tests, see CupConfig.seal_model."""

STANDARD_GRAVITY = 9.80665
"""Standard gravity in m/s^2."""

TOUCH_DOWN_COMPRESSION = 0.004
"""Compression (m) of the bellows at which a pick's guarded touch-down stops (the episode's
EpisodeConfig.compression_stop, two thirds of the default cup's 6 mm stroke): the press the object
carries while the seal forms, 6 N on the default cup's 1500 N/m bellows."""

TRANSPORT_TIMES = (0.8, 1.6)
"""The range of a pick episode's transport times (s) the labeller draws from
(PerturbationConfig.transport_time_max). The transport (sim/episode.py, `PickEpisode._carry`) is a
straight min-jerk move from the lift's end to the tool tip's place over the bin, at least
EpisodeConfig.transport_min_time (0.8 s), longer where the cup's rated acceleration
(T = sqrt(5.774 L / a): 0.35 m at 3.1 m/s^2 take 0.81 s) or the joints' speed limits ask for it.
Over 300 random transports from the workspace (lift ends within 10 cm of its centre, 0.15-0.3 m
high, tools up to 45 deg off vertical; 0.23-0.49 m long; eval/agreement/transport_probe/
transport_bounds.py): 10 % take the shortest 0.8 s, half at most 1.02 s, 90 % at most 1.65 s, the
longest 2.16 s (the tilted tools' joint travel); the joints' speed limits set 80 % of the times. The upper end is
that 90th percentile: a longer transport is gentler still (the response factor falls towards 1)."""

CUP_DEFAULT = CupConfig()
"""The physical cup: 15 mm silicone bellows, 60 kPa ejector, V = 60 kPa x pi (6.5 mm)^2 = 7.96 N,
ring-pressure tilt limit."""

CUP_PAPER = CupConfig(
    name="paper", vacuum_force_override=250.0, kappa=0.005, seal_model="springs", bellows_swing=False
)
"""The paper's literal values, V = 250 N and kappa = 0.005 (units as the paper states them): fitted by
grid search against its robot trials, not physical constants; with the paper's spring seal model and a
cup rigid in bending."""


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

    lip_samples: int = 48
    """Places on the lip circle where the "lip" seal model measures the surface (rounded up to a
    multiple of the cup's n_vertices, which are among them). 48 on the 15 mm cup's 47 mm lip are
    0.98 mm apart, so a 2 mm groove crossing the lip covers at least two of them."""

    def __post_init__(self) -> None:
        if self.lip_samples < 32:
            raise InputError(f"seal config: lip_samples = {self.lip_samples} must be >= 32")
        if self.edge_samples < 0:
            raise InputError(f"seal config: edge_samples = {self.edge_samples} must be >= 0")


@dataclass(frozen=True)
class PerturbationConfig:
    """The paper's environment model for robust wrench resistance ("Details of Distributions").

    The paper writes N(0, s I) without saying whether s is a variance; every value here is a
    standard deviation in SI units.
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

    inertial_acceleration: float = 0.0
    """Peak acceleration a (m/s^2) of the cup while it carries the object; 0 (the paper's
    quasi-static model) leaves only gravity. With a > 0 every sample must also resist the inertial
    load of the two motions of a pick: the lift (straight up at its own peak `lift_acceleration`,
    at most a, so the object hangs with m (g + a_lift)) and the transport (a
    horizontal, at an azimuth drawn per sample from the grasp's keyed stream). `for_episode` sets it
    to the cup's peak acceleration."""

    lift_height: float = 0.15
    """Height (m) of the pick's straight min-jerk lift (the episode's EpisodeConfig.lift_height): with
    lift_time, how fast the object tips off the table into its swing (contact/arrival.py)."""

    lift_time: float = 1.0
    """Duration (s) of that lift (EpisodeConfig.lift_height / lift_speed)."""

    transport_time: float = 0.9
    """Duration (s) of the min-jerk transport, whose acceleration peaks at inertial_acceleration:
    how fast the transport's inertial load reaches the swing (contact/arrival.py); the shortest
    transport where `transport_time_max` is longer."""

    transport_time_max: float | None = None
    """The longest transport (s). Where set (and longer than `transport_time`), each sample's
    transport lasts a time drawn uniformly from [transport_time, transport_time_max] in the grasp's
    keyed stream (after the azimuth): how long the transport lasts depends on where the object lies
    relative to the bin, unknown when labelling, and the swing's overshoot depends on it (the
    response factor of contact/arrival.py peaks where the motion lasts about one swing period).
    `for_episode` sets the episode's range, TRANSPORT_TIMES."""

    transport_direction: tuple[float, float, float] | None = None
    """The transport's direction (mesh frame; normalised) where the pick's motion is known when
    labelling: the episode's labeller, whose planned transport runs straight from the lift's end
    to the bin (`PickEpisode.planned_transport`). The swing is then followed in time through the
    planned lift, transport (`transport_time`, `transport_length`) and hold (contact/swing_path.py)
    and judged at the lift's and the carry's worst instants. None: unknown (a dataset's labels),
    azimuths drawn per sample and the closed form's turning points (contact/arrival.py)."""

    hold_time: float = 0.5
    """How long (s) the pick holds the object over the bin after the transport (the episode's
    EpisodeConfig.hold_time): the planned swing (`transport_direction`) is followed through it,
    where a braking's overshoot may still peak."""

    transport_length: float | None = None
    """Length (m) of the planned transport's straight line, with `transport_direction`: a min-jerk
    move of L metres over T = transport_time peaks at 5.774 L / T^2, the transport's inertial load
    (at most inertial_acceleration, the cup's rating, which only the shortest transports reach:
    the joints' speed limits set 80 % of them longer; planned peaks 0.6-3.1 m/s^2, median 2.0, over
    300 random transports: eval/agreement/transport_probe/transport_bounds.py). None: the rated peak."""

    press_compression: float = 0.0
    """Compression (m) of the bellows at which the pick's touch-down stops and holds while the
    seal forms (the episode's EpisodeConfig.compression_stop). The object must stay put under the
    bellows' force k_a x along the approach (contact/press.py); 0 (the paper's quasi-static model)
    skips that test. `for_episode` sets it to TOUCH_DOWN_COMPRESSION."""

    table_friction: float = 0.6
    """Coulomb friction between the object and the table it lies on, against sliding under the
    touch-down's press: the scene's table (SceneConfig.friction; MuJoCo takes the larger of two
    surfaces' coefficients, and the objects' own, against silicone, are at most 0.5). Dry
    cardboard, paper or plastic on wood or laminate: 0.3-0.6."""

    @property
    def transport_peak(self) -> float:
        """Peak acceleration (m/s^2) of the transport: the planned line's 5.774 L / T^2 where its
        length is known (`transport_length`), at most the rated inertial_acceleration."""
        if self.transport_length is None:
            return self.inertial_acceleration
        planned = minjerk.PEAK_ACCELERATION * self.transport_length / self.transport_time**2
        return min(self.inertial_acceleration, planned)

    @property
    def lift_acceleration(self) -> float:
        """Acceleration (m/s^2) of the lift case: the min-jerk lift's peak 5.77 lift_height /
        lift_time^2 (0.87 m/s^2 by default; 10 / sqrt 3 = max s''), at most inertial_acceleration
        (the cup's rated peak, which the transport reaches). 0 without an inertial load."""
        return min(self.inertial_acceleration, minjerk.PEAK_ACCELERATION * self.lift_height / self.lift_time**2)

    @classmethod
    def for_episode(cls, cup: CupConfig, **kwargs: Any) -> PerturbationConfig:
        """The environment model of a pick episode: the paper's perturbations plus the inertial load
        of the cup's peak acceleration (cup.peak_acceleration) and the touch-down's press."""
        return cls(**{"inertial_acceleration": cup.peak_acceleration, "press_compression": TOUCH_DOWN_COMPRESSION,
                      "transport_time": TRANSPORT_TIMES[0], "transport_time_max": TRANSPORT_TIMES[1], **kwargs})

    def __post_init__(self) -> None:
        if self.num_samples < 1:
            raise InputError(f"perturbation config: num_samples = {self.num_samples} must be >= 1")
        for name in ("lift_height", "lift_time", "transport_time"):
            if not getattr(self, name) > 0.0:
                raise InputError(f"perturbation config: {name} = {getattr(self, name)!r} must be > 0")
        if self.transport_time_max is not None and not self.transport_time_max >= self.transport_time:
            raise InputError(f"perturbation config: transport_time_max = {self.transport_time_max!r} must be "
                             f">= transport_time = {self.transport_time!r}")
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if f.name in ("transport_time_max", "transport_direction", "transport_length") and value is None:
                continue
            if f.name == "transport_direction":
                if len(value) != 3 or not all(math.isfinite(v) for v in value) or not any(value):
                    raise InputError(f"perturbation config: transport_direction = {value!r} must be 3 finite "
                                     "numbers, not all zero")
                continue
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

    @classmethod
    def for_episode(cls, cup: CupConfig = CUP_DEFAULT, **kwargs: Any) -> LabelConfig:
        """Labels for grasps a pick episode executes: `cup`, and perturbations that include the
        inertial load of its peak acceleration (PerturbationConfig.for_episode)."""
        return cls(cup=cup, perturbation=PerturbationConfig.for_episode(cup), **kwargs)


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
