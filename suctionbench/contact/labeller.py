"""One object, one cup: the entry point that ties seal, wrench and robust models together."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import trimesh

from suctionbench.config import STANDARD_GRAVITY, LabelConfig
from suctionbench.contact.arrival import table_support
from suctionbench.contact.metrics import METRICS, GraspLabels
from suctionbench.contact.press import Footprint, stays_put
from suctionbench.contact.robust import ObjectState, arrivals, inertial_forces, planned_forces, robust_wrench_resistance
from suctionbench.contact.seal import PUSHED_AWAY, SealModel, SealResult
from suctionbench.contact.swing import lip_loads
from suctionbench.contact.wrench import resists
from suctionbench.errors import InputError
from suctionbench.geometry.frames import approach_frames
from suctionbench.geometry.mesh import MeshInfo, validate_mesh
from suctionbench.geometry.raycast import RayCaster
from suctionbench.objects.mass import solid_properties

DEFAULT_MASS = 1.0
"""Mass (kg) assumed when the object's mass is unknown, as in the paper."""

NOMINAL_TRANSPORT_AZIMUTHS = np.array([0.0, 0.5, 1.0, 1.5]) * np.pi
"""Transport directions (rad round the vertical, from the contact frame's x axis) the nominal wrench
test checks when the perturbation model has an inertial load: the worst of four horizontal ones."""


def _inertia_about(mesh: trimesh.Trimesh, mass: float, com: np.ndarray) -> np.ndarray:
    """(3, 3) inertia tensor (kg m^2) about `com` of the mesh's solid at uniform density weighing
    `mass` (an object whose centre of mass is modelled off the centroid, a full bottle, keeps its
    shape's spread of mass: an approximation)."""
    return solid_properties(mesh, 1.0).scaled_to(mass).inertia_about(com)


