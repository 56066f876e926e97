"""The pick cycle behind picks per hour: simulated motion plus a *modelled* compute time.

The paper's picks-per-hour figure is E[rate] = success rate / (sensing + computation + robot
motion time) per attempt (Dex-Net 3.0, Mahler et al., ICRA 2018, "Performance Metrics"). In a
benchmark run the motion time is simulated, hence the same on every run with the same seed, but the
wall-clock time of rendering and planning is not: it depends on the machine, its load and the
number of workers. Picks per hour therefore use a compute time from this model, a constant per
policy, so that identical seeds give identical tables; the measured wall times of sensing and
planning are reported beside it (`mean_sensing_s`, `mean_plan_s`, `picks_per_hour_wall`).

The model's numbers are the seconds one planned grasp took on the 2-core development machine
(`suctionbench bench plan`, typical set, one process): they stand for "a laptop CPU", not for
the robot's computer, and are recorded in each run's run.json, so a later change of the model does
not change the tables of existing runs.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

SENSOR_FRAME_S = 1.0 / 30.0
"""Sensing: one depth frame of a 30 Hz sensor (the PrimeSense Carmine's depth stream; RealSense
D400 cameras stream at 30 Hz too)."""

PLANNING_S: dict[str, float] = {
    "random": 0.015,
    "centroid": 0.015,
    "planarity": 0.02,
    "planarity-centroid": 0.03,
    "gqcnn": 0.1,
    "fc-gqcnn": 0.06,
}
"""Planning time (s per grasp) per built-in image policy, as `suctionbench bench plan --policies
gqcnn,fc-gqcnn --scenes 5 --cores 2` measures it on the idle 2-core development machine (a robot's
planning computer does nothing else), rounded up. Heuristics: 0.013-0.028 s. gqcnn (the shipped
gqcnn-context model, CEM with batched network calls): 0.090-0.094 s, twice; gqcnn-adv runs the same
network; fc-gqcnn (the same model, dense): 0.066 s, 0.035-0.036 s since every angle bin's lattice
runs in one batch (twice; gqcnn 0.100 s in the same runs). (The compact model before it: CEM 0.055 s,
dense 0.043-0.045 s; gqcnn was then modelled at 0.15 s from plan times inside benchmark runs,
where two workers and the simulation share the cores.) With the 48 px default (gqcnn-sensor48)
the dense policy took 0.095 s while still charged 0.04; after the planning-time work of 2026-11-28
(bench plan, 20 scenes, 12 runs over the work's last steps): gqcnn 0.082-0.103 s (charged 0.1),
fc-gqcnn 0.049-0.055 s, charged 0.06 since. For scale, the paper's Dex-Net 3.0 GQ-CNN policy took about 3.0 s per grasp
on a GeForce 980 desktop."""

DEFAULT_PLANNING_S = PLANNING_S["gqcnn"]
"""Planning time of a user or plug-in policy, whose cost the benchmark cannot know: a learned
policy's (the GQ-CNN's)."""

KNOWN_STATE_PLANNING_S = 0.0
"""The known-state policies are oracles that read the true object state: no planning time, and for
analytic and random-surface (which read no image) no sensing either, so their picks per hour is
what the motion alone allows (analytic-image adds the camera's frame)."""


@dataclass(frozen=True)
class CycleModel:
    """Modelled compute time of one attempt: sensing (one frame) plus the policy's planning."""

    sensing_s: float = SENSOR_FRAME_S
    """Seconds to acquire the depth image."""

    planning_s: dict[str, float] = field(default_factory=lambda: dict(PLANNING_S))
    """Seconds to plan one grasp, per built-in policy name."""

    default_planning_s: float = DEFAULT_PLANNING_S
    """Seconds to plan one grasp for any other image policy."""

    def compute_time(self, policy: str) -> dict[str, float]:
        """{"sensing_s", "planning_s"} of one attempt of `policy` (a registry name or a user spec)."""
        from suctionbench.policies.base import ADV_VARIANTS, IMAGE_KNOWN_STATE_POLICIES, KNOWN_STATE_POLICIES

        if policy in KNOWN_STATE_POLICIES:  # an oracle's ranking takes no time; a camera frame does
            return {"sensing_s": self.sensing_s if policy in IMAGE_KNOWN_STATE_POLICIES else 0.0,
                    "planning_s": KNOWN_STATE_PLANNING_S}
        from suctionbench.policies.plugins import builtin_name

        name = builtin_name(policy)
        name = ADV_VARIANTS.get(name, name)  # the same search and network with other weights
        planning = self.planning_s.get(name, self.default_planning_s) if name else self.default_planning_s
        return {"sensing_s": self.sensing_s, "planning_s": planning}


CYCLE_MODEL = CycleModel()
"""The model new runs record."""


def picks_per_hour(success_rate: float, cycle_s: float) -> float | None:
    """Successful picks per hour at `success_rate` with `cycle_s` seconds per attempt (None when the
    cycle is not positive)."""
    return round(3600.0 * success_rate / cycle_s, 1) if cycle_s > 0 else None


def modelled_compute(run: dict[str, Any]) -> dict[str, float]:
    """The compute time a run recorded (run.json "compute_model"), or the current model's for runs
    that predate it."""
    recorded = run.get("compute_model")
    if isinstance(recorded, dict) and {"sensing_s", "planning_s"} <= set(recorded):
        return {"sensing_s": float(recorded["sensing_s"]), "planning_s": float(recorded["planning_s"])}
    return CYCLE_MODEL.compute_time(run.get("policy_spec") or run["policy"])
