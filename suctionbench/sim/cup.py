"""The simulated suction cup (docs/physics.md, "Simulated cup"): physics, not magic.

A bellows on passive joints (an axial slide and two tilt hinges about the lip centre, damped
springs with the rates of `CupConfig`) carries a lip of n >= 16 points, each a small sphere on its
own sprung axial slide that folds back by at most `CupConfig.lip_travel`: the lip conforms to a
curved surface as a silicone lip does, and where the surface falls away by more than it can fold,
a gap stays open.

Vacuum: the cup's pressure acts through two actuators driven by `suctionbench.sim.suction`'s
`SuctionController` (its leak test, the ejector's vacuum, the seal).

The physical cup (radius, effective area, vacuum, ejector, stiffnesses, stroke, lip travel, seal gap,
friction) is `CupConfig`, shared with the analytic labeller; `SimCupConfig` holds only what the
simulation adds (masses and MuJoCo solver settings chosen for stability at the 2 ms step, damping,
the leak test's sampling). Nothing here is tuned to agree with the labeller.

`SimCupConfig.rigid()` is the cup this module replaced (8 spheres on a rigid ring, sealed while all
touch one body within 1 mm and held within 2 mm): kept only as the speed reference of
`suctionbench bench episode`.

Collision bitmasks used by the scene (contype / conaffinity):
    environment (table, bin) 1 / 7, objects 1 / 7 + 8 (`expose_to_vacuum`), robot links 2 / 1,
    cup lip and shell 4 / 1, the cup's vacuum probe 8 / 0.
Geom groups: objects' visual meshes 2; their collision geoms SURFACE_GROUP (5, what the leak test
measures) once `expose_to_vacuum` has marked them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco

from suctionbench.config import CupConfig

ENV_CONTYPE, ENV_CONAFFINITY = 1, 7
CUP_CONTYPE, CUP_CONAFFINITY = 4, 1
VACUUM_CONTYPE = 8
"""Collision bit of the cup's vacuum probe; objects accept it (`expose_to_vacuum`), the environment,
the robot and the cup do not."""
SURFACE_GROUP = 5
"""Geom group of the objects' collision geoms once `expose_to_vacuum` has marked them: the surface
the lip rests on, which the leak test measures (hidden in renders and the viewer, like group 3)."""


@dataclass(frozen=True)
class SimCupConfig:
    """What the simulation adds to the physical cup (`CupConfig`): masses, damping, MuJoCo solver
    settings and the leak test's sampling (SI units)."""

    compliant: bool = True
    """The compliant, leak-aware cup. False: the rigid reference cup (see `rigid()`)."""

    lip_points: int = 16
    """Lip points, each on its own sprung axial slide (>= 16: 2.9 mm apart on the 47 mm lip, so the
    1.5 mm spheres form a nearly closed rim)."""

    leak_samples: int = 48
    """Places round the lip circle where the leak test measures the gap (0.98 mm apart on the 15 mm
    cup: a 2 mm groove crossing the lip covers at least two)."""

    tool_length: float = 0.10
    """Distance from the robot flange to the lip plane along the tool axis (shaft + cup)."""

    shaft_radius: float = 0.008
    """Radius of the rigid tool shaft between flange and bellows."""

    lip_sphere_radius: float = 0.001
    """Radius of each lip sphere (the lip's rounded edge). Small, because a sphere resting on a
    slope touches it inside the lip circle (by rho sin(slope): 0.6 mm on a 38 deg slope), which
    shortens the lip's effective radius on curved surfaces; 1 mm spheres 2.9 mm apart still form
    a rim that nothing the objects have reaches between."""

    axial_damping: float = 30.0
    """Bellows axial damping (N s/m): about 1.5 x critical for the lip plus a light object (lossy
    silicone). Less lets a light object chatter against the lip under the vacuum pull."""

    swing_frequency: float = 14.0
    """Angular frequency (rad/s) of a lifted object's swing on the bellows, at which the tilt
    damping matches the silicone's loss: sqrt((m g h + k_b) / (m h^2 + I)), centre of mass h below
    the lip, is 13.4 rad/s for the 0.37 kg cube held at the centre of its top face, and 9.7-28.6
    rad/s (median 13.5) over the ten basic objects above 0.15 kg held so (the loads that test the
    lip); light objects swing faster (up to 150 rad/s, a matchbox) and hardly load it."""

    tilt_damping: float | None = None
    """Bellows tilt damping (N m s/rad). None: the silicone's, eta k_b / swing_frequency (a
    hysteretic loss factor eta = CupConfig.bellows_loss_factor acts as a viscous damping
    eta k / omega at frequency omega): 2.3e-4 for the default cup. It was 0.01, 44x that, which
    turned a swinging object's speed into moment on the lip (0.019 N m at 107 deg/s, as much as
    its whole ring limit) and peeled it in the lift."""

    stop_travel: float = 0.23
    """How far (rad) the bellows tilts beyond its stop before the hinges' hard limit: the squeezed
    wall's stack (3 mm, `CupConfig.stop_stiffness`) crushed by half at its mean radius 6.5 mm,
    atan(1.5 / 6.5). Up to it the stop is the controller's spring."""

    tilt_armature: float = 1e-5
    """Armature (kg m^2) of the bellows' tilt hinges. MuJoCo's limit stiffness scales with the dof's
    inertia; the bellows' own (~1e-6 kg m^2) lets a lip pressed with ~6 N tilt 1.5 deg past the
    limit, 1e-5 keeps it to ~0.2 deg."""

    lip_damping_ratio: float = 1.0
    """Damping of each lip point's fold, as a fraction of critical (lossy silicone: no ringing)."""

    lip_mass: float = 0.004
    """Mass of the whole lip (kg), shared by its points: a few grams of silicone."""

    lip_armature: float = 0.01
    """Armature (kg) of each lip point's slide: inertia along the fold only, no weight. MuJoCo's
    contact stiffness scales with the contact's effective mass; at a fraction of a gram per point
    the vacuum's pull would press a point a millimetre into the object. With 10 g the pressed lip
    rests within ~0.1 mm of its margin (see `contact_margin`), and a point still folds through its
    travel in ~15 ms."""

    bellow_mass: float = 0.006
    """Mass of the bellows (kg)."""

    contact_solref: tuple[float, float] = (0.004, 2.0)
    """MuJoCo solref of lip contacts and of the bellows' and lip's travel limits: time constant = 2
    timesteps (as stiff as the 2 ms step allows), damping ratio 2. Critically damped (1), a 0.2 kg
    object hanging on the lip under the vacuum's pull rings in a ~35 Hz limit cycle of +-0.5 mm
    (the light lip points between two stiff constraints), which also lets it walk sideways under
    the lip; at 2 it rests still, 0.1 mm into the lip's margin."""

    contact_solimp: tuple[float, float, float] = (0.95, 0.99, 0.0005)
    """MuJoCo solimp of lip contacts (impedance rising to 0.99 within 0.5 mm)."""

    contact_margin: float = 0.0005
    """MuJoCo margin of the lip spheres (m): a pressed lip point rests this far from the object's
    collision surface. The leak test measures gaps from this resting distance."""

    contact_gap: float = 0.001
    """MuJoCo gap of the lip spheres (m): contacts exist (inactive for the solver) up to this far
    beyond the margin, so a lip point lifted by less still carries its share of the vacuum's pull
    (the pressure acts on the object as long as it lasts; the leak test decides how long)."""

    vacuum_time_constant: float = 0.03
    """First-order time constant (s) of the cup's vacuum: the cup (~2.7 cm^3) and its hose
    (~4 cm^3) evacuated by the 16 l/min ejector, V / Q = 6.7 cm^3 / 267 cm^3/s = 25 ms."""

    leak_test_interval: float = 0.008
    """Time (s) between leak tests: about a quarter of the vacuum time constant, so the pressure
    reacts to a new leak within a fraction of the time it takes to vent."""

    ray_apex_height: float = 0.05
    """The leak test casts its rays from one point on the cup axis this far behind the lip plane
    (inside the shaft) through each lip place: 8.5 deg off axial on the 15 mm cup."""

    probe_radius: float = 0.001
    """Radius (m) of the vacuum probe sphere on the cup axis."""

    probe_clearance: float = 0.001
    """Distance (m) of the probe's surface behind the deepest the lip can fold to (lip_travel behind
    the lip plane), so a surface the lip rests on never touches it."""

    shell_height_fraction: float = 0.5
    """The bellows' solid shell (radius 0.8 r) reaches down to this fraction of the cup height above
    the lip plane: anything reaching higher inside the ring hits the cup."""

    rigid_seal_gap: float = 0.001
    """Rigid reference only: a seal forms when every lip sphere is within this distance (m)."""

    rigid_release_gap: float = 0.002
    """Rigid reference only: a seal holds while every lip sphere stays within this distance (m)."""

    rigid_lip_mass: float = 0.02
    """Rigid reference only: mass of its rigid lip ring (kg)."""

    rigid_contact_solref: tuple[float, float] = (0.004, 1.0)
    """Rigid reference only: its lip contacts' solref (as it was)."""

    rigid_sphere_radius: float = 0.0015
    """Rigid reference only: radius of its lip spheres (m)."""

    def __post_init__(self) -> None:
        if self.compliant and self.lip_points < 16:
            raise ValueError(f"sim cup: lip_points = {self.lip_points} must be >= 16 for the compliant cup")
        if self.leak_samples < 32:
            raise ValueError(f"sim cup: leak_samples = {self.leak_samples} must be >= 32")

    @classmethod
    def rigid(cls) -> SimCupConfig:
        """The rigid reference cup: 8 spheres on one rigid ring, no leak test (speed reference)."""
        return cls(compliant=False, lip_points=8)

    def silicone_damping(self, cup: CupConfig, stiffness: float) -> float:
        """Viscous damping (N m s/rad) equivalent to the silicone's loss on a spring of `stiffness`
        swinging at swing_frequency: eta k / omega (eta = cup.bellows_loss_factor)."""
        return cup.bellows_loss_factor * stiffness / self.swing_frequency

    def tilt_damping_for(self, cup: CupConfig) -> float:
        """The tilt hinges' damping for `cup` (see tilt_damping)."""
        return self.tilt_damping if self.tilt_damping is not None else self.silicone_damping(cup, cup.bending_stiffness)

    def stop_damping_for(self, cup: CupConfig) -> float:
        """Damping of the bellows' stop spring: the silicone's loss on `cup.stop_stiffness` (an upper
        estimate at the swing's frequency: the catch rings faster)."""
        return self.silicone_damping(cup, cup.stop_stiffness)

    def lip_point_stiffness(self, cup: CupConfig) -> float:
        """Fold stiffness (N/m) of one lip point: the ring's rate `cup.lip_rate`
        (V / (lip_fold_fraction x lip_travel)) shared by the points."""
        return cup.lip_rate / self.lip_points


