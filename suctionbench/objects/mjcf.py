"""Objects as MuJoCo bodies (MjSpec): one collision geom per convex part, a visual mesh, and the
inertial properties from object.toml. Meshes are passed as vertex/face arrays, so the model needs
no mesh directory."""

from __future__ import annotations

import mujoco
import numpy as np

from suctionbench.objects.build import ObjectRecord

OBJECT_CONTYPE, OBJECT_CONAFFINITY = 1, 7
"""Collision bits of objects: collide with the environment, the robot and the cup (sim/cup.py)."""

TORSIONAL_FRICTION = 0.005
"""Torsional friction (m) of object geoms, used by condim 6 contacts with the suction cup."""

ROLLING_FRICTION = 0.0001
"""Rolling friction (m) of object geoms."""

VISUAL_GROUP = 2
"""Geom group of the objects' surface meshes (rendered; no contacts): the object's real surface,
which its convex parts only approximate (`suctionbench.sim.suction`'s leak test measures both)."""

CONTACT_SOLREF = (0.005, 1.0)
"""MuJoCo solref of object contacts (5 ms, critically damped): rigid objects, stiffer than the
default 20 ms so that drops do not sink objects into each other."""


def add_object_body(
    spec: mujoco.MjSpec,
    record: ObjectRecord,
    *,
    name: str = "object",
    pos=(0.0, 0.0, 0.0),
    quat=(1.0, 0.0, 0.0, 0.0),
    free: bool = True,
) -> mujoco.MjsBody:
    """Add `record` as a body named `name` under the world body of `spec`; returns the body. Its
    collision geoms are its convex parts, or its convex hull when it has none."""
    body = spec.worldbody.add_body(name=name, pos=list(pos), quat=list(quat))
    if free:
        body.add_freejoint(name=f"{name}_free")
    body.explicitinertial = True
    body.mass = record.mass
    body.ipos = list(record.com)
    body.fullinertia = [record.inertia[0][0], record.inertia[1][1], record.inertia[2][2],
                        record.inertia[0][1], record.inertia[0][2], record.inertia[1][2]]
    friction = [record.friction, TORSIONAL_FRICTION, ROLLING_FRICTION]
    # An object built without convex parts (the training corpus: rendered only, never decomposed)
    # collides as its surface mesh, which MuJoCo treats as its convex hull.
    for i, part in enumerate(record.part_meshes() or [record.mesh()]):
        mesh = spec.add_mesh(name=f"{name}_part_{i:03d}")
        mesh.uservert = np.asarray(part.vertices, dtype=np.float32).ravel().tolist()
        mesh.userface = np.asarray(part.faces, dtype=np.int32).ravel().tolist()
        body.add_geom(
            name=f"{name}_collision_{i:03d}", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh.name,
            friction=friction, condim=6, group=3, density=0.0, solref=list(CONTACT_SOLREF),
            contype=OBJECT_CONTYPE, conaffinity=OBJECT_CONAFFINITY,
        )
    add_surface_mesh(spec, body, name, record.mesh())
    return body


def add_surface_mesh(spec: mujoco.MjSpec, body: mujoco.MjsBody, name: str, mesh) -> mujoco.MjsGeom:
    """The object's surface mesh (a trimesh) as geom `{name}_visual` of `body`: rendered, no
    contacts, in VISUAL_GROUP, where the simulated cup's leak test finds the real surface."""
    surface = spec.add_mesh(name=f"{name}_visual")
    surface.uservert = np.asarray(mesh.vertices, dtype=np.float32).ravel().tolist()
    surface.userface = np.asarray(mesh.faces, dtype=np.int32).ravel().tolist()
    return body.add_geom(
        name=f"{name}_visual", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=surface.name,
        contype=0, conaffinity=0, group=VISUAL_GROUP, density=0.0, rgba=[0.8, 0.55, 0.3, 1.0],
    )


def rest_on_plane(record: ObjectRecord, seconds: float = 2.0) -> dict[str, float]:
    """Drop-free check: place the object in its most probable stable pose on a plane and simulate.

    Returns the displacement (m) and rotation (rad) of the object after `seconds`, and whether the
    state stayed finite.
    """
    spec = mujoco.MjSpec()
    spec.option.timestep = 0.002
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[1, 1, 0.1])
    pose = record.most_probable_pose()
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, pose[:3, :3].ravel())
    add_object_body(spec, record, pos=pose[:3, 3] + [0, 0, 0.0005], quat=quat)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    start_pos, start_quat = data.qpos[:3].copy(), data.qpos[3:7].copy()
    mujoco.mj_step(model, data, nstep=int(seconds / model.opt.timestep))
    dq = np.zeros(3)
    mujoco.mju_subQuat(dq, data.qpos[3:7], start_quat)
    return {
        "displacement": float(np.linalg.norm(data.qpos[:3] - start_pos)),
        "rotation": float(np.linalg.norm(dq)),
        "finite": bool(np.all(np.isfinite(data.qpos))),
    }
