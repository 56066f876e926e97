"""Robust wrench resistance (Dex-Net 3.0, "Robust Wrench Resistance" and "Details of Distributions").

lambda(u, x) = P(seal and resist | u, x) under perturbations of the object pose, the grasp pose,
the centre of mass, friction and the disturbing wrench, estimated as the mean of J binary samples.

Object-pose perturbations are applied as their inverse to the grasp, so every sample is a grasp
on the same mesh in the mesh's own frame (one batched ray cast for all grasps x samples), with
gravity rotated into the perturbed object frame. All perturbations are drawn in the nominal
grasp's contact frame from a random stream keyed by (seed, grasp id), so a grasp's label does not
depend on which other grasps share its batch, and labels move with the object under rigid motions.

Inertial load (PerturbationConfig.inertial_acceleration = a > 0). The paper's model is
quasi-static; a pick episode is not: the cup accelerates the object at up to a (3.1 m/s^2 for the
default cup's episode), and in the cup's frame the object then feels the d'Alembert force -m a_cup
on top of its weight. The two motions of a pick point it two ways, and a grasp must survive both:
the lift (a_cup straight up at the lift's own peak, PerturbationConfig.lift_acceleration <= a, so
the object hangs with m (g + a_lift)) and the transport (a_cup
horizontal, direction unknown when labelling: its azimuth round the vertical is drawn uniformly per
sample from the grasp's keyed stream, after the paper's 19 draws so that a = 0 reproduces the
paper's labels bit for bit; its duration likewise, from the episode's range, after the azimuth).
A sample resists iff it resists every load case. The static weight
needs no case of its own: it lies on the segment between the zero wrench and the lift case, and
the set of resisted wrenches is convex. The azimuth is measured from the nominal contact frame's x
axis projected on the horizontal, so labels stay invariant under rigid motions. How each load
reaches the swinging cup (the lift-off, the transport's rising acceleration) follows from the
object's inertia and support (`ObjectState`) and the pick's motion: contact/arrival.py. Where the
pick's motion is planned when labelling (the episode's labeller, PerturbationConfig
.transport_direction), the transport has the plan's direction, time and peak, and the swing is
followed in time through the lift, the transport and the hold (contact/swing_path.py): two load
cases, the lift's and the carry's worst instants.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr, ndtri

from suctionbench.config import CupConfig, PerturbationConfig
from suctionbench.contact.arrival import Arrival
from suctionbench.contact.press import Footprint, stays_put
from suctionbench.contact.seal import SealModel
from suctionbench.contact.swing import lip_loads
from suctionbench.contact.wrench import resists, resists_qp
from suctionbench.geometry.frames import so3_exp

CHUNK_SAMPLES = 8192
"""Grasp samples evaluated per batch: bounds peak memory (~100 MB) independent of N."""


@dataclass
class ObjectState:
    """What the wrench model needs to know about the object, in the mesh frame."""

    com: np.ndarray
    """(3,) centre of mass (m)."""

    mass: float
    """Mass (kg)."""

    gravity: np.ndarray
    """(3,) gravitational acceleration in the mesh frame (m/s^2), e.g. (0, 0, -9.81)."""

    inertia: np.ndarray | None = None
    """(3, 3) inertia tensor about the centre of mass (kg m^2), mesh frame. With `support`, the swing
    follows the pick's arrivals (contact/arrival.py); without, the step bound."""

    support: np.ndarray | None = None
    """(H, 3) the hull vertices (m, mesh frame) the object stands on along `gravity`
    (`arrival.table_support`)."""

    footprint: Footprint | None = None
    """Where the object touches the table (contact/press.py): with a touch-down press in the
    perturbation model, a sample must also leave the object at rest under it. None: not tested."""

    @property
    def gravity_force(self) -> np.ndarray:
        """(3,) weight m g (N)."""
        return self.mass * np.asarray(self.gravity, dtype=float)


@dataclass
class GraspSamples:
    """Perturbed grasps, J per nominal grasp, flattened grasp-major to (N * J, ...)."""

    points: np.ndarray
    """(N*J, 3) perturbed target points in the mesh frame."""

    frames: np.ndarray
    """(N*J, 3, 3) perturbed grasp frames in the mesh frame."""

    com: np.ndarray
    """(N*J, 3) perturbed centres of mass."""

    force: np.ndarray
    """(N*J, 3) disturbing force (weight plus noise) in the perturbed mesh frame."""

    friction: np.ndarray
    """(N*J,) friction coefficients."""

    transport_time: np.ndarray | None
    """(N*J,) each sample's transport time (s), drawn from the config's range; None: the config's
    fixed transport_time."""

    inertial: np.ndarray
    """(N*J, L, 3) inertial force -m a_cup of each load case (lift, transport) in the perturbed mesh
    frame; L = 0 without inertial load."""

    @property
    def loads(self) -> np.ndarray:
        """(N*J, max(L, 1), 3) the disturbing forces a sample must resist, one per load case."""
        if self.inertial.shape[1] == 0:
            return self.force[:, None, :]
        return self.force[:, None, :] + self.inertial


