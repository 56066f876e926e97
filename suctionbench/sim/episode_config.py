"""What a pick episode is given and what it returns: `EpisodeConfig` (timing, geometry and health
limits) and `EpisodeResult` (the outcome, one of `FAILURES` when it fails), apart from the motion and
physics that run it (`suctionbench.sim.episode.PickEpisode`), so runners, environments and logs can
read and build them without the simulator."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from suctionbench.config import TRANSPORT_TIMES

FAILURES = (
    "no_grasp",
    "unreachable",
    "collision",
    "no_seal",
    "seal_lost_lift",
    "seal_lost_transport",
    "seal_lost_hold",
    "not_lifted",
    "unstable",
)
"""Failure reasons, in the order of the episode's phases ("no_grasp": the image policy found no
grasp in the observation, so nothing was executed)."""


@dataclass(frozen=True)
class EpisodeConfig:
    """Timing and geometry of a pick (SI units)."""

    settle_time: float = 8.0
    """Longest time given to a dropped object to come to rest (s). One still moving then is an
    unstable placement (not executed). Measured over the 1,000 drops of the agreement study: 1.5 s
    (the old limit) left 107 objects rocking (a tall jug at up to 2 rad/s) while the policy chose
    and the labeller judged a grasp on a pose the object was about to leave. 6 s left one of them
    (typical/jar_wide, seed 235) and 3 of the typical benchmark's 125 drops moving, all jar_wide:
    a jar lying on its side with its centre of mass off its axis rocks about its axis like a
    roly-poly, losing energy only to rolling resistance (0.1 mm), and came to rest at 6.15-6.28 s.
    An object at rest sooner is not affected by the limit."""

    rest_time: float = 0.1
    """An object is at rest once it has stayed within `rest_motion` of one pose for this long (s). Motion,
    not speed: a rocking object passes through zero speed at every turn, and one resting on a few
    contacts chatters at up to ~0.01 m/s or rad/s about a fixed pose (a hex nut on its side)."""

    rest_motion: float = 2e-4
    """...at most this far (m), its orientation turning by at most rest_motion / 0.05 m (0.23 deg)."""

    ready_tip: tuple[float, float, float] = (0.12, -0.42, 0.30)
    """Where the tool tip waits (pointing down) while the object settles and is observed: out of
    the overhead camera's view, as on the real system."""

    drop_clearance: float = 0.03
    """A dropped object starts this high above the table at its lowest possible point (its
    bounding sphere about the body origin), whatever its random orientation."""

    drop_spread: float = 0.04
    """Half-width of the square around the workspace centre where objects are dropped."""

    pregrasp_offset: float = 0.06
    """Distance before the target along the approach where the straight approach starts."""

    press_depth: float = 0.03
    """How far past the target the guarded approach may continue before giving up: it stops as
    soon as the bellow compresses, so sensing errors of up to this much are absorbed."""

    compression_stop: float = 0.004
    """The approach stops once the bellow is compressed this much: two thirds of its travel, so
    the bellow presses hard enough to tilt onto a surface approached up to ~20 deg off its normal
    (at 2 mm, 13 of 25 GQ-CNN trials on the basic set failed to seal against 10 at 4 mm)."""

    approach_speed: float = 0.08
    """Mean tool speed of the approach from the pregrasp pose to the guarded move's start (m/s)."""

    transit_clearance: float = 0.05
    """The move to the pregrasp pose passes through a point this far (m) above the object's top,
    over the pregrasp pose, and descends from there along a straight line: a joint-space move
    straight from the ready pose swept the cup through the object on the way (a lying can, seed
    107 of the agreement study, knocked 23 cm away at 0.4 m/s before the approach began)."""

    guarded_standoff: float = 0.01
    """The last stretch before the target (m) is a guarded move at `guarded_speed`: sensing errors
    of up to this much still meet the surface slowly."""

    guarded_speed: float = 0.02
    """Tool speed of the guarded move (m/s), constant until the bellows reports contact, as pick
    systems touch down (the old approach met the object near its ~0.14 m/s peak, 6 cm into one
    9 cm minimum-jerk move; the objects the agreement study found knocked away were hit earlier,
    by the transit: `transit_clearance`)."""

    vacuum_dwell: float = 0.15
    """Time with the vacuum on before lifting (the cup evacuates)."""

    lift_height: float = 0.15
    """Straight lift after sealing (m)."""

    lift_speed: float = 0.15
    """Average tool speed while lifting (m/s)."""

    transport_height: float = 0.25
    """Height of the tool tip above the table over the bin."""

    transport_min_time: float = TRANSPORT_TIMES[0]
    """Shortest transport (s); longer where the joints' speed limits or the cup's rated acceleration
    ask for it (`PickEpisode._carry_time`). The labeller's range of transport times
    (config.TRANSPORT_TIMES) starts here."""

    speed_scale: float = 0.5
    """Fraction of the YuMi's joint speed limits used by trajectories."""

    hold_time: float = 0.5
    """Time the object must stay held over the bin."""

    release_time: float = 0.4
    """Time after venting, for the object to fall into the bin."""

    clearance: float = 0.01
    """An object counts as lifted when its lowest point is this far above the table."""

    max_penetration: float = 0.01
    """Any contact deeper than this marks the simulation as unstable."""

    max_speed: float = 20.0
    """Any body faster than this (m/s) marks the simulation as unstable."""


@dataclass
class EpisodeResult:
    """Outcome of one episode."""

    success: bool
    failure: str | None
    valid: bool
    seal_time: float | None
    peak_slip: float
    lifted: bool
    in_bin: bool
    sim_time: float
    wall_time: float
    detail: str | None = None
    phases: dict[str, float] = field(default_factory=dict)
    peak_acceleration: dict[str, float] = field(default_factory=dict)
    """Largest acceleration (m/s^2) of the cup (the rigid tool body on the flange) in each motion
    that carries the object ("lift", "transport"), from its position at the sim rate (second
    differences over one 2 ms step)."""
    touchdown_short: float | None = None
    """How far (m) short of the planned point, along the approach, the guarded approach stopped
    (the unloaded cup's lip centre at the arm's stop): about -compression_stop on target, more
    where the bellows met a surface before it (the object's own wall in the way: a grasp inside a
    tube's bore is approached through the tube, and the cup seals on the outside). None if the
    arm never reached the object."""

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)

    @classmethod
    def not_executed(cls, failure: str, detail: str | None = None, *, valid: bool = True) -> EpisodeResult:
        """The outcome of an attempt that never moved the robot (no grasp, invalid action; an
        unstable placement, `valid` False: the trial says nothing about the policy)."""
        return cls(success=False, failure=failure, valid=valid, seal_time=None, peak_slip=0.0, lifted=False,
                   in_bin=False, sim_time=0.0, wall_time=0.0, detail=detail)
