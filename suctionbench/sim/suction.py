"""The simulated cup's controller (docs/physics.md, "Simulated cup"): the leak test, the ejector's
vacuum and the seal, stepped with the simulation.

Vacuum. `SuctionController` runs a leak test while the vacuum is commanded and lip points touch an
object: it measures the gap between the lip's edge and that object's surface at `leak_samples`
places round the lip circle (`mujoco.mj_multiRay` against the object's collision geometry, where
the lip rests, from the distance at which a pressed lip rests, the contact margin; and a second
call against its surface mesh, where the air leaks past a lip that can fold only so far toward it:
`measure_lip`), and integrates the leak area A = sum max(gap - seal_gap, 0) x arc, the seal_gap allowance
only where the lip is pressed on (folded: an unfolded, lifted lip carries no pressure and closes
nothing). The ejector holds the vacuum p(A) where its flow curve meets the leak's orifice flow
(`suctionbench.vacuum.equilibrium_vacuum`); the cup's pressure follows p(A) with a first-order time
constant (the cup and hose volume evacuated by the ejector's flow), as MuJoCo actuator state. The
pressure pulls the object toward the cup with V x p / p_max (V = p_max x effective area) and the
tool toward the object, so the bellows contracts and the lip is squeezed between its end and the
object: a MuJoCo `adhesion` actuator (gain V, ctrl = p / p_max) on a probe sphere on the bellows'
axis whose only contacts are inactive ones with the object's part that the axis meets (the
pressure's resultant acts along the axis, however the object is decomposed: `_aim_vacuum`), and
the same force along the bellows' slide (`suctionbench.sim.cup.add_suction_tool` builds both). The
lip's contacts carry the rest: a torque about the lip is resisted only until one side's contact
force reaches zero and the lip opens there (the ring-pressure peel limit r (V - m g) / 2 emerges
from the contact forces; it is not coded). The seal breaks when the cup's vacuum falls below the
ejector's part-present switch (`CupConfig.vacuum_switch_fraction`, i.e. a leak beyond
`CupConfig.leak_threshold_area`): no hysteresis, no gap allowance beyond `seal_gap` (and none at
all where the lip has lifted).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from suctionbench.objects.mjcf import VISUAL_GROUP
from suctionbench.sim.cup import SURFACE_GROUP, VACUUM_CONTYPE, CupHandles
from suctionbench.vacuum import equilibrium_vacuum

_COS_WALL = math.cos(math.radians(45.0))
"""Surfaces steeper than 45 deg to the lip plane are walls, not where a lip rests (`lip_gaps`)."""


class SuctionController:
    """Drives the cup's vacuum each step from its seal state (the compliant cup's leak test, or the
    rigid reference's contact gaps). `commanded`: the vacuum valve; `sealed`: the object body the
    cup holds by vacuum (-1: none)."""

    def __init__(self, model: mujoco.MjModel, handles: CupHandles):
        self.model = model
        self.handles = handles
        self.cup, self.sim = handles.cup, handles.sim
        self.lip_geoms = np.array([model.geom(n).id for n in handles.lip_geoms])
        self._lip_slot = np.full(model.ngeom, -1)
        """Per geom: its index among the lip spheres, -1 for any other geom."""
        self._lip_slot[self.lip_geoms] = np.arange(len(self.lip_geoms))
        self.actuators = np.array([model.actuator(a).id for a in handles.actuators])
        self.actuator = int(self.actuators[0])
        self._act = int(model.actuator_actadr[self.actuator])
        """Address of the first actuator's state: the cup's vacuum as a fraction of p_max."""
        self.slide_qpos = model.jnt_qposadr[model.joint(handles.slide_joint).id]
        self.lip_qpos = np.array([model.jnt_qposadr[model.joint(j).id] for j in handles.lip_joints], dtype=int)
        self.bellow = model.body(handles.bellow_body).id
        self._tilt_qpos = np.array([model.jnt_qposadr[model.joint(j).id] for j in handles.tilt_joints], dtype=int)
        self._tilt_dof = np.array([model.jnt_dofadr[model.joint(j).id] for j in handles.tilt_joints], dtype=int)
        self._stop_at = self.cup.approach_tolerance
        self._stop_rate, self._stop_damping = self.cup.stop_stiffness, self.sim.stop_damping_for(self.cup)
        self.commanded = False
        self.sealed = -1
        self.candidate = -1
        """The object body the lip touches at the last leak test (-1: none)."""
        self.leak_area = math.inf
        """Leak area (m^2) at the last leak test (inf: no object under the lip)."""
        self.leak_tests = 0
        self._next_test = -math.inf
        self._switch = self.cup.vacuum_switch_fraction
        n, k = len(self.lip_geoms), self.sim.leak_samples
        self._phi = 2.0 * math.pi * np.arange(k) / k
        self._ring = np.stack([self.cup.radius * np.cos(self._phi), self.cup.radius * np.sin(self._phi)], axis=1)
        self._arc = 2.0 * math.pi * self.cup.radius / k
        self._group = np.zeros(6, dtype=np.uint8)
        self._group[SURFACE_GROUP] = 1
        self._ray_geom = np.zeros(k, dtype=np.int32)
        self._ray_dist = np.zeros(k)
        self._ray_normal = np.zeros((k, 3))
        self._axis_geom = np.zeros(1, dtype=np.int32)
        self._receiver = -1
        """The geom the vacuum probe alone may touch (`_aim_vacuum`; -1: every exposed part)."""
        self._muted = np.zeros(0, dtype=int)
        """Geoms whose vacuum bit `_aim_vacuum` has taken for `_receiver` (given back by `_unmute`)."""
        self._fold_weights = _periodic_interpolation(self._phi, n) if n else np.zeros((k, 0))
        """(k, n): the lip's fold at each leak-test place, linear between its points round the circle."""
        self._plane = np.column_stack([np.ones(k), np.cos(self._phi), np.sin(self._phi)])
        """(k, 3): the lip plane's mean and tilt at the leak test's places (`measure_lip`)."""
        self._visual_group = np.zeros(6, dtype=np.uint8)
        self._visual_group[VISUAL_GROUP] = 1
        self._true_geom = np.zeros(k, dtype=np.int32)
        self._true_dist = np.zeros(k)
        self._true_normal = np.zeros((k, 3))
        self._surface_geom: dict[int, int] = {}
        """Per object body: its surface-mesh geom (-1: none, or convex: its collision geometry is its surface)."""

    # -- read-outs --------------------------------------------------------------------------------
    def compression(self, data: mujoco.MjData) -> float:
        """How far (m) the bellows is compressed."""
        return -float(data.qpos[self.slide_qpos])

    def axis_offset(self, data: mujoco.MjData, point: np.ndarray) -> float:
        """Distance (m) of `point` from the bellows' axis: how far beside a planned grasp point the
        cup stands (measured where the lip lands: the landing offset of eval/episode)."""
        axis = data.xmat[self.bellow].reshape(3, 3)[:, 2]
        v = np.asarray(point, dtype=float) - data.xpos[self.bellow]
        return float(np.linalg.norm(v - (v @ axis) * axis))

    def vacuum(self, data: mujoco.MjData) -> float:
        """The cup's vacuum as a fraction of the ejector's p_max (the actuators' filtered state)."""
        return float(data.act[self._act])

    def vacuum_on(self, data: mujoco.MjData) -> bool:
        """Whether the vacuum pulls (valve open and the cup not vented)."""
        return bool(self.commanded and data.ctrl[self.actuator] > 0.0)

    def touching(self, data: mujoco.MjData, gap: float | None = None) -> np.ndarray:
        """(n_lip, nbody) bool: which lip point has a contact within `gap` (default: any contact
        MuJoCo reports, i.e. within margin + gap) with which body."""
        n = data.ncon
        touching = np.zeros((len(self.lip_geoms), self.model.nbody), dtype=bool)
        if n == 0 or not len(self.lip_geoms):
            return touching
        geoms = data.contact.geom[:n]
        near = np.ones(n, dtype=bool) if gap is None else data.contact.dist[:n] <= gap
        for mine, other in ((0, 1), (1, 0)):
            slot = self._lip_slot[geoms[:, mine]]
            hit = near & (slot >= 0)
            touching[slot[hit], self.model.geom_bodyid[geoms[hit, other]]] = True
        return touching

    # -- the seal ---------------------------------------------------------------------------------
    def update(self, data: mujoco.MjData) -> int:
        """Drive the vacuum (and the bellows' stop spring) for this step; returns the body sealed
        by vacuum (-1 if none)."""
        if not self.sim.compliant:
            return self._update_rigid(data)
        self.apply_stop(data)
        if not self.commanded:
            data.ctrl[self.actuators] = 0.0
            self.sealed, self.candidate, self._next_test = -1, -1, -math.inf
            self._unmute()
            return -1
        if data.time >= self._next_test:
            self._next_test = data.time + self.sim.leak_test_interval - 1e-9
            self.leak_test(data)
            target = 0.0 if self.candidate < 0 else float(equilibrium_vacuum(self.leak_area, self.cup))
            data.ctrl[self.actuators] = target / self.cup.vacuum_pressure
        sealed = self.candidate >= 0 and data.act[self._act] >= self._switch
        self.sealed = self.candidate if sealed else -1
        return self.sealed

    def release(self, data: mujoco.MjData) -> None:
        """Vent and hold nothing, with no stop force left on the bellows: the cup's state after a
        reset or a retract (its next `update` drives it from there)."""
        self.commanded, self.sealed, self.candidate, self._next_test = False, -1, -1, -math.inf
        self._unmute()
        if len(self._tilt_dof):
            data.qfrc_applied[self._tilt_dof] = 0.0

    def bellows_tilt(self, data: mujoco.MjData) -> float:
        """The bellows' tilt (rad): the size of its two hinges' tilt vector."""
        tilt = data.qpos[self._tilt_qpos]
        return math.hypot(tilt[0], tilt[1]) if len(tilt) else 0.0

    def apply_stop(self, data: mujoco.MjData) -> None:
        """The bellows' stop as a spring (`CupConfig.stop_stiffness`, damped by the silicone's
        loss) on the tilt beyond `approach_tolerance`, round in every azimuth (the tilt vector of
        the two hinges): set as the hinges' applied force, zero inside the stop."""
        size = self.bellows_tilt(data)
        if size <= self._stop_at:
            data.qfrc_applied[self._tilt_dof] = 0.0
            return
        axis = data.qpos[self._tilt_qpos] / size
        speed = float(data.qvel[self._tilt_dof] @ axis)
        moment = self._stop_rate * (size - self._stop_at) + self._stop_damping * speed
        data.qfrc_applied[self._tilt_dof] = -moment * axis

    def leak_test(self, data: mujoco.MjData) -> float:
        """Measure the leak under the lip: sets `candidate` (the object body most lip points touch)
        and `leak_area` (m^2); returns the leak area (inf when no object is under the lip)."""
        self.leak_tests += 1
        touching = self.touching(data)
        touching[:, 0] = False  # the world body (table, bin walls): not an object we can lift
        counts = touching.sum(axis=0)
        if not counts.any():
            self.candidate, self.leak_area = -1, math.inf
            self._unmute()
            return self.leak_area
        self.candidate = int(np.argmax(counts))
        self.leak_area = float(self._leak_area(data, self.candidate))
        self._aim_vacuum(data)
        return self.leak_area

    def _aim_vacuum(self, data: mujoco.MjData) -> None:
        """Let the vacuum probe touch only the candidate's part that the cup's axis meets.

        Uniform pressure on any surface bounded by the planar lip loop has the resultant p x A along
        the loop's normal through the loop's centre (close the surface with the loop's disc: the
        pressure on a closed surface sums to no force and no moment, and the disc's resultant is
        p A n through its centroid). MuJoCo's adhesion splits its force equally among the probe's
        contacts along their normals, so an object whose convex decomposition puts several parts
        near the probe (a mug's curved side, a toy's body) got a share of the pull tilted up to
        65 deg off the axis: 4.7 N along it where 6.8 N were due (eval/README.md). The part the axis
        meets is where that resultant acts; the others lose the vacuum bit while the cup holds it
        (model state, restored by `release`). Where the axis meets no part of the candidate (a hole
        under the cup's centre), every part keeps it."""
        receiver = -1
        if self.candidate >= 0:
            rot, apex = self._apex(data)
            mujoco.mj_ray(self.model, data, apex, rot[:, 2].copy(), self._group, 0, -1, self._axis_geom)
            hit = int(self._axis_geom[0])
            if hit >= 0 and self.model.geom_bodyid[hit] == self.candidate:
                receiver = hit
        if receiver == self._receiver:  # the usual case while the cup holds: nothing to change
            return
        self._unmute()
        if receiver < 0:
            return
        affinity = self.model.geom_conaffinity
        self._muted = np.flatnonzero(affinity & VACUUM_CONTYPE)
        self._muted = self._muted[self._muted != receiver]
        affinity[self._muted] &= ~VACUUM_CONTYPE
        self._receiver = receiver

    def _unmute(self) -> None:
        """Give the vacuum bit back to every part `_aim_vacuum` took it from."""
        if self._receiver >= 0:
            self.model.geom_conaffinity[self._muted] |= VACUUM_CONTYPE
            self._receiver, self._muted = -1, self._muted[:0]

    def _apex(self, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """The bellows' rotation and the leak test's ray apex on its axis, `ray_apex_height` behind
        the lip plane."""
        rot = data.xmat[self.bellow].reshape(3, 3)
        return rot, data.xpos[self.bellow] + (self.cup.height - self.sim.ray_apex_height) * rot[:, 2]

    def lip_folds(self, data: mujoco.MjData) -> np.ndarray:
        """The lip's fold (m, negative: pressed toward the cup) at the leak test's places round the
        lip circle, linear between its points."""
        return self._fold_weights @ data.qpos[self.lip_qpos]

    def lip_gaps(self, data: mujoco.MjData, body: int, folds: np.ndarray | None = None) -> np.ndarray:
        """Gap (m) between the lip's edge and `body`'s convex parts (where the lip rests) at the leak
        test's places round the lip circle: `measure_lip`'s first result."""
        return self.measure_lip(data, body, folds, surface=False)[0]

    def measure_lip(
        self, data: mujoco.MjData, body: int, folds: np.ndarray | None = None, *, surface: bool = True
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """(gaps, offsets) at the leak test's places round the lip circle, both along the cup axis
        (m). `folds`: `lip_folds(data)`, if the caller has it; `surface` False skips the offsets.

        gaps: between the lip's edge and `body`'s convex parts, from where a pressed lip rests;
        `cup.radius` where they are missing (over an edge, another body in the way). A lip sphere
        (radius rho) pressed on a surface sloping by alpha to the lip plane sits with its centre
        rho + margin from the surface, so its lowest point is (rho + margin) / cos(alpha) - rho
        above the surface along the axis (margin on a parallel face). That is the rounded sphere's
        geometry, not a gap of the thin lip it stands for. Slopes beyond 45 deg are walls (a
        groove's side, an object's side face), not surfaces a lip rests on: the correction stops
        growing there.

        offsets: how much further `body`'s real surface (its surface mesh) lies than the parts,
        relative to the lip's plane; nan where the ray that meets the parts finds no real surface
        (a hole, a tooth gap the parts span); zeros for a body without a surface mesh (a primitive,
        whose collision geometry is its surface). MuJoCo collides with convex parts, which span an
        object's concavities: a soap dish's drain ribs, a gear's tooth gaps, the trough between a
        toy's wheels (up to 5 mm under the lip in the agreement trials). A real lip follows the
        real surface as far as it can fold; the bellows' plane settles where the lip's springs
        have no net force or moment (the spring ring of docs/physics.md, "Lip preload"), so an
        offset's mean and first harmonic move the plane and only the rest reaches the lip
        (`_leak_area`). The real surface is a second ray cast from the same apex through the same
        places, against the surface mesh (MuJoCo intersects a mesh geom's triangles in ray casts,
        not its hull)."""
        cup, sim, k = self.cup, self.sim, len(self._phi)
        rot, apex = self._apex(data)
        axis = rot[:, 2]
        # In the bellows' frame a lip place is (r cos phi, r sin phi, h + fold(phi)), the lip's edge
        # between its points following their folds (linear interpolation round the circle), and
        # the apex is (0, 0, h - H): the ray to a place is (r cos phi, r sin phi, H + fold).
        folds = self.lip_folds(data) if folds is None else folds
        depth = sim.ray_apex_height + folds
        length = np.sqrt(cup.radius**2 + depth * depth)
        local = np.column_stack([self._ring, depth]) / length[:, None]
        rays = (local @ rot.T).ravel()
        cutoff = float(length.max() + cup.radius)
        mujoco.mj_multiRay(self.model, data, apex, rays, self._group, 0, -1, self._ray_geom,
                           self._ray_dist, self._ray_normal.ravel(), k, cutoff)
        parts = (self._ray_geom >= 0) & (self.model.geom_bodyid[self._ray_geom] == body)
        beyond = (self._ray_dist - length) * local[:, 2]  # axial distance from the lip's edge
        cos_slope = np.maximum(np.abs(self._ray_normal @ axis), _COS_WALL)
        rest = (sim.lip_sphere_radius + sim.contact_margin) / cos_slope - sim.lip_sphere_radius
        gaps = np.clip(np.where(parts, beyond - rest, cup.radius), 0.0, cup.radius)
        if not surface:
            return gaps, None
        mesh = self._surface_mesh(body)
        if mesh < 0:
            return gaps, np.zeros(k)
        mujoco.mj_multiRay(self.model, data, apex, rays, self._visual_group, 0, -1, self._true_geom,
                           self._true_dist, self._true_normal.ravel(), k, cutoff)
        real = self._true_geom == mesh
        both = parts & real
        offsets = np.where(both, (self._true_dist - self._ray_dist) * local[:, 2], 0.0)
        # The plane is held by the springs that press (folded places); where fewer than three do,
        # by every place that meets both surfaces.
        carry = both & (folds < 0.0)
        carry = carry if carry.sum() >= 3 else both
        if carry.sum() >= 3:
            offsets -= self._plane @ np.linalg.lstsq(self._plane[carry], offsets[carry], rcond=None)[0]
        return gaps, np.where(parts & ~real, np.nan, offsets)

    def _surface_mesh(self, body: int) -> int:
        """`body`'s surface-mesh geom (`objects.mjcf.add_surface_mesh`) where its convex parts can
        span a concavity; -1 where they cannot: no surface mesh (a primitive is its own surface) or
        a convex one (its parts are the surface), whose second ray cast would measure nothing."""
        if body not in self._surface_geom:
            geom = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, f"{self.model.body(body).name}_visual")
            self._surface_geom[body] = geom if geom >= 0 and not _convex_mesh(self.model, geom) else -1
        return self._surface_geom[body]

    def _leak_area(self, data: mujoco.MjData, body: int) -> float:
        """Leak area (m^2) under the lip: the gap beyond what the lip's edge closes by itself, which
        it does only where the lip is pressed on (folded, q < 0): a lip that has unfolded to its
        free shape and lifted carries no pressure, and an unpressed edge seals nothing (the
        ring-pressure condition p >= 0; Hudoklin et al.'s validated continuous cup model seals only
        while the lip pressure stays compressive). Without this, a lifting side kept its seal for
        another seal_gap and the simulated cup held 1.17x the ring limit's moment (now 1.01x)."""
        folds = self.lip_folds(data)
        gaps, offsets = self.measure_lip(data, body, folds)
        # Where the real surface lies further than the parts (offset > 0), the lip unfolds toward
        # it by as much as it is folded (folds <= 0) and the rest opens the gap; no real surface at
        # all: the whole arc is open. Offsets below the plane close nothing: the parts enclose the
        # object, so the real surface is never nearer than they are, only the plane's shift makes
        # it look so, and that shift is exact only while the whole lip presses (a lifting side's
        # gap is a peel the parts measure as it is).
        missing = np.isnan(offsets)
        further = np.maximum(np.where(missing, 0.0, offsets), 0.0)
        pressed = (folds + further < 0.0) & ~missing
        gaps = np.where(missing, self.cup.radius, gaps + np.maximum(folds + further, 0.0))
        return float(np.sum(np.maximum(gaps - np.where(pressed, self.cup.seal_gap, 0.0), 0.0)) * self._arc)

    # -- the rigid reference ------------------------------------------------------------------------
    def sealed_body(self, data: mujoco.MjData, gap: float | None = None) -> int:
        """Rigid reference: the body that every lip sphere touches within `gap` (default its seal
        gap), else -1."""
        touching = self.touching(data, self.sim.rigid_seal_gap if gap is None else gap)
        common = touching.all(axis=0)
        common[0] = False
        return int(np.argmax(common)) if common.any() else -1

    def _update_rigid(self, data: mujoco.MjData) -> int:
        """Rigid reference: a seal forms within rigid_seal_gap and, while the vacuum is commanded,
        holds on the same body within rigid_release_gap (hysteresis); once lost, the vacuum vents."""
        if self.commanded and self.sealed >= 0 and self.sealed_body(data, self.sim.rigid_release_gap) == self.sealed:
            body = self.sealed
        else:
            body = self.sealed_body(data)
        self.sealed = body if self.commanded else -1
        data.ctrl[self.actuators] = 1.0 if (self.commanded and body >= 0) else 0.0
        return body


def _convex_mesh(model: mujoco.MjModel, geom: int) -> bool:
    """Whether mesh geom `geom`'s triangles bound a convex solid (trimesh's test, with its tolerance)."""
    import trimesh

    mesh = int(model.geom_dataid[geom])
    vert, nvert = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
    face, nface = int(model.mesh_faceadr[mesh]), int(model.mesh_facenum[mesh])
    return bool(trimesh.Trimesh(model.mesh_vert[vert:vert + nvert], model.mesh_face[face:face + nface],
                                process=False).is_convex)


def _periodic_interpolation(phi: np.ndarray, n: int) -> np.ndarray:
    """(len(phi), n) weights of linear interpolation at angles `phi` between n values at angles
    2 pi i / n, periodic."""
    position = np.asarray(phi) / (2.0 * math.pi) * n
    lower = np.floor(position).astype(int) % n
    frac = position - np.floor(position)
    weights = np.zeros((len(position), n))
    weights[np.arange(len(position)), lower] += 1.0 - frac
    weights[np.arange(len(position)), (lower + 1) % n] += frac
    return weights
