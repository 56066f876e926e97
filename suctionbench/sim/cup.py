"""The simulated suction cup (DESIGN.md, "Simulated suction cup"): physics, not magic.

A compliant bellow on passive joints (an axial slide and two tilt hinges, each a damped spring)
carries a lip ring of n small spheres at the cup radius. Vacuum is a MuJoCo `adhesion` actuator
on the lip body, with gain = the cup's vacuum force (pressure x area), switched on only while the
seal test passes: every lip sphere touches (within `seal_gap`) one and the same object body. When
a lip sphere lifts off, air leaks in and the vacuum, and with it the force, is gone.

The geometric cup (n, radius, height, vacuum force, friction) is the labeller's `CupConfig`; the
mechanical parameters only the simulation needs are in `SimCupConfig`. Neither is tuned to agree
with the analytic labeller: they are set from physical estimates, documented per field.

Collision bitmasks used by the scene (contype / conaffinity):
    environment (table, bin) 1 / 7, objects 1 / 7, robot links 2 / 1, cup lip and shell 4 / 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from suctionbench.config import CupConfig

ENV_CONTYPE, ENV_CONAFFINITY = 1, 7
CUP_CONTYPE, CUP_CONAFFINITY = 4, 1


@dataclass(frozen=True)
class SimCupConfig:
    """Mechanical properties of the simulated bellow and lip (SI units)."""

    tool_length: float = 0.10
    """Distance from the robot flange to the lip plane along the tool axis (shaft + cup)."""

    shaft_radius: float = 0.008
    """Radius of the rigid tool shaft between flange and bellow."""

    lip_sphere_radius: float = 0.0015
    """Radius of each lip sphere (the lip's rounded edge)."""

    axial_stiffness: float = 1500.0
    """Bellow spring rate along the axis (N/m): a 15 mm single bellow compresses ~5 mm under
    ~7 N of contact force."""

    axial_damping: float = 30.0
    """Axial damping (N s/m): about 1.5 x critical for the lip plus a light object (lossy
    silicone). Less lets a light object chatter against the lip under the 9 N vacuum pull."""

    tilt_stiffness: float = 0.05
    """Bellow bending stiffness about either tilt axis (N m/rad)."""

    tilt_damping: float = 0.01
    """Tilt damping (N m s/rad): silicone bellows are lossy."""

    max_compression: float = 0.006
    """Axial travel of the bellow (m), 40 % of the cup height."""

    max_tilt: float = 0.5
    """Tilt range of the bellow (rad) on either side."""

    lip_mass: float = 0.02
    """Mass of the lip ring (kg), with its fitting. MuJoCo's contact stiffness scales with the
    effective mass, so a few grams would let the 9 N vacuum pull the lip millimetres into the
    object; 20 g with `contact_solref` keeps penetration under ~0.5 mm."""

    contact_solref: tuple[float, float] = (0.004, 1.0)
    """MuJoCo solref of lip contacts (time constant = 2 timesteps, critically damped): as stiff as
    the 2 ms step allows, because the lip is hard rubber on a rigid object."""

    contact_solimp: tuple[float, float, float] = (0.95, 0.99, 0.0005)
    """MuJoCo solimp of lip contacts (impedance rising to 0.99 within 0.5 mm)."""

    contact_margin: float = 0.0005
    """MuJoCo margin of the lip spheres (m): the contact constraint engages 0.5 mm before touch,
    which damps the object's approach when the vacuum pulls it in (a held object hangs ~0.5 mm
    below the lip, a visual artefact)."""

    bellow_mass: float = 0.006
    """Mass of the bellow (kg)."""

    seal_gap: float = 0.001
    """A seal forms when every lip sphere is within this distance (m) of one object's surface."""

    release_gap: float = 0.002
    """An existing seal holds while every lip sphere stays within this distance: the lip is
    flexible and a sub-millimetre gap leaks little. Also the MuJoCo contact gap, so such
    near-contacts exist (inactive for the solver) and the adhesion acts through them."""

    vacuum_time_constant: float = 0.03
    """First-order time constant (s) of the vacuum force: a small cup evacuates, and vents after a
    leak, in tens of milliseconds, so a momentary lift-off does not drop the force at once."""

    shell_height_fraction: float = 0.5
    """The bellow's solid shell starts this fraction of the cup height above the lip plane: anything
    reaching higher inside the ring hits the cup (the labeller's cone collision, physically)."""


@dataclass(frozen=True)
class CupHandles:
    """Names of the cup's MuJoCo elements."""

    tip_site: str
    actuator: str
    slide_joint: str
    lip_geoms: tuple[str, ...]


def add_suction_tool(
    parent: mujoco.MjsBody,
    spec: mujoco.MjSpec,
    cup: CupConfig,
    sim: SimCupConfig = SimCupConfig(),
    *,
    prefix: str = "cup",
    pos=(0.0, 0.0, 0.0),
    quat=(1.0, 0.0, 0.0, 0.0),
) -> CupHandles:
    """Attach shaft, bellow, lip ring, tip site and vacuum actuator to `parent`.

    The tool axis is the parent frame's +z at `pos`/`quat`: the approach direction v. The tip site
    sits at the lip plane's centre, the point that is brought onto the grasp target.
    """
    shaft_len = sim.tool_length - cup.height
    tool = parent.add_body(name=f"{prefix}_tool", pos=list(pos), quat=list(quat))
    tool.add_geom(
        name=f"{prefix}_shaft", type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[sim.shaft_radius, shaft_len / 2, 0],
        pos=[0, 0, shaft_len / 2], contype=CUP_CONTYPE, conaffinity=CUP_CONAFFINITY, mass=0.05, group=3,
        rgba=[0.3, 0.3, 0.35, 1],
    )
    bellow = tool.add_body(name=f"{prefix}_bellow", pos=[0, 0, shaft_len])
    bellow.add_joint(
        name=f"{prefix}_compress", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1],
        stiffness=sim.axial_stiffness, damping=sim.axial_damping, range=[-sim.max_compression, 0.0],
        limited=True, armature=1e-4, solref_limit=list(sim.contact_solref),
    )
    for axis, label in (([1, 0, 0], "tilt_x"), ([0, 1, 0], "tilt_y")):
        bellow.add_joint(
            name=f"{prefix}_{label}", type=mujoco.mjtJoint.mjJNT_HINGE, axis=axis, pos=[0, 0, cup.height],
            stiffness=sim.tilt_stiffness, damping=sim.tilt_damping, range=[-sim.max_tilt, sim.max_tilt],
            limited=True, armature=1e-6, solref_limit=list(sim.contact_solref),
        )
    shell_start = sim.shell_height_fraction * cup.height
    shell_len = cup.height - shell_start
    bellow.add_geom(
        name=f"{prefix}_shell", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
        size=[0.8 * cup.radius, shell_len / 2, 0], pos=[0, 0, shell_start + shell_len / 2],
        contype=CUP_CONTYPE, conaffinity=CUP_CONAFFINITY, mass=sim.bellow_mass, group=3,
        rgba=[0.2, 0.4, 0.8, 0.6],
    )
    # The lip: ring of spheres whose outer surfaces touch the lip plane at z = tool_length.
    lip = bellow.add_body(name=f"{prefix}_lip", pos=[0, 0, cup.height - sim.lip_sphere_radius])
    lip_mass = sim.lip_mass / cup.n_vertices
    names = []
    for i in range(cup.n_vertices):
        angle = 2.0 * math.pi * i / cup.n_vertices
        name = f"{prefix}_lip_{i}"
        lip.add_geom(
            name=name, type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[sim.lip_sphere_radius, 0, 0],
            pos=[cup.radius * math.cos(angle), cup.radius * math.sin(angle), 0.0],
            contype=CUP_CONTYPE, conaffinity=CUP_CONAFFINITY, condim=6, mass=lip_mass,
            friction=[cup.friction, 0.005, 0.0001], margin=sim.contact_margin, gap=sim.release_gap, group=3,
            rgba=[0.1, 0.1, 0.1, 1], priority=1, solref=list(sim.contact_solref),
            solimp=list(sim.contact_solimp) + [0.5, 2.0],
        )
        names.append(name)
    lip.add_site(name=f"{prefix}_tip", pos=[0, 0, sim.lip_sphere_radius], size=[0.002, 0, 0])
    spec.add_actuator(
        name=f"{prefix}_vacuum", trntype=mujoco.mjtTrn.mjTRN_BODY, target=f"{prefix}_lip",
        gaintype=mujoco.mjtGain.mjGAIN_FIXED, gainprm=[cup.vacuum_force] + [0] * 9,
        biastype=mujoco.mjtBias.mjBIAS_NONE, ctrlrange=[0, 1], ctrllimited=True,
        dyntype=mujoco.mjtDyn.mjDYN_FILTEREXACT, dynprm=[sim.vacuum_time_constant] + [0] * 9,
    )
    return CupHandles(
        tip_site=f"{prefix}_tip",
        actuator=f"{prefix}_vacuum", slide_joint=f"{prefix}_compress", lip_geoms=tuple(names),
    )