def arrivals(obj: ObjectState, config: PerturbationConfig, cup: CupConfig, weight: np.ndarray,
             inertial: np.ndarray, transport_time: np.ndarray | None = None) -> list[Arrival] | None:
    """One `Arrival` per load case for rows of weight (N, 3) and inertial forces (N, L, 3) (lift,
    then transports; L = 0: the lift with the weight alone), with each row's transport time (N,)
    (None: the config's fixed one), or None where the object's inertia or support is unknown (the
    step bound)."""
    if obj.inertia is None or obj.support is None:
        return None
    duration = config.transport_time if transport_time is None else transport_time

    def case(transport_force: np.ndarray | None, planned: bool = False) -> Arrival:
        return Arrival(weight, transport_force, np.asarray(obj.inertia, dtype=float), obj.mass,
                       np.asarray(obj.support, dtype=float), config.lift_height, config.lift_time, duration,
                       cup.axial_stiffness, cup.swing_damping_ratio, planned=planned,
                       transport_peak=config.transport_peak, hold_time=config.hold_time)

    if config.transport_direction is not None and inertial.shape[1] == 2:  # one swing in time, both phases
        return [case(inertial[:, 1], planned=True)] * 2
    return [case(None if index == 0 else inertial[:, index]) for index in range(max(inertial.shape[1], 1))]


def inertial_forces(
    mass: float, gravity: np.ndarray, acceleration: float, frames: np.ndarray, azimuths: np.ndarray,
    lift_acceleration: float,
) -> np.ndarray:
    """(N, 1 + A, 3) inertial forces -m a_cup of a pick's motions, in the mesh frame: the lift
    (a_cup = `lift_acceleration` straight up: m a_lift along gravity) and one transport per azimuth
    in `azimuths` (N, A) (a_cup = `acceleration` horizontal, at that angle round the vertical from
    the contact frame's x axis)."""
    gravity = np.asarray(gravity, dtype=float)
    norm = float(np.linalg.norm(gravity))
    count = len(frames)
    down = np.broadcast_to(gravity / norm, (count, 3)) if norm > 0 else frames[:, :, 2]  # no gravity: along v
    ref = frames[:, :, 0] - np.einsum("ni,ni->n", frames[:, :, 0], down)[:, None] * down
    alt = frames[:, :, 1] - np.einsum("ni,ni->n", frames[:, :, 1], down)[:, None] * down
    ref = np.where((np.linalg.norm(ref, axis=1) > 1e-6)[:, None], ref, alt)
    h0 = ref / np.linalg.norm(ref, axis=1, keepdims=True)
    h1 = np.cross(down, h0)
    horizontal = np.cos(azimuths)[..., None] * h0[:, None] + np.sin(azimuths)[..., None] * h1[:, None]
    lift = (mass * lift_acceleration) * down[:, None, :]
    return np.concatenate([lift, -(mass * acceleration) * horizontal], axis=1)


def planned_forces(mass: float, gravity: np.ndarray, config: PerturbationConfig) -> np.ndarray:
    """(2, 3) inertial forces -m a_cup at the peaks of a pick whose transport's direction d is
    known (config.transport_direction, mesh frame): the lift (m a_lift along gravity) and the
    transport (-m a_p d, the object pushed back as the cup sets off). The planned swing
    (contact/swing_path.py) takes the transport's direction from it and follows its braking too."""
    along = np.asarray(config.transport_direction, dtype=float)
    along = along / np.linalg.norm(along)
    gravity = np.asarray(gravity, dtype=float)
    down = gravity / max(float(np.linalg.norm(gravity)), 1e-12)
    return np.stack([mass * config.lift_acceleration * down, -(mass * config.transport_peak) * along])


def truncated_normal(u: np.ndarray, mean: float, std: float, low: float, high: float) -> np.ndarray:
    """Map uniforms u in [0, 1) to a normal(mean, std) truncated to [low, high] (inverse CDF)."""
    if std == 0.0:
        return np.full_like(u, np.clip(mean, low, high))
    a, b = ndtr((low - mean) / std), ndtr((high - mean) / std)
    return np.clip(mean + std * ndtri(a + u * (b - a)), low, high)