SIM_CUP_DEFAULT = SimCupConfig()
"""The compliant, leak-aware cup of the benchmark."""


@dataclass(frozen=True)
class CupHandles:
    """Names of the cup's MuJoCo elements and the configurations they were built from."""

    tip_site: str
    tool_body: str
    actuators: tuple[str, ...]
    slide_joint: str
    lip_geoms: tuple[str, ...]
    lip_joints: tuple[str, ...]
    bellow_body: str
    cup: CupConfig
    sim: SimCupConfig
    tilt_joints: tuple[str, ...] = ()
    """The bellows' two tilt hinges whose stop spring the controller applies (compliant cup)."""

    @property
    def actuator(self) -> str:
        """The first vacuum actuator (all carry the same pressure)."""
        return self.actuators[0]


def add_suction_tool(
    parent: mujoco.MjsBody,
    spec: mujoco.MjSpec,
    cup: CupConfig,
    sim: SimCupConfig = SIM_CUP_DEFAULT,
    *,
    prefix: str = "cup",
    pos=(0.0, 0.0, 0.0),
    quat=(1.0, 0.0, 0.0, 0.0),
) -> CupHandles:
    """Attach shaft, bellows, lip, tip site and vacuum actuators to `parent`.

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
    # Bellows: the axial spring over the stroke, and the tilt about the lip centre. One side of the
    # wall can compress by at most the stroke while the other is uncompressed: the lip plane reaches
    # its stop at cup.approach_tolerance = atan(stroke / 2r) (21.8 deg for the default cup). The
    # compliant cup's stop is a spring the controller applies beyond it (the folded wall squeezed,
    # `CupConfig.stop_stiffness`); the hinges' hard limit lies where the wall is crushed.
    hinge_limit = cup.approach_tolerance + (sim.stop_travel if sim.compliant else 0.0)
    hinge_limit *= 180.0 / math.pi if spec.compiler.degree else 1.0  # hinge ranges are in the spec's unit
    bellow.add_joint(
        name=f"{prefix}_compress", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1],
        stiffness=cup.axial_stiffness, damping=sim.axial_damping, range=[-cup.stroke, 0.0],
        limited=True, armature=1e-4, solref_limit=list(sim.contact_solref),
    )
    for axis, label in (([1, 0, 0], "tilt_x"), ([0, 1, 0], "tilt_y")):
        bellow.add_joint(
            name=f"{prefix}_{label}", type=mujoco.mjtJoint.mjJNT_HINGE, axis=axis, pos=[0, 0, cup.height],
            stiffness=cup.bending_stiffness, damping=sim.tilt_damping_for(cup), range=[-hinge_limit, hinge_limit],
            limited=True, armature=sim.tilt_armature, solref_limit=list(sim.contact_solref),
        )
    shell_len = (1.0 - sim.shell_height_fraction) * cup.height
    bellow.add_geom(
        name=f"{prefix}_shell", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
        size=[0.8 * cup.radius, shell_len / 2, 0], pos=[0, 0, shell_len / 2],
        contype=CUP_CONTYPE, conaffinity=CUP_CONAFFINITY, mass=sim.bellow_mass, group=3,
        rgba=[0.2, 0.4, 0.8, 0.6],
    )
    bellow.add_site(name=f"{prefix}_tip", pos=[0, 0, cup.height], size=[0.002, 0, 0])
    lip_geom = {
        "type": mujoco.mjtGeom.mjGEOM_SPHERE, "size": [sim.lip_sphere_radius, 0, 0],
        "contype": CUP_CONTYPE, "conaffinity": CUP_CONAFFINITY, "margin": sim.contact_margin, "group": 3,
        "rgba": [0.1, 0.1, 0.1, 1], "priority": 1, "solref": list(sim.contact_solref),
        "solimp": list(sim.contact_solimp) + [0.5, 2.0],
    }
    vacuum = {
        "trntype": mujoco.mjtTrn.mjTRN_BODY, "gaintype": mujoco.mjtGain.mjGAIN_FIXED,
        "biastype": mujoco.mjtBias.mjBIAS_NONE, "ctrlrange": [0, 1], "ctrllimited": True,
        "dyntype": mujoco.mjtDyn.mjDYN_FILTEREXACT, "dynprm": [sim.vacuum_time_constant] + [0] * 9,
    }
    n = sim.lip_points
    if not sim.compliant:  # the rigid reference: one ring body, one actuator, the old 1 / 2 mm gaps
        rho = sim.rigid_sphere_radius
        lip = bellow.add_body(name=f"{prefix}_lip", pos=[0, 0, cup.height - rho])
        names = []
        for i in range(n):
            angle = 2.0 * math.pi * i / n
            names.append(f"{prefix}_lip_{i}")
            lip.add_geom(
                name=names[-1], pos=[cup.radius * math.cos(angle), cup.radius * math.sin(angle), 0.0],
                condim=6, mass=sim.rigid_lip_mass / n, friction=[cup.friction, 0.005, 0.0001],
                **{**lip_geom, "size": [rho, 0, 0], "solref": list(sim.rigid_contact_solref)},
                gap=sim.rigid_release_gap,
            )
        spec.add_actuator(name=f"{prefix}_vacuum", target=f"{prefix}_lip", gainprm=[cup.vacuum_force] + [0] * 9,
                          **vacuum)
        return CupHandles(
            tip_site=f"{prefix}_tip", tool_body=f"{prefix}_tool", actuators=(f"{prefix}_vacuum",),
            slide_joint=f"{prefix}_compress",
            lip_geoms=tuple(names), lip_joints=(), bellow_body=f"{prefix}_bellow", cup=cup, sim=sim,
        )
    # The compliant lip: n points, each on its own slide along the axis, folding back (q < 0) by up
    # to lip_travel against its spring; unfolded (q = 0) the sphere's bottom is on the lip plane.
    k = sim.lip_point_stiffness(cup)
    point_mass = sim.lip_mass / n
    damping = 2.0 * sim.lip_damping_ratio * math.sqrt(k * (point_mass + sim.lip_armature))
    names, joints = [], []
    for i in range(n):
        angle = 2.0 * math.pi * i / n
        body = bellow.add_body(
            name=f"{prefix}_lip_point_{i}",
            pos=[cup.radius * math.cos(angle), cup.radius * math.sin(angle), cup.height - sim.lip_sphere_radius],
        )
        joints.append(f"{prefix}_lip_fold_{i}")
        body.add_joint(
            name=joints[-1], type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1], stiffness=k, damping=damping,
            range=[-cup.lip_travel, 0.0], limited=True, armature=sim.lip_armature,
            solref_limit=list(sim.contact_solref), solimp_limit=list(sim.contact_solimp) + [0.5, 2.0],
        )
        # condim 3: a ring of point contacts resists torsion through tangential friction at the
        # lever arm r, so per-point torsional friction (condim 6) would count it twice.
        names.append(f"{prefix}_lip_{i}")
        body.add_geom(name=names[-1], condim=3, mass=point_mass, friction=[cup.friction, 0.0, 0.0],
                      gap=sim.contact_gap, **lip_geom)
    # The vacuum. The pressure p inside the cup pulls the object toward the cup (p x effective area
    # on the object) and the tool toward the object (p x the bellows' cross-section, about the same
    # for a single bellows as wide as its lip): the bellows contracts and the lip is squeezed between
    # its end and the object. Two actuators with the same pressure state carry it. (1) MuJoCo's
    # adhesion acts along contact normals, so the bellows' end carries a small probe sphere on the
    # axis, behind where the lip can fold to, that touches nothing but objects (VACUUM_CONTYPE) and
    # whose contacts with them are never active (margin 0, gap: the cup's height): through them
    # V x p / p_max pulls the object's point nearest the axis and the bellows' end together (only
    # the part the axis meets, once the cup holds: `SuctionController._aim_vacuum`). (2) The
    # same force pulls the bellows' end back toward the tool along the bellows' slide.
    setback = cup.lip_travel + sim.probe_clearance + sim.probe_radius
    probe = bellow.add_body(name=f"{prefix}_vacuum", pos=[0, 0, cup.height - setback])
    probe.add_geom(
        name=f"{prefix}_vacuum_probe", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[sim.probe_radius, 0, 0],
        contype=VACUUM_CONTYPE, conaffinity=0, margin=0.0, gap=cup.height, condim=1, mass=1e-4, group=4,
        rgba=[0.9, 0.2, 0.2, 0.3],
    )
    spec.add_actuator(name=f"{prefix}_vacuum", target=probe.name, gainprm=[cup.vacuum_force] + [0] * 9, **vacuum)
    spec.add_actuator(
        name=f"{prefix}_vacuum_bellows", target=f"{prefix}_compress",
        gainprm=[-cup.vacuum_force] + [0] * 9, **{**vacuum, "trntype": mujoco.mjtTrn.mjTRN_JOINT},
    )
    return CupHandles(
        tip_site=f"{prefix}_tip", tool_body=f"{prefix}_tool",
        actuators=(f"{prefix}_vacuum", f"{prefix}_vacuum_bellows"), slide_joint=f"{prefix}_compress",
        lip_geoms=tuple(names), lip_joints=tuple(joints), bellow_body=f"{prefix}_bellow", cup=cup, sim=sim,
        tilt_joints=(f"{prefix}_tilt_x", f"{prefix}_tilt_y"),
    )


def expose_to_vacuum(body: mujoco.MjsBody) -> None:
    """Let the cup act on `body`: its colliding geoms accept the vacuum probe's contacts and join
    SURFACE_GROUP, the surface the leak test measures.

    The lip rests on the collision geometry; the leak test measures it and, behind it, the surface
    mesh, where a groove or hole the decomposition fills still leaks (`SuctionController.measure_lip`)."""
    for geom in body.geoms:
        if geom.contype or geom.conaffinity:
            geom.conaffinity = geom.conaffinity | VACUUM_CONTYPE
            geom.group = SURFACE_GROUP
