"""The pick scene: YuMi on a table, suction tool on the right flange, a receptacle bin at the
side, one object, and an overhead depth camera. Assembled with MjSpec from assets/yumi/yumi.xml,
the object's record and the shared cup configuration. `assemble_scene` builds the same workspace
around several objects and extra world geometry (the cluttered bin, `suctionbench.clutter.scene`)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import mujoco
import numpy as np

from suctionbench.config import CupConfig
from suctionbench.objects.build import ObjectRecord
from suctionbench.objects.liquid import Liquid
from suctionbench.objects.mjcf import add_object_body
from suctionbench.sensing.camera import CameraIntrinsics, add_camera
from suctionbench.sim.cup import (
    ENV_CONAFFINITY,
    ENV_CONTYPE,
    CupHandles,
    SimCupConfig,
    add_suction_tool,
    expose_to_vacuum,
)
from suctionbench.sim.yumi import RIGHT_FLANGE_SITE, load_yumi_spec

FLANGE_BODY = "yumi_link_7_r"
"""Body carrying the right flange site; the tool is attached there at the site's pose."""


@dataclass(frozen=True)
class SceneConfig:
    """Layout of the workspace (metres, world frame: z up, table top at z = 0, robot base at the
    origin facing +x)."""

    workspace_centre: tuple[float, float] = (0.45, -0.15)
    """Where objects are dropped and where the camera looks: in front of the right arm."""

    table_extents: tuple[float, float, float] = (0.9, 1.2, 0.04)
    """Table size; its top surface is the plane z = 0."""

    table_centre_x: float = 0.35
    """x of the table's centre (the robot base sits on it at the origin)."""

    bin_centre: tuple[float, float] = (0.25, -0.45)
    """Centre of the receptacle bin, at the right side of the workspace."""

    bin_size: tuple[float, float, float] = (0.20, 0.20, 0.06)
    """Inner width, depth and wall height of the bin."""

    bin_wall: float = 0.01
    """Wall and floor thickness of the bin (thick enough that a dropped object cannot tunnel)."""

    contact_solref: tuple[float, float] = (0.005, 1.0)
    """MuJoCo solref of table and bin contacts: stiffer than MuJoCo's default 20 ms, so objects
    dropped into the bin sink at most a few millimetres."""

    timestep: float = 0.002
    """Physics time step (s)."""

    friction: float = 0.6
    """Friction of table and bin surfaces."""


@dataclass
class Scene:
    """A compiled scene and the names needed to drive it."""

    model: mujoco.MjModel
    cup: CupHandles
    object_body: str
    camera: str
    intrinsics: CameraIntrinsics
    camera_pose: np.ndarray
    config: SceneConfig
    home_qpos: np.ndarray
    """Full-length qpos of the robot's home pose (other joints at their defaults)."""
    home_ctrl: np.ndarray
    """Full-length ctrl matching home_qpos (vacuum off)."""
    object_bodies: tuple[str, ...] = ()
    """Every object body of the scene, in the order they were given (one: `object_body`)."""
    liquids: dict[str, Liquid] = field(default_factory=dict)
    """The liquids of the object bodies that hold one, by body name (`sim.liquids`)."""

    def __post_init__(self) -> None:
        if not self.object_bodies:
            self.object_bodies = (self.object_body,)


def build_scene(
    record: ObjectRecord,
    cup: CupConfig,
    intrinsics: CameraIntrinsics,
    camera_pose: np.ndarray,
    *,
    sim_cup: SimCupConfig | None = None,
    config: SceneConfig | None = None,
) -> Scene:
    """Assemble and compile the scene for one object (placed later by the episode)."""
    return assemble_scene([record], cup, intrinsics, camera_pose, sim_cup=sim_cup, config=config)


