"""A cup test rig: the simulated suction cup on a stiff three-axis carriage over a floor, for
physical-fact experiments on small objects without the robot arm (tests/test_cup_physics.py).

The carriage is a heavy body (gravity compensated, like a robot holding its tool) on x, y, z slides
with stiff position servos; it carries the cup at any fixed orientation. `CupRig.grasp` runs the
episode's grasp: a guarded approach along the cup axis until the bellows is compressed by
`EpisodeConfig.compression_stop`, the vacuum dwell, a minimum-jerk lift, and a hold, and reports
what happened. Objects are added by a callback on the MjSpec; the rig exposes their colliding geoms
to the cup (`suctionbench.sim.cup.expose_to_vacuum`: SURFACE_GROUP, where the leak test looks).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco
import numpy as np

from suctionbench import minjerk
from suctionbench.config import CUP_DEFAULT, CupConfig
from suctionbench.sim.cup import (
    ENV_CONAFFINITY,
    ENV_CONTYPE,
    SIM_CUP_DEFAULT,
    SimCupConfig,
    add_suction_tool,
    expose_to_vacuum,
)
from suctionbench.sim.episode_config import EpisodeConfig
from suctionbench.sim.suction import SuctionController

CARRIAGE_MASS = 5.0
"""Mass (kg) of the carriage: much heavier than anything the cup lifts, as an arm is."""

CARRIAGE_STIFFNESS = 2.0e4
"""Position-servo stiffness (N/m) per axis; 10 N of contact load deflects it by 0.5 mm."""


@dataclass
class RigResult:
    """What one grasp in the rig did."""

    sealed: bool
    """The vacuum reached the switch point on the object before the lift."""
    held: bool
    """Still sealed at the end of the hold."""
    lifted: bool
    """The object rose by at least half the lift height."""
    leak_area: float
    """Leak area (m^2) at the end of the dwell."""
    vacuum: float
    """Vacuum (fraction of p_max) at the end of the dwell."""
    compression: float
    """Bellows compression (m) when the approach stopped."""
    tilt: float
    """Bellows tilt (rad) at the end of the dwell."""
    gaps: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    """Lip gaps (m) at the end of the dwell."""
    peak_acceleration: float = 0.0
    """Largest acceleration (m/s^2) of the carriage during the lift."""
    peak_gravity_torque: float = 0.0
    """Largest gravity torque (N m) of the object about the lip centre while it hung sealed and clear
    of the floor: m g times the horizontal distance from the lip centre to the centre of mass."""
    tilt_hanging: float = 0.0
    """Angle (rad) between the cup axis and the vertical at the end (or when the seal broke)."""


def add_box(spec: mujoco.MjSpec, name: str, body: mujoco.MjsBody, size, pos, rgba=(0.8, 0.55, 0.3, 1)) -> None:
    """A box geom with the objects' friction, solver and collision settings
    (suctionbench.objects.mjcf)."""
    from suctionbench.objects.mjcf import CONTACT_SOLREF, OBJECT_CONAFFINITY, OBJECT_CONTYPE, TORSIONAL_FRICTION

    body.add_geom(
        name=name, type=mujoco.mjtGeom.mjGEOM_BOX, size=list(size), pos=list(pos), group=2, condim=6,
        friction=[CUP_DEFAULT.friction, TORSIONAL_FRICTION, 0.0001], solref=list(CONTACT_SOLREF),
        contype=OBJECT_CONTYPE, conaffinity=OBJECT_CONAFFINITY, rgba=list(rgba), density=0.0,
    )


class CupRig:
    """A floor, one object (added by `build_object(spec) -> body name`), and the cup on a carriage
    whose tool axis is `axis` (unit, world frame; default straight down)."""

    def __init__(
        self,
        build_object: Callable[[mujoco.MjSpec], str],
        *,
        axis=(0.0, 0.0, -1.0),
        cup: CupConfig = CUP_DEFAULT,
        sim: SimCupConfig = SIM_CUP_DEFAULT,
        start=(0.0, 0.0, 0.2),
        timestep: float = 0.002,
    ):
        spec = mujoco.MjSpec()
        spec.compiler.degree = False
        spec.option.timestep = timestep
        spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
        spec.worldbody.add_geom(
            name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[1, 1, 0.1], contype=ENV_CONTYPE,
            conaffinity=ENV_CONAFFINITY, friction=[0.6, 0.005, 0.0001], solref=[0.005, 1.0],
        )
        self.object_name = build_object(spec)
        expose_to_vacuum(spec.body(self.object_name))
        axis = np.asarray(axis, float) / np.linalg.norm(axis)
        carriage = spec.worldbody.add_body(name="carriage", pos=list(start), gravcomp=1.0)
        carriage.add_geom(name="carriage_mass", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.01, 0, 0],
                          mass=CARRIAGE_MASS, contype=0, conaffinity=0, group=4)
        damping = 2.0 * np.sqrt(CARRIAGE_STIFFNESS * CARRIAGE_MASS)  # critically damped servo
        for i, name in enumerate("xyz"):
            direction = [0.0, 0.0, 0.0]
            direction[i] = 1.0
            carriage.add_joint(name=f"carriage_{name}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=direction,
                               damping=damping)
            spec.add_actuator(
                name=f"carriage_{name}", target=f"carriage_{name}", trntype=mujoco.mjtTrn.mjTRN_JOINT,
                gaintype=mujoco.mjtGain.mjGAIN_FIXED, gainprm=[CARRIAGE_STIFFNESS] + [0] * 9,
                biastype=mujoco.mjtBias.mjBIAS_AFFINE, biasprm=[0, -CARRIAGE_STIFFNESS, 0] + [0] * 7,
            )
        quat = np.zeros(4)
        mujoco.mju_quatZ2Vec(quat, axis)
        self.handles = add_suction_tool(carriage, spec, cup, sim, quat=quat)
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self.cup = SuctionController(self.model, self.handles)
        self.axis = axis
        self.tool_length = sim.tool_length
        self.carriage_dofs = np.array([self.model.joint(f"carriage_{n}").dofadr[0] for n in "xyz"])
        self.carriage_qpos = np.array([self.model.joint(f"carriage_{n}").qposadr[0] for n in "xyz"])
        self.carriage_act = np.array([self.model.actuator(f"carriage_{n}").id for n in "xyz"])
        self.object = self.model.body(self.object_name).id
        self.tip = self.model.site(self.handles.tip_site).id
        self.start = np.asarray(start, float)

    def settle(self, seconds: float = 0.3) -> None:
        """Let the object come to rest on the floor, the cup parked at its start."""
        mujoco.mj_forward(self.model, self.data)
        self.data.ctrl[self.carriage_act] = 0.0
        self._run(int(seconds / self.model.opt.timestep), np.zeros(3))

    def _run(self, steps: int, target, until=None) -> int:
        for k in range(steps):
            self.data.ctrl[self.carriage_act] = target(k) if callable(target) else target
            self.cup.update(self.data)
            mujoco.mj_step(self.model, self.data)
            if until is not None and until():
                return k + 1
        return steps

    def hold(self, seconds: float, each_step: Callable[[int], bool] | None = None) -> int:
        """Keep the carriage where it is for `seconds` (the vacuum as it is), calling
        `each_step(k)` before each step; stop early when it returns True. Returns the steps run."""
        here = self.data.ctrl[self.carriage_act].copy()
        steps = int(round(seconds / self.model.opt.timestep))
        for k in range(steps):
            if each_step is not None and each_step(k):
                return k
            self.data.ctrl[self.carriage_act] = here
            self.cup.update(self.data)
            mujoco.mj_step(self.model, self.data)
        return steps

    def gravity_torque(self) -> float:
        """Gravity torque (N m) of everything hanging from the object's subtree about the lip centre:
        its weight times the horizontal distance from the lip centre to its centre of mass."""
        m, d = self.model, self.data
        lever = d.subtree_com[self.object][:2] - self.tip_position()[:2]
        return float(m.body_subtreemass[self.object] * np.linalg.norm(m.opt.gravity) * np.linalg.norm(lever))

    def clear_of_floor(self) -> bool:
        """Whether the object hangs free: no contact with the world (within its margin)."""
        n = self.data.ncon
        if n == 0:
            return True
        bodies = self.model.geom_bodyid[self.data.contact.geom[:n]]
        mine = (bodies == self.object).any(axis=1) & (bodies == 0).any(axis=1)
        return not bool(np.any(mine & (self.data.contact.dist[:n] < 0.001)))

    def tip_position(self) -> np.ndarray:
        return self.data.site_xpos[self.tip].copy()

    def grasp(self, target, *, episode: EpisodeConfig | None = None, lift: float = 0.1,
              lift_time: float = 1.0, hold: float = 0.5) -> RigResult:
        """Bring the lip centre to `target` (world) along the cup axis (guarded: stop once the bellows
        has compressed by compression_stop), vacuum on, dwell, lift by `lift` (straight up,
        minimum-jerk over `lift_time`), hold; report the seal, hold and lift."""
        episode = episode or EpisodeConfig()
        self.settle()
        m, d, dt = self.model, self.data, self.model.opt.timestep
        target = np.asarray(target, float)
        # The carriage's set point that puts the (uncompressed) lip centre at p: p - tip offset.
        offset = self.tip_position() - d.qpos[self.carriage_qpos]
        start = target - episode.pregrasp_offset * self.axis - offset
        steps = int(0.5 / dt)
        here = d.qpos[self.carriage_qpos].copy()
        self._run(steps, lambda k: here + (start - here) * minjerk.position((k + 1) / steps))
        travel = episode.pregrasp_offset + episode.press_depth
        steps = int(travel / episode.approach_speed / dt)
        self._run(steps, lambda k: start + self.axis * travel * (k + 1) / steps,
                  until=lambda: self.cup.compression(d) >= episode.compression_stop)
        compression = self.cup.compression(d)
        hold_at = d.qpos[self.carriage_qpos].copy()  # hold where the approach stopped, as the episode does
        self.cup.commanded = True
        self._run(int(episode.vacuum_dwell / dt), hold_at)
        gaps = self.cup.lip_gaps(d, self.object) if self.cup.candidate == self.object else np.zeros(0)
        sealed = self.cup.sealed == self.object
        leak, vacuum = self.cup.leak_area, self.cup.vacuum(d)
        tilt = float(np.hypot(*[d.qpos[m.joint(f"cup_tilt_{a}").qposadr[0]] for a in "xy"]))
        z0 = d.xipos[self.object][2]
        steps = int(lift_time / dt)
        velocities = []
        torque = [0.0, 0.0]
        weight = m.body_subtreemass[self.object] * float(np.linalg.norm(m.opt.gravity))

        def watch() -> bool:
            if self.cup.sealed == self.object and self.clear_of_floor():
                lever = d.xipos[self.object][:2] - self.tip_position()[:2]
                torque[0] = max(torque[0], weight * float(np.linalg.norm(lever)))
                rot = d.xmat[self.cup.bellow].reshape(3, 3)
                torque[1] = float(np.arccos(np.clip(-rot[2, 2], -1.0, 1.0)))
            return False

        def lifting(k):
            velocities.append(d.qvel[self.carriage_dofs].copy())
            return hold_at + np.array([0.0, 0.0, lift]) * minjerk.position((k + 1) / steps)

        self._run(steps, lifting, until=watch)
        self._run(int(hold / dt), hold_at + np.array([0.0, 0.0, lift]), until=watch)
        acc = np.linalg.norm(np.diff(np.array(velocities), axis=0), axis=1) / dt if len(velocities) > 1 else [0.0]
        return RigResult(
            sealed=sealed, held=self.cup.sealed == self.object,
            lifted=bool(d.xipos[self.object][2] - z0 > 0.5 * lift), leak_area=leak, vacuum=vacuum,
            compression=compression, tilt=tilt, gaps=gaps, peak_acceleration=float(np.max(acc)),
            peak_gravity_torque=torque[0], tilt_hanging=torque[1],
        )