class SuctionLabeller:
    """Labels suction grasps (p, v) on one mesh (in its own frame, metres) with one cup.

    Grasp frames take their x axis from the direction to the centre of mass, so labels move with
    the object under rigid motions (when gravity moves with it too).
    """

    def __init__(
        self,
        mesh: MeshInfo | trimesh.Trimesh,
        config: LabelConfig | None = None,
        *,
        mass: float = DEFAULT_MASS,
        com: np.ndarray | None = None,
        gravity: np.ndarray | tuple[float, float, float] = (0.0, 0.0, -STANDARD_GRAVITY),
    ):
        self.info = mesh if isinstance(mesh, MeshInfo) else validate_mesh(mesh)
        self.config = config or LabelConfig()
        if not (isinstance(mass, (int, float)) and math.isfinite(mass) and mass > 0):
            raise InputError(f"mass {mass!r}: must be a positive number of kilograms")
        com = self.info.center_mass if com is None else np.asarray(com, dtype=float)
        if com.shape != (3,) or not np.all(np.isfinite(com)):
            raise InputError(f"centre of mass {com.tolist()!r}: must be three finite numbers")
        gravity = np.asarray(gravity, dtype=float)
        if gravity.shape != (3,) or not np.all(np.isfinite(gravity)):
            raise InputError(f"gravity {gravity.tolist()!r}: must be three finite numbers")
        hull = np.asarray(self.info.mesh.convex_hull.vertices, dtype=float)
        self.object = ObjectState(com=com, mass=float(mass), gravity=gravity,
                                  inertia=_inertia_about(self.info.mesh, float(mass), com),
                                  support=table_support(hull, gravity), footprint=Footprint(hull, gravity))
        self.caster = RayCaster(self.info.mesh)
        self.seal_model = SealModel(self.caster, self.config.cup, self.config.seal)

    @property
    def mesh(self) -> trimesh.Trimesh:
        """The labelled mesh."""
        return self.info.mesh

    def frames(self, points: np.ndarray, approaches: np.ndarray) -> np.ndarray:
        """Grasp frames (N, 3, 3): z = approach, x toward the centre of mass in the cup plane."""
        points, approaches = _check_grasps(points, approaches)
        return approach_frames(approaches, self.object.com - points)

    def seal(self, points: np.ndarray, approaches: np.ndarray) -> SealResult:
        """Nominal seal model for each grasp; with a touch-down press in the perturbation model, a
        seal also needs the object to stay put under it (contact/press.py), pressed where the lip
        lands: the ring centre on the first surface along the approach (seal.py), which is not the
        target where another surface lies across the approach (a target inside a lying tube's bore
        is reached through its crown, where the cup seals)."""
        points, approaches = _check_grasps(points, approaches)
        result = self.seal_model.evaluate(points, self.frames(points, approaches))
        landed = np.where(np.isfinite(result.ring_centre), result.ring_centre, points)
        pushed = result.seal & ~self.stays_put(landed, approaches)
        result.seal[pushed] = False
        result.failure[pushed] = PUSHED_AWAY
        return result

    def stays_put(self, points: np.ndarray, approaches: np.ndarray) -> np.ndarray:
        """bool (N,): the object stays at rest while the touch-down presses each grasp (all True
        without a press in the perturbation model)."""
        motion = self.config.perturbation
        if motion.press_compression <= 0.0:
            return np.ones(len(points), dtype=bool)
        return stays_put(points, approaches, self.object.com, self.object.gravity_force,
                         self.config.cup.axial_stiffness * motion.press_compression, self.config.cup.friction,
                         motion.table_friction, self.object.footprint)

    def wrench_resistance(
        self, points: np.ndarray, approaches: np.ndarray, seal: SealResult | None = None
    ) -> np.ndarray:
        """Nominal (unperturbed) wrench resistance: seal, and resist the weight with the vacuum the
        seal holds. With an inertial load in the perturbation model, also the lift and transport
        loads (the transport at four horizontal directions, NOMINAL_TRANSPORT_AZIMUTHS)."""
        points, approaches = _check_grasps(points, approaches)
        frames = self.frames(points, approaches)
        seal = seal if seal is not None else self.seal(points, approaches)  # with the press, as label() has it
        ok = seal.seal.copy()
        for wrench in self.nominal_lip_loads(frames, seal):
            ok &= resists(wrench, self.config.cup.friction, self.config.cup, seal.vacuum_force, seal.lip_heights)
        return ok

    def nominal_lip_loads(self, frames: np.ndarray, seal: SealResult) -> list[np.ndarray]:
        """The wrench (N, 6) the lip carries in each nominal load case (`lip_loads`): the weight
        alone, or with an inertial load the lift and the transport at each of
        NOMINAL_TRANSPORT_AZIMUTHS (at the swing's turning points), or, where the pick's motion is
        planned, the lift's and the carry's worst instants of the swing followed in time; for
        grasps of contact `frames` (N, 3, 3) and their `seal`."""
        count = len(frames)
        weight = np.broadcast_to(self.object.gravity_force, (count, 3))
        inertial = np.zeros((count, 1, 3))
        motion = self.config.perturbation
        if motion.inertial_acceleration > 0.0 and motion.transport_direction is not None:
            inertial = np.broadcast_to(planned_forces(self.object.mass, self.object.gravity, motion), (count, 2, 3))
        elif motion.inertial_acceleration > 0.0:
            azimuths = np.broadcast_to(NOMINAL_TRANSPORT_AZIMUTHS, (count, len(NOMINAL_TRANSPORT_AZIMUTHS)))
            inertial = inertial_forces(self.object.mass, self.object.gravity, motion.inertial_acceleration, frames,
                                       azimuths, motion.lift_acceleration)
        com = np.broadcast_to(self.object.com, (count, 3))
        cases = arrivals(self.object, motion, self.config.cup, weight, inertial)
        loads = lip_loads(weight[:, None] + inertial, com, seal.ring_centre, frames, self.config.cup, cases)
        return list(loads.transpose(1, 0, 2))

    def robust(
        self,
        points: np.ndarray,
        approaches: np.ndarray,
        seed: int,
        *,
        grasp_ids: np.ndarray | None = None,
        reference: bool = False,
        progress: Callable[[int], None] | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Robust wrench resistance per grasp, and the (N, J) sample outcomes behind it."""
        points, approaches = _check_grasps(points, approaches)
        return robust_wrench_resistance(
            self.seal_model, points, self.frames(points, approaches), self.object,
            self.config.perturbation, seed, grasp_ids=grasp_ids, reference=reference,
            progress=progress,
        )

    def label(
        self,
        points: np.ndarray,
        approaches: np.ndarray,
        seed: int,
        *,
        metrics: tuple[str, ...] = tuple(METRICS),
        grasp_ids: np.ndarray | None = None,
        progress: Callable[[int], None] | None = None,
    ) -> GraspLabels:
        """Every requested metric for each grasp (the robust one only when asked for)."""
        unknown = [m for m in metrics if m not in METRICS]
        if unknown:
            raise InputError(f"metric '{unknown[0]}' is unknown (known: {', '.join(METRICS)})")
        points, approaches = _check_grasps(points, approaches)
        seal = self.seal(points, approaches)
        rwr, samples = (None, None)
        if "rwr" in metrics:
            rwr, samples = self.robust(points, approaches, seed, grasp_ids=grasp_ids, progress=progress)
        return GraspLabels(
            points=points,
            approaches=approaches,
            seal=seal,
            wr=self.wrench_resistance(points, approaches, seal),
            rwr=rwr,
            samples=samples,
            com=self.object.com,
            config=self.config,
        )


def _check_grasps(points: np.ndarray, approaches: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Validate grasp arrays: (N, 3) finite points and unit approach vectors."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    approaches = np.atleast_2d(np.asarray(approaches, dtype=float))
    if points.shape != approaches.shape or points.ndim != 2 or points.shape[1] != 3:
        raise InputError(
            f"grasps: points {points.shape} and approaches {approaches.shape} must both be (N, 3)"
        )
    if not (np.all(np.isfinite(points)) and np.all(np.isfinite(approaches))):
        raise InputError("grasps: points and approaches must be finite (got NaN or inf)")
    norms = np.linalg.norm(approaches, axis=1)
    bad = np.flatnonzero(np.abs(norms - 1.0) > 1e-6)
    if len(bad):
        raise InputError(
            f"grasp {bad[0]}: approach vector {approaches[bad[0]].tolist()} has length "
            f"{norms[bad[0]]:.6g}, must be a unit vector"
        )
    return points, approaches
