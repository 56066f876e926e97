"""Picking from a cluttered bin: the objects dropped in one by one and settled, then one pick
attempt after another, each the single-object episode's motion (`sim.episode.PickEpisode`) on
whichever object the cup seals on.

Between attempts
----------------
An object carried to the receptacle is taken out of the scene (parked: out of view, without
contacts, held against gravity), as a conveyor under a real receptacle would take it, so the
receptacle never fills. An object that has left the pick bin any other way (dropped between the
bins, pushed or dragged over the rim) is out of reach: it is parked too, and counts as not
cleared. After every attempt the vacuum vents, the arm returns to its waiting configuration (set
directly, standing for a retract that does not touch the pile, as the gymnasium environment
does) and the pile settles where it is: objects a failed grasp disturbed stay where they land.

Failure reasons beyond the single-object episode's (`CLUTTER_FAILURES`)
-----------------------------------------------------------------------
- "collision_bin": the cup touched a wall of the pick bin on the way in (the arm's links
  touching anything is the episode's "collision", as before).
- "collision_neighbour": the cup touched an object other than the one under the grasp point on
  the way in, before the bellows met its target, and then did not seal. (Brushing a neighbour is
  common in a pile and harmless when the cup still seals; the arm stops only at a wall.)
- "two_lifted": another object left the bin from the moment the held one was lifted (carried
  along, stuck to it or dragged over the rim), whether or not it reached the receptacle.
- "dragged_out": the target left the bin without being carried to the receptacle while it was
  not held (pushed or dragged over the rim); out of reach from then on.
- "missed_receptacle": the object was held to the end and released, but did not come to rest in
  the receptacle.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from suctionbench.clutter.scene import PICK_BIN, PickBinConfig
from suctionbench.config import STANDARD_GRAVITY
from suctionbench.sim.episode import PickEpisode, _Failure, _random_quat, _Unstable
from suctionbench.sim.episode_config import FAILURES, EpisodeConfig, EpisodeResult
from suctionbench.sim.scene import Scene

CLUTTER_FAILURES = FAILURES + ("collision_bin", "collision_neighbour", "two_lifted", "dragged_out", "missed_receptacle")
"""Every failure reason of an attempt in clutter (see the module docstring)."""

PARK_SPACING = 0.5
"""Distance (m) between parked objects, far behind the robot and out of every camera's view."""


@dataclass(frozen=True)
class BinEpisodeConfig:
    """How the bin is filled and how the pile is watched between attempts."""

    drop_height: float = 0.03
    """Each object starts this far (m) above the top of the pile so far, at its lowest possible point
    (its bounding sphere), from a uniformly random orientation."""

    drop_margin: float = 0.03
    """Drops start this far (m) inside the walls."""

    retries: int = 2
    """An object that bounced out of the bin while the bin was filled is dropped again, at most this
    many times, nearer the centre; after that it is left out of the scene (recorded as spilled)."""

    carried_height: float = 0.03
    """The lift raises the held object's lowest point this far (m) above the rim and the pile."""

    settle_time: float = 6.0
    """Longest wait (s) for the pile to come to rest after a drop or an attempt. A pile's own
    limit, apart from the single object's `EpisodeConfig.settle_time`: objects leaning on each
    other creep in MuJoCo's soft contacts and may never pass the rest test, so every wait that
    reaches this limit costs its full length and moves the pile on."""


@dataclass
class AttemptResult:
    """One pick attempt in the bin."""

    episode: EpisodeResult
    """The motion's outcome (its `failure` rewritten with the clutter reasons)."""

    target: str | None
    """The object body under the grasp point when the attempt started (None: none was hit)."""

    held: str | None
    """The object body the cup sealed on (None: no seal)."""

    transported: list[str] = field(default_factory=list)
    """Objects that reached the receptacle (and were taken out of the scene)."""

    lost: list[str] = field(default_factory=list)
    """Objects that left the bin any other way (out of reach, taken out of the scene)."""

    @property
    def success(self) -> bool:
        return self.episode.success

    @property
    def failure(self) -> str | None:
        return self.episode.failure