def sample_perturbations(
    points: np.ndarray,
    frames: np.ndarray,
    obj: ObjectState,
    cup: CupConfig,
    config: PerturbationConfig,
    seed: int,
    grasp_ids: np.ndarray | None = None,
) -> GraspSamples:
    """Draw J perturbed grasps per nominal grasp (points (N, 3), frames (N, 3, 3))."""
    count, j = len(points), config.num_samples
    ids = np.arange(count) if grasp_ids is None else np.asarray(grasp_ids)
    noise = np.empty((count, j, 19))
    inertial = config.inertial_acceleration > 0.0
    known = inertial and config.transport_direction is not None
    t_min, t_max = config.transport_time, config.transport_time_max
    spread = inertial and not known and t_max is not None and t_max > t_min
    azimuth = np.empty((count, j))
    duration = np.empty((count, j)) if spread else None
    for row, gid in enumerate(ids):  # one short stream per grasp: batch-independent labels
        stream = np.random.default_rng((int(seed), int(gid)))
        noise[row] = stream.standard_normal((j, 19))
        if inertial and not known:  # drawn after the paper's perturbations, which a = 0 leaves untouched
            azimuth[row] = 2.0 * np.pi * stream.random(j)
        if spread:  # and after the azimuth, which a fixed transport time leaves untouched
            duration[row] = t_min + (t_max - t_min) * stream.random(j)
    noise[:, :, 18] = ndtr(noise[:, :, 18])  # the friction draw, as a uniform

    def in_world(cols: slice, std: float) -> np.ndarray:
        """Noise drawn in each nominal contact frame, expressed in the mesh frame."""
        return std * np.einsum("nij,nsj->nsi", frames, noise[:, :, cols])

    grasp_shift = in_world(slice(0, 3), config.grasp_point_std)
    grasp_rot = so3_exp(in_world(slice(3, 6), config.approach_rotation_std))
    obj_shift = in_world(slice(6, 9), config.object_translation_std)
    obj_rot = so3_exp(in_world(slice(9, 12), config.object_rotation_std))
    com_shift = in_world(slice(12, 15), config.com_std)
    force_noise = in_world(slice(15, 18), config.force_noise_std)

    com = np.asarray(obj.com, dtype=float)
    # The object moves by (R_o about the COM, then t_o); the gripper by its own perturbation.
    # In the perturbed object's frame, the grasp is the inverse object motion applied to it.
    inv = np.swapaxes(obj_rot, -1, -2)
    p_world = points[:, None, :] + grasp_shift
    p_obj = np.einsum("nsij,nsj->nsi", inv, p_world - com - obj_shift) + com
    f_obj = inv @ grasp_rot @ frames[:, None]
    force = np.einsum("nsij,j->nsi", inv, obj.gravity_force) + force_noise
    mu = truncated_normal(
        noise[:, :, 18], cup.friction, config.friction_std, config.friction_min, config.friction_max
    )
    if known:  # (N, J, 2, 3): the lift and the transport along the planned line, in the perturbed frame
        cases = np.broadcast_to(planned_forces(obj.mass, obj.gravity, config), (count, j, 2, 3))
        extra = np.einsum("nsij,nskj->nski", inv, cases).reshape(-1, 2, 3)
    elif inertial:  # (N, J, 2, 3): lift and transport, rotated into the perturbed object frame
        cases = inertial_forces(obj.mass, obj.gravity, config.inertial_acceleration, frames, azimuth,
                                config.lift_acceleration)
        lift = np.broadcast_to(cases[:, None, 0], (count, j, 3))
        cases = np.stack([lift, cases[:, 1:]], axis=2)
        extra = np.einsum("nsij,nskj->nski", inv, cases).reshape(-1, 2, 3)
    else:
        extra = np.zeros((count * j, 0, 3))
    return GraspSamples(
        points=p_obj.reshape(-1, 3),
        frames=f_obj.reshape(-1, 3, 3),
        com=(com + com_shift).reshape(-1, 3),
        force=force.reshape(-1, 3),
        friction=mu.reshape(-1),
        transport_time=None if duration is None else duration.reshape(-1),
        inertial=extra,
    )