def assemble_scene(
    records: Sequence[ObjectRecord],
    cup: CupConfig,
    intrinsics: CameraIntrinsics,
    camera_pose: np.ndarray,
    *,
    sim_cup: SimCupConfig | None = None,
    config: SceneConfig | None = None,
    names: Sequence[str] | None = None,
    add_world: Callable[[mujoco.MjsBody, dict], None] | None = None,
    floating: bool = False,
) -> Scene:
    """Assemble and compile the workspace with one body per record (named `names`, default
    "object" for one record, "object_00", "object_01", ... for several; all placed later by the
    episode), and whatever `add_world(worldbody, contact_options)` adds to the world (fixed
    geometry sharing the table's contact options)."""
    if not records:
        raise ValueError("assemble_scene: no object records")
    if names is None:
        names = ["object"] if len(records) == 1 else [f"object_{i:02d}" for i in range(len(records))]
    sim_cup = sim_cup or SimCupConfig()
    config = config or SceneConfig()
    spec = load_yumi_spec()
    home = _home_by_joint_name(spec)
    spec.option.timestep = config.timestep
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.noslip_iterations = 0
    world = spec.worldbody
    tx, ty, tz = config.table_extents
    env = {
        "contype": ENV_CONTYPE, "conaffinity": ENV_CONAFFINITY, "friction": [config.friction, 0.005, 0.0001],
        "solref": list(config.contact_solref),
    }
    world.add_geom(
        name="table", type=mujoco.mjtGeom.mjGEOM_BOX, size=[tx / 2, ty / 2, tz / 2],
        pos=[config.table_centre_x, 0.0, -tz / 2], rgba=[0.55, 0.45, 0.35, 1], **env,
    )
    _add_bin(world, config, env)
    if add_world is not None:
        add_world(world, env)
    cx, cy = config.workspace_centre
    for i, (record, name) in enumerate(zip(records, names, strict=True)):
        body = add_object_body(spec, record, name=name, pos=(cx, cy, 0.3 + 0.3 * i))
        body.gravcomp = 1.0 if floating else 0.0
        expose_to_vacuum(body)
    flange = spec.site(RIGHT_FLANGE_SITE)
    handles = add_suction_tool(
        spec.body(FLANGE_BODY), spec, cup, sim_cup, prefix="cup", pos=list(flange.pos), quat=list(flange.quat)
    )
    add_camera(spec, "overhead", camera_pose, intrinsics)
    world.add_light(
        name="overhead_light", pos=[0.4, -0.1, 1.5], dir=[0, 0, -1], type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL
    )
    model = spec.compile()
    home_qpos, home_ctrl = model.qpos0.copy(), np.zeros(model.nu)
    for joint, value in home.items():
        home_qpos[model.jnt_qposadr[model.joint(joint).id]] = value
        home_ctrl[model.actuator(joint).id] = value
    return Scene(
        model=model, cup=handles, object_body=names[0], camera="overhead", intrinsics=intrinsics,
        camera_pose=np.asarray(camera_pose, dtype=float), config=config, home_qpos=home_qpos, home_ctrl=home_ctrl,
        object_bodies=tuple(names),
        liquids={name: liquid for record, name in zip(records, names, strict=True)
                 if (liquid := Liquid.of(record)) is not None},
    )


def _home_by_joint_name(spec: mujoco.MjSpec) -> dict[str, float]:
    """The robot's "home" keyframe as {joint name: angle}, then the keyframe is removed.

    Keyframes store qpos positionally; adding the cup's joints inside the arm's kinematic tree
    shifts every later joint's address, so the keyframe would put arm angles on the bellow.
    """
    key = spec.key("home")
    joints = [j for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_HINGE]
    home = {j.name: float(v) for j, v in zip(joints, key.qpos, strict=True)}
    spec.delete(key)
    return home


def _add_bin(world: mujoco.MjsBody, config: SceneConfig, env: dict) -> None:
    """The receptacle: an open box of five thin walls standing on the table."""
    add_open_box(world, "bin", config.bin_centre, config.bin_size, config.bin_wall, env, rgba=(0.2, 0.5, 0.3, 1))


def add_open_box(world: mujoco.MjsBody, prefix: str, centre: Sequence[float], size: Sequence[float], wall: float,
                 env: dict, rgba: Sequence[float]) -> None:
    """An open box standing on the table: a floor of thickness `wall` (inner floor at z = wall)
    and four walls of that thickness around the inner `size` (width, depth, wall height), geoms
    named PREFIX_floor, PREFIX_wall_xp, _xn, _yp, _yn."""
    (bx, by), (w, d, h), t = centre, size, wall
    walls = {
        f"{prefix}_floor": ([w / 2 + t, d / 2 + t, t / 2], [bx, by, t / 2]),
        f"{prefix}_wall_xp": ([t / 2, d / 2 + t, h / 2], [bx + w / 2 + t / 2, by, h / 2]),
        f"{prefix}_wall_xn": ([t / 2, d / 2 + t, h / 2], [bx - w / 2 - t / 2, by, h / 2]),
        f"{prefix}_wall_yp": ([w / 2, t / 2, h / 2], [bx, by + d / 2 + t / 2, h / 2]),
        f"{prefix}_wall_yn": ([w / 2, t / 2, h / 2], [bx, by - d / 2 - t / 2, h / 2]),
    }
    for name, (half, pos) in walls.items():
        world.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX, size=half, pos=pos, rgba=list(rgba), **env)