class BinEpisode(PickEpisode):
    """Fills the pick bin and runs pick attempts in it; one instance per scene (reusable across
    resets, which refill the bin)."""

    def __init__(self, scene: Scene, bin_config: PickBinConfig | None = None,
                 config: EpisodeConfig | None = None, bin_episode: BinEpisodeConfig | None = None):
        super().__init__(scene, config)
        self.bin = bin_config or PickBinConfig()
        self.bin_episode = bin_episode or BinEpisodeConfig()
        m = self.model
        self.bodies = [m.body(name).id for name in scene.object_bodies]
        self.names = {b: m.body(b).name for b in self.bodies}
        self.present: list[int] = []
        """Object bodies in the pick bin now, in drop order."""
        self.spilled: list[str] = []
        """Objects that would not stay in the bin while it was filled (not part of this scene)."""
        self.unsettled = 0
        """How often the pile was still moving at the end of `BinEpisodeConfig.settle_time` (after a
        drop or an attempt): objects leaning on each other creep by up to about 1 mm/s in MuJoCo's
        soft contacts; the next attempt goes ahead on the pile as it is."""
        self._geoms = {b: np.flatnonzero((m.geom_bodyid == b) & ((m.geom_contype != 0) | (m.geom_conaffinity != 0)))
                       for b in self.bodies}
        self._contact_bits = {b: (m.geom_contype[g].copy(), m.geom_conaffinity[g].copy())
                              for b, g in self._geoms.items()}
        names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or "" for g in range(m.ngeom)]
        self._is_wall = np.array([n.startswith(f"{PICK_BIN}_wall") for n in names], dtype=bool)
        tool = m.body(scene.cup.tool_body).id
        self._is_cup = np.array([_descends_from(m, m.geom_bodyid[g], tool) for g in range(m.ngeom)], dtype=bool)
        self._object_of_geom = np.full(m.ngeom, -1)
        for b, geoms in self._geoms.items():
            self._object_of_geom[geoms] = b
        self._surface_group = np.zeros(6, dtype=np.uint8)
        self._surface_group[2] = 1  # the objects' surface meshes (objects.mjcf: visual geoms, group 2)

    # -- filling the bin --------------------------------------------------------------------------
    def reset(self, rng: np.random.Generator, *, stable_pose: np.ndarray | None = None) -> None:
        """Home the arm, take every object out, and drop them into the bin one after another (drop
        order: the scene's), each from a random orientation over a random point of the bin, letting
        the pile settle after each drop."""
        if stable_pose is not None:
            raise ValueError("a bin is filled by drops; stable poses are for single-object scenes")
        self._home()
        self.present, self.spilled, self.placement_error, self.unsettled = [], [], None, 0
        for b in self.bodies:
            self._park(b)
        mujoco.mj_forward(self.model, self.data)
        q_hold = self.data.qpos[self.arm_qpos].copy()
        c = self.bin_episode
        for b in self.bodies:
            for attempt in range(c.retries + 1):
                self._drop(b, rng, shrink=attempt / (c.retries + 1))
                try:
                    settled = self.settle(lambda: self._step(q_hold), [*self.present, b], self.bin_episode.settle_time)
                except _Unstable as exc:  # the pile exploded: nothing to pick
                    self.placement_error = f"while filling the bin: {exc}"
                    return
                if self._in_bin(b):
                    break
            if self._in_bin(b):
                self.present.append(b)
            else:
                self._park(b)
                self.spilled.append(self.names[b])
            if not settled:  # a pile may creep (objects leaning on each other slide by < 1 mm/s): noted, not fatal
                self.unsettled += 1
        self.set_target(self.present[0] if self.present else self.bodies[0])

    def _drop(self, body: int, rng: np.random.Generator, shrink: float) -> None:
        """Place `body` at rest, from a random orientation, with its surface's centre over a random
        point of the bin (a region shrunk towards the centre by `shrink` for re-drops) and its lowest
        point `drop_height` above the top of the pile."""
        c, m, d = self.bin_episode, self.model, self.data
        self._unpark(body)
        g = self.visual_geom(body)
        (cx, cy), (w, depth) = self.bin.centre, self.bin.inner
        half = np.maximum(np.array([w, depth]) / 2 - c.drop_margin - 0.5 * m.geom_rbound[g], 0.0) * (1.0 - shrink)
        top = max([self.bin.floor, *(float(self._object_z(b).max()) for b in self.present)])
        adr = self.qpos_of(body).start
        d.qpos[adr : adr + 3] = 0.0
        d.qpos[adr + 3 : adr + 7] = _random_quat(rng)
        d.qvel[self.dofs_of(body)] = 0.0
        mujoco.mj_kinematics(m, d)
        target = np.array([cx + rng.uniform(-half[0], half[0]), cy + rng.uniform(-half[1], half[1])])
        d.qpos[adr : adr + 2] = target - d.geom_xpos[g][:2]
        d.qpos[adr + 2] = top + c.drop_height - float(self._object_z(body).min())
        mujoco.mj_forward(m, d)

    def _park(self, body: int) -> None:
        """Take `body` out of the scene: far away, without contacts, floating at rest."""
        m, d = self.model, self.data
        i = self.bodies.index(body)
        d.qpos[self.qpos_of(body)] = [-2.0 - PARK_SPACING * i, 2.0, 1.0, 1.0, 0.0, 0.0, 0.0]
        d.qvel[self.dofs_of(body)] = 0.0
        m.geom_contype[self._geoms[body]] = 0
        m.geom_conaffinity[self._geoms[body]] = 0
        m.body_gravcomp[body] = 1.0

    def _unpark(self, body: int) -> None:
        m = self.model
        m.geom_contype[self._geoms[body]], m.geom_conaffinity[self._geoms[body]] = self._contact_bits[body]
        m.body_gravcomp[body] = 0.0

    def _in_bin(self, body: int) -> bool:
        """Whether the object's centre of mass is over the bin's floor and below its rim."""
        p = self.data.xipos[body]
        return bool(self.bin.contains(p[:2]) and p[2] < self.bin.wall_height + 0.5 * self._object_radius(body) + 0.02)

    # -- one attempt ------------------------------------------------------------------------------
    def target_at(self, point: np.ndarray, approach: np.ndarray) -> int:
        """The object whose surface the approach ray through `point` meets first (the ray starts
        5 cm before the point); -1 if it meets none."""
        geom = np.zeros(1, dtype=np.int32)
        start = np.asarray(point, float) - 0.05 * np.asarray(approach, float)
        dist = mujoco.mj_ray(self.model, self.data, start, np.asarray(approach, float), self._surface_group,
                             0, -1, geom)
        if dist < 0 or geom[0] < 0:
            return -1
        body = int(self.model.geom_bodyid[geom[0]])
        return body if body in self.present else -1

    def attempt(self, point: np.ndarray, approach: np.ndarray, target: int | None = None) -> AttemptResult:
        """Pick at world `point` along unit world `approach`, then clear what left the bin, retract
        and let the pile settle. `target`: the object under the grasp (`target_at`), if known."""
        point = np.asarray(point, float)
        approach = np.asarray(approach, float) / np.linalg.norm(approach)
        target = self.target_at(point, approach) if target is None else target
        self.set_target(target if target >= 0 else self.present[0])
        self._aim = target
        self._held = -1
        result = self.execute(point, approach)
        held = self._held
        self._retract()
        transported = [b for b in self.present if not self._in_bin(b) and self._over_receptacle(b)]
        lost = [b for b in self.present if not self._in_bin(b) and b not in transported]
        carried = [b for b in transported + lost if b != held and b in (self._in_bin_at_lift or ())]
        failure = result.failure
        if failure is None and carried:
            failure = "two_lifted"
        elif failure is None and held not in transported:
            failure = "missed_receptacle"
        elif failure is not None and target in lost and held != target:
            failure = "dragged_out"
        for b in transported + lost:
            self.present.remove(b)
            self._park(b)
        mujoco.mj_forward(self.model, self.data)
        result.failure = failure
        result.success = bool(result.valid and failure is None)
        name = self.names.get
        return AttemptResult(
            episode=result, target=name(target), held=name(held),
            transported=[self.names[b] for b in transported], lost=[self.names[b] for b in lost],
        )

    def _over_receptacle(self, body: int) -> bool:
        (bx, by), (w, d, h) = self.scene.config.bin_centre, self.scene.config.bin_size
        p = self.data.xipos[body]
        return bool(abs(p[0] - bx) < w / 2 and abs(p[1] - by) < d / 2 and p[2] < h + 0.1)

    # -- the episode's hooks ----------------------------------------------------------------------
    def _take_seal(self, body: int) -> bool:
        """The cup lifts whichever object of the bin it sealed on."""
        if body not in self.present:
            return False
        self.set_target(body)
        self._held = body
        return True

    def _lift_end(self, point: np.ndarray) -> np.ndarray:
        """Straight up until the held object's lowest point clears the rim and the rest of the pile
        (the transport swings sideways from there): the lift height, or more where the object hangs
        below the grasp further than the pile's top is below it."""
        end = super()._lift_end(point)
        hang = point[2] - float(self._object_z().min())
        tops = [float(self._object_z(b).max()) for b in self.present if b != self.object]
        end[2] = max(end[2], max([self.bin.wall_height, *tops]) + hang + self.bin_episode.carried_height)
        return end

    def _hover_height(self) -> float:
        """Over the whole pile and the rim, not only the target."""
        tops = [float(self._object_z(b).max()) for b in self.present]
        return max([self.bin.wall_height, *tops]) + self.config.transit_clearance

    def _check_robot_collision(self) -> None:
        """The episode's arm check, then the cup against the bin's walls and against objects other
        than the aimed one (only while the arm moves in: `watch_collisions`)."""
        super()._check_robot_collision()
        d, n = self.data, self.data.ncon
        if n == 0:
            return
        geoms = d.contact.geom[:n]
        touching = d.contact.dist[:n] < 0
        cup = self._is_cup[geoms[:, 0]] | self._is_cup[geoms[:, 1]]
        other = np.where(self._is_cup[geoms[:, 0]], geoms[:, 1], geoms[:, 0])
        hit = touching & cup
        walls = hit & self._is_wall[other]
        if np.any(walls):
            raise _Failure("collision_bin", self.contact_names(geoms[np.argmax(walls)]))
        objects = self._object_of_geom[other]
        if np.any(hit & (objects >= 0) & (objects != self._aim) & (self._aim >= 0)):
            self._brushed = True

    def _follow_holding(self, waypoints: np.ndarray, duration: float, grip: np.ndarray) -> tuple[bool, float]:
        """The episode's carrying motion; at the start of the first (the lift) it notes which other
        objects are in the bin, so that one leaving it from then on left with the held object."""
        if self._in_bin_at_lift is None:
            self._in_bin_at_lift = {b for b in self.present if b != self.object and self._in_bin(b)}
        return super()._follow_holding(waypoints, duration, grip)

    def execute(self, point: np.ndarray, approach: np.ndarray) -> EpisodeResult:
        self._in_bin_at_lift: set[int] | None = None
        self._brushed = False
        result = super().execute(point, approach)
        if result.failure == "no_seal" and self._brushed:  # a neighbour was in the cup's way
            result.failure = "collision_neighbour"
        return result

    def _retract(self) -> None:
        """Vent, put the arm back in its waiting configuration and let the pile settle (see the
        module docstring); an unstable pile is the next attempt's `placement_error`."""
        m, d = self.model, self.data
        keep = [(self.qpos_of(b), self.dofs_of(b)) for b in self.bodies]
        saved = [(d.qpos[q].copy(), d.qvel[v].copy()) for q, v in keep]
        d.qpos[:], d.qvel[:], d.ctrl[:] = self.scene.home_qpos, 0.0, self.scene.home_ctrl
        d.qpos[self.arm_qpos] = self._ready_configuration()
        for (q, v), (qs, vs) in zip(keep, saved, strict=True):
            d.qpos[q], d.qvel[v] = qs, vs
        self.cup.release(d)
        mujoco.mj_forward(m, d)
        q_hold = d.qpos[self.arm_qpos].copy()
        self.watch_collisions = False
        if not self.present:
            return
        try:
            if not self.settle(lambda: self._step(q_hold), self.present, self.bin_episode.settle_time):
                self.unsettled += 1
        except _Unstable as exc:
            self.placement_error = f"after the attempt: {exc}"

    def remove(self, body: int) -> None:
        """Take an object out of the bin (as a pick would) and let the rest settle: how dataset
        generation shows a network a pile at several stages of its clearing."""
        self.present.remove(body)
        self._park(body)
        mujoco.mj_forward(self.model, self.data)
        self._retract()

    def posed_mesh(self, body: int, mesh: Any) -> tuple[Any, np.ndarray]:
        """An object's surface mesh (given in its own frame) and centre of mass (the body's, so with
        its liquid as levelled: `sim.liquids`) at its current world pose."""
        d = self.data
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = d.xmat[body].reshape(3, 3), d.xpos[body]
        mesh = mesh.copy()
        mesh.apply_transform(pose)
        return mesh, pose[:3, :3] @ self.model.body_ipos[body] + pose[:3, 3]

    def resting_load(self, body: int) -> tuple[float, np.ndarray | None]:
        """The downward force (N) the other objects in the bin press onto `body` with, summed over
        their contacts (MuJoCo's contact forces, world z), and where it acts: the force-weighted mean
        of those contact points (None without any)."""
        m, d = self.model, self.data
        force, total, moment = np.zeros(6), 0.0, np.zeros(3)
        others = set(self.present) - {body}
        for i in range(d.ncon):
            contact = d.contact[i]
            b1, b2 = int(m.geom_bodyid[contact.geom1]), int(m.geom_bodyid[contact.geom2])
            if body not in (b1, b2) or not ({b1, b2} & others):
                continue
            mujoco.mj_contactForce(m, d, i, force)
            world = contact.frame.reshape(3, 3).T @ force[:3]  # the force on geom2, from geom1
            down = -(world[2] if b2 == body else -world[2])
            if down > 0.0:
                total += down
                moment += down * contact.pos
        return total, (moment / total if total > 0.0 else None)

    def loaded(self, body: int, mass: float, com: np.ndarray) -> tuple[float, np.ndarray]:
        """The mass and centre of mass (world) the cup must lift at `body`: the object's own, plus
        what its neighbours press onto it (`resting_load`) as mass at where it acts. A lift raises
        whatever rests on the object until it slides off, so the labeller, which sees the object
        alone, must carry that weight too (objects pinned under others were lost in the lift with
        robust labels: eval/bin/pinned.py). Horizontal contact forces are left out."""
        load, at = self.resting_load(body)
        if at is None:
            return mass, np.asarray(com, float)
        extra = load / STANDARD_GRAVITY
        total = mass + extra
        return total, (mass * np.asarray(com, float) + extra * at) / total


def _descends_from(model: mujoco.MjModel, body: int, ancestor: int) -> bool:
    """Whether `body` is `ancestor` or one of its descendants."""
    while body > 0:
        if body == ancestor:
            return True
        body = int(model.body_parentid[body])
    return ancestor == 0