def evaluate_samples(seal: SealModel, samples: GraspSamples, cases: list[Arrival] | None = None
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Fast path: bool (N*J,) seal-and-resist per sample, staged so rays are cast only where needed,
    and (N*J, 3) where each sample's lip lands (its ring centre where the seal got as far as the
    wrench test, else its target point). `cases`: each load case's arrival (`arrivals`), None for
    the step bound."""
    out = np.zeros(len(samples.points), dtype=bool)
    landed = samples.points.copy()
    cup = seal.cup
    for start in range(0, len(out), CHUNK_SAMPLES):
        sl = slice(start, start + CHUNK_SAMPLES)
        chunk = None if cases is None else [case.take(sl) for case in cases]
        gate = _wrench_gate(samples.loads[sl], samples.com[sl], samples.frames[sl], samples.friction[sl], cup, chunk,
                            landed[sl])
        out[sl] = seal.evaluate(samples.points[sl], samples.frames[sl], gate=gate)
    return out, landed


def _wrench_gate(loads: np.ndarray, com: np.ndarray, frames: np.ndarray, mu: np.ndarray, cup: CupConfig,
                 cases: list[Arrival] | None = None, landed: np.ndarray | None = None):
    """The closed-form wrench test of every load case as a seal-model gate: it only needs the ring
    centres, the vacuum force and the lip's profile. The seal model asks twice (seal.Gate) with
    the same ring centres, so each sample's swung wrench is computed once and kept, and its ring
    centre written to `landed` (a view of the caller's array), where the touch-down presses."""
    wrenches = np.full((len(loads), loads.shape[1], 6), np.nan)
    known = np.zeros(len(loads), dtype=bool)

    def gate(
        idx: np.ndarray, centres: np.ndarray, vacuum: np.ndarray,
        lip_heights: np.ndarray | None = None, rim_bound: bool = False,
    ) -> np.ndarray:
        new = ~known[idx]
        todo, at = idx[new], centres[new]
        wrenches[todo] = lip_loads(loads[todo], com[todo], at, frames[todo], cup,
                                   None if cases is None else [case.take(todo) for case in cases])
        known[todo] = True
        if landed is not None:
            landed[todo] = at
        ok = np.ones(len(idx), dtype=bool)
        for case in range(loads.shape[1]):
            ok &= resists(wrenches[idx, case], mu[idx], cup, vacuum, lip_heights, rim_bound=rim_bound)
        return ok

    return gate


def evaluate_samples_reference(seal: SealModel, samples: GraspSamples, cases: list[Arrival] | None = None
                               ) -> tuple[np.ndarray, np.ndarray]:
    """Reference path: per sample, one full seal evaluation and one cone program per load case,
    in a Python loop; with where each sealed sample's lip lands (as `evaluate_samples`)."""
    out = np.zeros(len(samples.points), dtype=bool)
    landed = samples.points.copy()
    loads = samples.loads
    for i in range(len(out)):
        result = seal.evaluate(samples.points[i : i + 1], samples.frames[i : i + 1])
        if not result.seal[0]:
            continue
        centre, frame = result.ring_centre[0], samples.frames[i]
        landed[i] = centre
        wrenches = lip_loads(loads[i : i + 1], samples.com[i][None], centre[None], frame[None], seal.cup,
                             None if cases is None else [case.take(slice(i, i + 1)) for case in cases])[0]
        out[i] = all(
            resists_qp(
                None, None, centre, frame, float(samples.friction[i]),
                seal.cup, vacuum_force=float(result.vacuum_force[0]),
                lip_heights=None if result.lip_heights is None else result.lip_heights[0],
                wrench_contact=wrench,
            )[0]
            for wrench in wrenches
        )
    return out, landed


def robust_wrench_resistance(
    seal: SealModel,
    points: np.ndarray,
    frames: np.ndarray,
    obj: ObjectState,
    config: PerturbationConfig,
    seed: int,
    *,
    grasp_ids: np.ndarray | None = None,
    reference: bool = False,
    progress: Callable[[int], None] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Robust wrench resistance per grasp and the (N, J) per-sample outcomes behind it.

    `progress`, if given, is called with the number of grasps finished after each chunk.

    Grasps are processed in chunks of about CHUNK_SAMPLES samples, so memory stays flat in N.
    """
    count, j = len(points), config.num_samples
    ids = np.arange(count) if grasp_ids is None else np.asarray(grasp_ids)
    run = evaluate_samples_reference if reference else evaluate_samples
    outcomes = np.zeros((count, j), dtype=bool)
    step = max(1, CHUNK_SAMPLES // j)
    for start in range(0, count, step):
        sl = slice(start, start + step)
        samples = sample_perturbations(points[sl], frames[sl], obj, seal.cup, config, seed, ids[sl])
        cases = arrivals(obj, config, seal.cup, samples.force, samples.inertial, samples.transport_time)
        ok, landed = run(seal, samples, cases)
        if obj.footprint is not None and config.press_compression > 0.0:
            # The object rests on its footprint when pressed: its weight and centre of mass are
            # the nominal ones, which that footprint carries. A perturbed rotation or centre of
            # mass on the same footprint is a state no object at rest is in (a box tilted 0.1 rad
            # on its face, a lying cylinder's centre of mass beside its support line): the table
            # would turn it back. What the perturbation moves for this test is the grasp relative
            # to the object (samples.frames, and where each lip lands: its ring centre, not a
            # target behind the surface it meets first, as the nominal label has it) and the
            # lip's friction.
            ok &= stays_put(landed, samples.frames[:, :, 2], obj.com, obj.gravity_force,
                            seal.cup.axial_stiffness * config.press_compression, samples.friction,
                            config.table_friction, obj.footprint)
        outcomes[sl] = ok.reshape(-1, j)
        if progress is not None:
            progress(len(samples.points) // j)
    return outcomes.mean(axis=1), outcomes