class SuctionController:
    """Reads the lip contacts each step and drives the vacuum: on only while sealed and commanded."""

    def __init__(self, model: mujoco.MjModel, handles: CupHandles, sim: SimCupConfig = SimCupConfig()):
        self.model = model
        self.sim = sim
        self.lip_geoms = np.array([model.geom(n).id for n in handles.lip_geoms])
        self._lip_slot = np.full(model.ngeom, -1)
        """Per geom: its index among the lip spheres, -1 for any other geom."""
        self._lip_slot[self.lip_geoms] = np.arange(len(self.lip_geoms))
        self.actuator = model.actuator(handles.actuator).id
        self.slide_qpos = model.jnt_qposadr[model.joint(handles.slide_joint).id]
        self.commanded = False
        self.sealed = -1

    def sealed_body(self, data: mujoco.MjData, gap: float | None = None) -> int:
        """Id of the body that every lip sphere touches within `gap` (default seal_gap), else -1."""
        gap = self.sim.seal_gap if gap is None else gap
        n = data.ncon
        if n == 0 or not len(self.lip_geoms):
            return -1
        geoms, near = data.contact.geom[:n], data.contact.dist[:n] <= gap
        touching = np.zeros((len(self.lip_geoms), self.model.nbody), dtype=bool)  # lip sphere x body
        for mine, other in ((0, 1), (1, 0)):
            slot = self._lip_slot[geoms[:, mine]]
            hit = near & (slot >= 0)
            touching[slot[hit], self.model.geom_bodyid[geoms[hit, other]]] = True
        common = touching.all(axis=0)
        common[0] = False  # the world body (table, bin walls): not an object we can lift
        return int(np.argmax(common)) if common.any() else -1

    def compression(self, data: mujoco.MjData) -> float:
        """How far (m) the bellow is compressed."""
        return -float(data.qpos[self.slide_qpos])

    def update(self, data: mujoco.MjData) -> int:
        """Gate the vacuum for this step; returns the sealed body id (-1 if none).

        A seal forms within seal_gap and, while the vacuum is commanded, holds on the same body
        within release_gap (hysteresis); once lost, the vacuum vents.
        """
        if self.commanded and self.sealed >= 0 and self.sealed_body(data, self.sim.release_gap) == self.sealed:
            body = self.sealed
        else:
            body = self.sealed_body(data)
        self.sealed = body if self.commanded else -1
        data.ctrl[self.actuator] = 1.0 if (self.commanded and body >= 0) else 0.0
        return body
