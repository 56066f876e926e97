"""Seal formation: the physical lip (default) and the paper's quasi-static spring model.

Both models probe the surface by casting rays along the approach v from the plane orthogonal to v
through the target p; "depth" is the distance along v beyond that plane. Both share:

- the ring: the n perimeter vertices v_i of a regular n-gon of circumradius r around the axis,
  projected along v onto the mesh (first hit). A vertex that misses leaves the lip in the air
  (`ring_off_surface`). Their mean depth places the ring centre, the contact origin of the wrench
  model;
- the cup body: the apex a on the approach line, at the height that keeps the mean displacement
  along v between apex and vertices equal to h, and never beyond the surface: a = p_s + t* v with
  t* = min(mean_i (v_i - p_s).v - h, 0), p_s the target projected onto the surface (the paper
  prints a* = p - t* v, which with this t* would put the apex inside the object; its own
  constraint v.(a - p) <= 0 fixes the sign used here). The surface inside the footprint must
  nowhere rise above the triangular faces (a, v_i, v_i+1) (`cone_collision`: the cup would have
  to pass through it), and no ray inside the ring may pass through a gap in the surface (`hole`:
  a miss or a hit on a back face). In the lip model the body stands where the lip rests (item 3
  below), not where a vertex ray fell: a vertex over a groove the lip spans does not drag the cone
  face into the groove's edge;
- the springs of the paper (perimeter v_i v_i+1, flexion v_i v_i+2, cone v_i a) and their
  stretches, reported for the spring-stretch metric.

**Springs** (the paper's "Details of Quasi-Static Spring Seal Formation Model", `paper` preset):
each perimeter spring's deformed length is its path on the surface through `edge_samples` extra
points on the chord; a seal needs every spring's relative change in length within the stretch
limit (`stretch`), and the vacuum is the constant V. On a flat face this caps the approach tilt
where the longest cone spring reaches the limit (13.9 deg for the 15 mm cup).

**Lip** (the physical cup, default). The lip is measured at K >= 32 places on its circle
(`lip_samples`, 0.98 mm apart by default), depths d_k. Four pieces of physics decide the seal:

1. *The bellows tilts.* The bellows' end carries the lip and settles where the lip's
   spring forces (the paper's p(theta) = k delta(theta)) have no net moment about the axis, i.e.
   where the lip's fold delta(theta) has no first harmonic: the end plane is the least-squares
   first-harmonic fit P(theta) = c0 + a cos(theta) + b sin(theta) of the profile the lip rests
   on (fitted to the measured profile, then refitted after item 2's bridging, which works
   relative to the end plane: the lip bends relative to the bellows, not to the cup axis).
   The bellows can tilt until one side has used its whole stroke while the other is
   uncompressed: sqrt(a^2 + b^2) <= stroke / 2, i.e. a tilt of at most
   atan(stroke / (2 r)) = cup.approach_tolerance (21.8 deg); beyond it, `tilt`.
2. *The lip bends, but only so tightly.* A lip point folds independently of its neighbours up to
   lip_travel; on a cylinder of radius R lying on its side the lip circle's profile is
   z(s) = (r^2 / 2R) sin^2(s / r) along its arc length s, whose sag r^2 / (2R) must stay within
   lip_travel: R >= R_min = r^2 / (2 lip_travel) = cup.min_seal_radius (14.1 mm). That profile's
   curvature z'' = cos(2 s / r) / R is at most 1 / R, so the smallest cylinder the lip seals is
   also the tightest bend it makes: the lip bends along its circumference with radius >= R_min
   and bridges anything narrower. The profile the lip can rest on is the morphological closing
   of the surface profile by a disc of radius R_min rolled along the lip from the cup's side
   (parabolic in the small-slope approximation, s^2 / (2 R_min)): a 2 mm groove lets the lip in
   by only 1^2 / (2 x 14.1) = 0.04 mm, so the lip spans it and the groove stays open beneath.
   The window of the closing is +-r of arc: further away the rolled disc has risen by
   r^2 / (2 R_min) = lip_travel, more than the lip can fold anyway (item 3 covers that). Each
   place stands for its cell of lip, +-half the spacing: the disc rests on the cells' edges, not
   only on the places (else a groove would look up to two spacings wider than it is and the disc
   would sink up to 0.14 mm into a 2 mm groove instead of 0.04 mm).
3. *The lip folds at most lip_travel.* The vacuum pulls the cup on until the lip is folded flat
   where the bridged profile comes nearest the cup (relative to the bellows plane P); from there
   the lip reaches lip_travel further. Where the bridged profile lies deeper, a gap remains.
4. *Leak and vacuum.* The gap under each lip place is (depth - bridged profile) + what lies
   beyond the fold; where the lip is pressed on (folded) its thin edge closes seal_gap by itself,
   where it has unfolded to its full reach it carries no pressure and closes nothing (the
   ring-pressure condition p >= 0), so the leak area is A = sum_k max(0, gap_k - s_k) x (2 pi r / K)
   with s_k = seal_gap, or 0 beyond the fold. The ejector holds the vacuum
   p(A) = suctionbench.vacuum.equilibrium_vacuum (its flow curve against the orifice flow of the
   leak); the seal is made while p >= vacuum_switch_fraction p_max, i.e. A <= leak_threshold_area
   (~1.0 mm^2), else `leak`. The vacuum force V(A) (= p(A) x effective area) is the V of the
   wrench test, so a leaking seal holds less.

The profile the lip rests on relative to its bellows plane (zero mean and first harmonic) is also
returned, `SealResult.lip_heights`: the fold the lip lacks there, which sets its uneven preload in
the wrench test (wrench.py, "Lip preload").

The perimeter stretch of the lip model is that of the lip itself, relative to its bellows plane
(the tilt of the plane stretches nothing: the lip tilts with the bellows), and is still bound by
the stretch limit; the paper's flexion and cone springs are reported, not tested (the bellows
tilt replaces the cone springs' limit). Where the lip model and the paper's differ: the paper's
perimeter paths follow chords, so even a sphere stretches them; the lip circle on a sphere lies
at one depth and stretches nothing.

Cylinders lying on their side therefore seal down to ~R_min (slightly below: the first seal_gap
of excess and a small leak are tolerated, 12.5-13 mm for the default cup), a flat face seals up to
the approach tolerance, and a groove crossing the lip leaks. Not modelled: the bellows' axial
stroke beyond its tilt (a profile's mean depth is free), and any limit on small spheres other
than the lip landing on them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from suctionbench.config import CupConfig, SealConfig
from suctionbench.geometry.raycast import RayCaster
from suctionbench.vacuum import vacuum_force

FAILURES = ("none", "ring_off_surface", "hole", "cone_collision", "leak", "tilt", "stretch", "pushed_away")
"""Seal failure reasons, in the order they are reported (the first that applies wins): where the
lip leaks it usually also stretches (over an edge), and the leak is what loses the vacuum. The
last, "pushed_away", is the labeller's, not the seal model's: the cup would seal, but the object
slides or tips under the touch-down's press before it does (contact/press.py)."""

RING_OFF_SURFACE, HOLE, CONE_COLLISION, LEAK, TILT, STRETCH, PUSHED_AWAY = 1, 2, 3, 4, 5, 6, 7

Gate = Callable[..., np.ndarray]
"""gate(indices, ring_centres, vacuum_forces, lip_heights=None, rim_bound=False) -> bool mask: a
cheap test (the wrench test, `wrench.resists`) that lets later ray casts be skipped. The lip model
asks it twice: first with the full vacuum and `rim_bound=True`, before the leak and the lip's
profile are known (a necessary condition: what no vacuum or preload could resist is not
resisted), then with the vacuum the seal holds and the lip's profile heights (the exact test).
The spring model asks it once, with the full vacuum and no profile."""


@dataclass
class SealResult:
    """Per-grasp outcome of the seal model (arrays of length N)."""

    seal: np.ndarray
    """True where a seal is feasible."""

    failure: np.ndarray
    """Index into FAILURES of the first failed check (0 = sealed)."""

    max_stretch: np.ndarray
    """Largest relative length change over all springs (inf when the ring is off the surface)."""

    perimeter_stretch: np.ndarray
    """Largest relative length change of the perimeter springs (the lip model: of the lip itself,
    relative to its bellows plane)."""

    flexion_stretch: np.ndarray
    """Largest relative length change of the flexion springs."""

    cone_stretch: np.ndarray
    """Largest relative length change of the cone springs."""

    ring_off_surface: np.ndarray
    """True where some perimeter point missed the mesh."""

    hole: np.ndarray
    """True where the surface inside (or under) the ring has a gap."""

    cone_collision: np.ndarray
    """True where the surface rises above a cone face inside the footprint."""

    ring_centre: np.ndarray
    """(N, 3) centre of the contact ring (mean of the projected vertices): the contact origin."""

    surface_point: np.ndarray
    """(N, 3) the target projected onto the surface along v (NaN where the axis ray misses)."""

    planarity_rms: np.ndarray
    """RMS deviation (m) of the probed surface inside the disc from the plane through the surface
    point orthogonal to v (inf when a probe missed); feeds the planarity-based baselines."""

    tilt: np.ndarray
    """Tilt (rad) of the lip's bellows plane from the cup plane (lip model; NaN where the lip was
    not measured, and for the spring model)."""

    leak_area: np.ndarray
    """Leak area (m^2) under the lip (lip model; inf where the lip is not all on the surface; 0 for
    the spring model, which assumes a tight seal)."""

    vacuum_force: np.ndarray
    """Vacuum force V (N) the seal holds: the ejector's equilibrium against the leak (the spring
    model: the cup's constant V). The wrench test's V."""

    lip_heights: np.ndarray | None = None
    """(N, K) the profile the lip rests on, relative to its bellows plane (m, zero mean and first
    harmonic, positive away from the cup) at the K lip places `wrench.lip_angles(K)`: sets the lip's
    preload in the wrench test (NaN where the lip was not measured). None for the spring model."""

    @property
    def failure_names(self) -> list[str | None]:
        """Failure reason per grasp as a string, None where sealed."""
        return [None if f == 0 else FAILURES[f] for f in self.failure]


class SealModel:
    """The seal model for one mesh and cup (cup.seal_model picks lip or springs); vectorised over
    grasps."""

    def __init__(self, caster: RayCaster, cup: CupConfig, config: SealConfig | None = None):
        self.caster = caster
        self.cup = cup
        self.config = config or SealConfig()
        self.lip = cup.seal_model == "lip"
        n, m, r = cup.n_vertices, self.config.edge_samples, cup.radius
        angles = 2.0 * math.pi * np.arange(n) / n
        self.vertices_xy = r * np.stack([np.cos(angles), np.sin(angles)], axis=1)
        s = np.arange(m + 1) / (m + 1)
        nxt = np.roll(self.vertices_xy, -1, axis=0)
        # Perimeter points on the chords, edge by edge: vertex k then its m edge samples.
        self.perimeter_xy = (
            self.vertices_xy[:, None] * (1 - s)[None, :, None] + nxt[:, None] * s[None, :, None]
        ).reshape(-1, 2)
        self.edge_params = np.tile(s, n)
        self.edge_index = np.repeat(np.arange(n), m + 1)
        self.edge_only = np.tile(np.arange(m + 1) > 0, n)
        # Interior probes: fraction f of the way from the axis to a perimeter point; the outermost
        # fraction at every perimeter bearing, inner fractions at the vertex bearings only.
        fractions = sorted(self.config.interior_fractions)
        probe_f, probe_p = [], []
        for f in fractions:
            pts = np.arange(len(self.perimeter_xy)) if f == fractions[-1] else np.arange(n) * (m + 1)
            probe_f.append(np.full(len(pts), f))
            probe_p.append(pts)
        self.probe_fraction = np.concatenate(probe_f)
        self.probe_perimeter = np.concatenate(probe_p)
        self.probe_xy = self.probe_fraction[:, None] * self.perimeter_xy[self.probe_perimeter]
        self.perimeter_rest = 2.0 * r * math.sin(math.pi / n)
        self.segment_xy = self.perimeter_rest / (m + 1)
        self.flexion_rest = 2.0 * r * math.sin(2.0 * math.pi / n)
        self.cone_rest = math.hypot(r, cup.height)
        # The lip circle: K places, every per-th one a vertex.
        self.lip_per_edge = -(-self.config.lip_samples // n)
        k = n * self.lip_per_edge
        theta = 2.0 * math.pi * np.arange(k) / k
        self.lip_xy = r * np.stack([np.cos(theta), np.sin(theta)], axis=1)
        self.lip_vertex = np.arange(k) % self.lip_per_edge == 0
        self.lip_arc = 2.0 * math.pi * r / k
        self.lip_chord = 2.0 * r * math.sin(math.pi / k)
        self.lip_fit = np.stack([np.full(k, 1.0 / k), 2.0 * np.cos(theta) / k, 2.0 * np.sin(theta) / k], axis=1)
        self.lip_basis = np.stack([np.ones(k), np.cos(theta), np.sin(theta)], axis=1)
        reach = int(r / self.lip_arc)  # the closing's window: +-r of arc (module doc, item 2)
        self.bend_offsets = np.arange(-reach, reach + 1)
        self.bend_rise = (self.bend_offsets * self.lip_arc) ** 2 / (2.0 * cup.min_seal_radius)
        # each place stands for its cell of lip (+-half the spacing): the disc rests on the cells
        cell_gap = np.maximum(np.abs(self.bend_offsets) * self.lip_arc - 0.5 * self.lip_arc, 0.0)
        self.bend_rise_cell = cell_gap**2 / (2.0 * cup.min_seal_radius)
        self.leak_threshold = cup.leak_threshold_area

    # -- ray casting -------------------------------------------------------------------------
    def _depths(self, points: np.ndarray, frames: np.ndarray, offsets_xy: np.ndarray):
        """Depth (S, K) along v of the first hit below each in-plane offset, and back-face flags.

        Rays start on the plane orthogonal to v just outside the mesh's bounding sphere.
        """
        approach = frames[:, :, 2]
        start = (
            np.einsum("ij,ij->i", points - self.caster.center, approach)
            + self.caster.bounding_radius
            + self.cup.radius
            + 1e-3
        )
        base = points - start[:, None] * approach
        origins = (
            base[:, None, :]
            + offsets_xy[None, :, 0, None] * frames[:, None, :, 0]
            + offsets_xy[None, :, 1, None] * frames[:, None, :, 1]
        )
        k = len(offsets_xy)
        hits = self.caster.cast(origins.reshape(-1, 3), np.repeat(approach, k, axis=0))
        depth = hits.distance.reshape(-1, k) - start[:, None]
        return depth, hits.back_face.reshape(-1, k)

    # -- the lip -----------------------------------------------------------------------------
    def lip_profile(self, depth: np.ndarray) -> dict[str, np.ndarray]:
        """The lip on a measured profile `depth` (S, K) (finite, the lip circle's K places):
        module doc, items 1-4. Returns the bridged profile, where the lip rests, the gap under each
        place, the leak area, the bellows plane's tilt and the lip's own perimeter stretch."""
        # The lip bends relative to the bellows' end, so the end's plane comes off first: fit it
        # to the raw profile, close the rest, and refit what the closing changed (a groove pulls
        # the first fit, the bridged profile no longer has it).
        coef = depth @ self.lip_fit
        relative = depth - coef @ self.lip_basis.T
        height = -relative  # toward the cup; the rolled disc comes from above
        lip = self._closing(height, self.bend_rise_cell)
        correction = -lip @ self.lip_fit
        coef = coef + correction
        e = -lip - correction @ self.lip_basis.T  # the bridged profile relative to the end plane
        bridged = depth - (relative + lip)  # the same, in depth along v
        floor = e.min(axis=1, keepdims=True)
        beyond = np.maximum(e - floor - self.cup.lip_travel, 0.0)
        gap = (depth - bridged) + beyond
        resting = bridged - beyond  # where the lip itself ends up
        # the edge closes seal_gap only where the lip is pressed on; unfolded to its reach, it is not
        allowance = np.where(beyond > 0.0, 0.0, self.cup.seal_gap)
        leak = np.maximum(gap - allowance, 0.0).sum(axis=1) * self.lip_arc
        tilt = np.arctan(np.hypot(coef[:, 1], coef[:, 2]) / self.cup.radius)
        fold = np.minimum(e, floor + self.cup.lip_travel)  # the lip itself, relative to its plane
        rise = np.diff(np.concatenate([fold, fold[:, :1]], axis=1), axis=1)
        length = np.sqrt(self.lip_chord**2 + rise**2).reshape(len(depth), self.cup.n_vertices, -1).sum(axis=2)
        stretch = np.abs(length / (self.lip_per_edge * self.lip_chord) - 1.0).max(axis=1)
        return {"bridged": bridged, "resting": resting, "gap": gap, "leak": leak, "tilt": tilt, "stretch": stretch}

    def lip_heights(self, depth: np.ndarray) -> np.ndarray:
        """(S, K) the profile the lip rests on relative to its bellows plane (zero mean and first
        harmonic, positive away from the cup) for measured lip profiles `depth` (S, K): the wrench
        test's lip preload (`SealResult.lip_heights`). The same closing as `lip_profile`'s with each
        place a point, not a cell: the cells keep a 2 mm groove from looking wider than it is (the
        leak), but on a slope they lift the lip by up to slope x spacing / 2 (0.06 mm at 45 deg on a
        30 mm cylinder), which would shift the whole profile's mean; with points a slope whose
        curvature the lip follows (< 1 / R_min) closes to itself."""
        relative = depth - (depth @ self.lip_fit) @ self.lip_basis.T
        lip = self._closing(-relative, self.bend_rise)
        return -lip + (lip @ self.lip_fit) @ self.lip_basis.T

    def _closing(self, height: np.ndarray, rest_rise: np.ndarray) -> np.ndarray:
        """Morphological closing of `height` (S, K) (toward the cup) round the lip by the disc of
        radius R_min rolled from the cup's side (module doc, item 2): the lowest each disc rests
        on the places, `rest_rise` its rise at each offset (cells or points), then the envelope of
        the discs."""
        k, w = height.shape[1], int(self.bend_offsets[-1])
        wrapped = np.concatenate([height[:, k - w :], height, height[:, :w]], axis=1)  # round the circle
        rest = np.full_like(height, -np.inf)
        for o, rise in zip(self.bend_offsets, rest_rise, strict=True):
            np.maximum(rest, wrapped[:, w + o : w + o + k] - rise, out=rest)  # lowest resting disc at y
        wrapped = np.concatenate([rest[:, k - w :], rest, rest[:, :w]], axis=1)
        lip = np.full_like(height, np.inf)
        for o, rise in zip(self.bend_offsets, self.bend_rise, strict=True):
            np.minimum(lip, wrapped[:, w + o : w + o + k] + rise, out=lip)  # envelope of the discs
        return lip

    # -- the model ---------------------------------------------------------------------------
    def evaluate(self, points: np.ndarray, frames: np.ndarray, gate: Gate | None = None):
        """Seal model for grasps at `points` (N, 3) with grasp frames `frames` (N, 3, 3).

        Without a gate, every check runs for every grasp and the full `SealResult` is returned.
        With a gate (used by the robust metric), the checks run in stages, cheapest first, and a
        grasp that fails the gate or an earlier stage casts no further rays; then the return value
        is only the bool mask gate & seal.
        """
        with np.errstate(invalid="ignore"):  # inf - inf for rays that miss is handled explicitly
            return self._evaluate(np.asarray(points, dtype=float), frames, gate)

    def _evaluate(self, points: np.ndarray, frames: np.ndarray, gate: Gate | None):
        count = len(points)
        n, cup = self.cup.n_vertices, self.cup
        approach = frames[:, :, 2]
        staged = gate is not None
        full_vacuum = np.full(count, cup.vacuum_force)

        # Stage A: the axis and the n vertices fix the ring centre and the apex.
        axis_vertex_xy = np.vstack([np.zeros((1, 2)), self.vertices_xy])
        d_av, back_av = self._depths(points, frames, axis_vertex_xy)
        d_axis, d_vert = d_av[:, 0], d_av[:, 1:]
        ring_off = ~np.isfinite(d_vert).all(axis=1)
        hole = back_av.any(axis=1) | ~np.isfinite(d_axis)
        ring_depth = np.where(ring_off, np.nan, d_vert.mean(axis=1))
        ring_centre = points + ring_depth[:, None] * approach
        apex = np.minimum(ring_depth - cup.height, d_axis)  # depth of the apex, see module doc

        flexion = np.abs(
            np.sqrt(1.0 + ((np.roll(d_vert, -2, axis=1) - d_vert) / self.flexion_rest) ** 2) - 1.0
        ).max(axis=1)
        cone = np.abs(
            np.sqrt(cup.radius**2 + (d_vert - apex[:, None]) ** 2) / self.cone_rest - 1.0
        ).max(axis=1)

        alive = ~ring_off
        if staged:  # a wrench the full vacuum cannot resist is not resisted with less
            alive &= ~hole
            idx = np.flatnonzero(alive)
            ok = gate(idx, ring_centre[idx], full_vacuum[idx], rim_bound=self.lip)
            if not self.lip:
                ok &= np.maximum(flexion, cone)[idx] <= cup.stretch_limit
            alive[idx] = ok

        # Stage B: the perimeter (springs: chord paths; lip: the lip circle, gap, leak, vacuum).
        idx = np.flatnonzero(alive) if staged else np.arange(count)
        if self.lip:
            perimeter, d_per, tilt, leak, vacuum, resting = self._lip_stage(points, frames, idx, d_vert, ring_off, hole)
            # the cup body ends where the lip rests (it spans what it bridges), not in a groove
            rim = np.where(np.isfinite(resting), resting, d_vert)
            apex = np.minimum(rim.mean(axis=1) - cup.height, d_axis)  # the body stands on the lip
            tilt_fail = ~(tilt <= cup.approach_tolerance)
            leak_fail = ~(leak <= self.leak_threshold)
            stretch_fail = ~(perimeter <= cup.stretch_limit)
            max_stretch = np.maximum(perimeter, np.maximum(flexion, cone))
        else:
            perimeter, d_per = self._chord_stage(points, frames, idx, d_vert, ring_off, hole)
            rim = d_vert
            tilt = np.full(count, np.nan)
            leak = np.zeros(count)
            vacuum = full_vacuum
            tilt_fail = leak_fail = np.zeros(count, dtype=bool)
            max_stretch = np.maximum(perimeter, np.maximum(flexion, cone))
            stretch_fail = ~(max_stretch <= cup.stretch_limit)
        perimeter[ring_off] = np.inf
        max_stretch[ring_off] = np.inf
        if staged:
            alive &= ~ring_off & ~hole & ~stretch_fail & ~tilt_fail & ~leak_fail
            if self.lip:  # now with the vacuum the seal holds
                idx = np.flatnonzero(alive)
                alive[idx] = gate(idx, ring_centre[idx], vacuum[idx], lip_heights=self.lip_heights(d_per[idx]))

        # Stage C: probes inside the ring for holes and cone-face collisions.
        idx = np.flatnonzero(alive) if staged else np.arange(count)
        collision = np.zeros(count, dtype=bool)
        planarity = np.full(count, np.inf)
        if len(idx):
            d_in, back_in = self._depths(points[idx], frames[idx], self.probe_xy)
            hole[idx] |= back_in.any(axis=1) | ~np.isfinite(d_in).all(axis=1)
            f = self.probe_fraction
            s = self.edge_params[self.probe_perimeter]
            k = self.edge_index[self.probe_perimeter]
            face = (
                (1.0 - f) * apex[idx, None]
                + f * (1.0 - s) * rim[idx][:, k]
                + f * s * rim[idx][:, (k + 1) % n]
            )
            collision[idx] = (np.isfinite(d_in) & (d_in < face - self.config.collision_tolerance)).any(axis=1)
            if not staged:
                probed = np.concatenate([d_per[idx], d_in], axis=1) - d_axis[idx, None]
                planarity[idx] = np.sqrt(np.mean(probed**2, axis=1))

        if staged:
            return alive & ~hole & ~collision

        failure = np.zeros(count, dtype=np.int8)
        for code, flag in ((STRETCH, stretch_fail), (TILT, tilt_fail), (LEAK, leak_fail),
                           (CONE_COLLISION, collision), (HOLE, hole), (RING_OFF_SURFACE, ring_off)):
            failure[flag] = code
        surface = np.where(np.isfinite(d_axis)[:, None], points + d_axis[:, None] * approach, np.nan)
        planarity[~np.isfinite(planarity)] = np.inf
        heights = None
        if self.lip:  # where the lip was measured (all of it on the surface)
            heights = np.full(d_per.shape, np.nan)
            measured = np.isfinite(leak)
            heights[measured] = self.lip_heights(d_per[measured])
        return SealResult(
            seal=failure == 0,
            failure=failure,
            max_stretch=max_stretch,
            perimeter_stretch=perimeter,
            flexion_stretch=np.where(ring_off, np.inf, flexion),
            cone_stretch=np.where(ring_off, np.inf, cone),
            ring_off_surface=ring_off,
            hole=hole,
            cone_collision=collision,
            ring_centre=ring_centre,
            surface_point=surface,
            planarity_rms=planarity,
            tilt=tilt,
            leak_area=leak,
            vacuum_force=vacuum,
            lip_heights=heights,
        )

    def _chord_stage(self, points, frames, idx, d_vert, ring_off, hole):
        """The paper's perimeter springs: each spring's path on the surface through its chord's
        edge samples. Updates ring_off / hole in place; returns (stretch, depths of all points)."""
        count, n = len(points), self.cup.n_vertices
        perimeter = np.full(count, np.inf)
        d_per = np.full((count, len(self.perimeter_xy)), np.inf)
        if len(idx):
            edge_xy = self.perimeter_xy[self.edge_only]
            d_edge, back_edge = self._depths(points[idx], frames[idx], edge_xy)
            d_per[np.ix_(idx, np.flatnonzero(self.edge_only))] = d_edge
            d_per[np.ix_(idx, np.flatnonzero(~self.edge_only))] = d_vert[idx]
            ring_off[idx] |= ~np.isfinite(d_edge).all(axis=1)
            hole[idx] |= back_edge.any(axis=1)
            rise = np.diff(np.concatenate([d_per[idx], d_per[idx, :1]], axis=1), axis=1)
            length = np.sqrt(self.segment_xy**2 + rise**2).reshape(len(idx), n, -1).sum(axis=2)
            perimeter[idx] = np.abs(length / self.perimeter_rest - 1.0).max(axis=1)
        return perimeter, d_per

    def _lip_stage(self, points, frames, idx, d_vert, ring_off, hole):
        """The lip circle: cast its non-vertex places, then `lip_profile` where all of it landed.
        Updates ring_off / hole in place; returns (lip stretch, depths, tilt, leak area, vacuum
        force, resting depth of the lip at the n vertex bearings), inf / NaN / inf / 0 / inf where
        the lip is not (all) on the surface."""
        count = len(points)
        stretch = np.full(count, np.inf)
        tilt = np.full(count, np.nan)
        leak = np.full(count, np.inf)
        d_lip = np.full((count, len(self.lip_xy)), np.inf)
        resting = np.full((count, self.cup.n_vertices), np.inf)
        if len(idx):
            d_new, back_new = self._depths(points[idx], frames[idx], self.lip_xy[~self.lip_vertex])
            d_lip[np.ix_(idx, np.flatnonzero(~self.lip_vertex))] = d_new
            d_lip[np.ix_(idx, np.flatnonzero(self.lip_vertex))] = d_vert[idx]
            ring_off[idx] |= ~np.isfinite(d_new).all(axis=1)
            hole[idx] |= back_new.any(axis=1)
            on = idx[np.isfinite(d_lip[idx]).all(axis=1)]
            if len(on):
                lip = self.lip_profile(d_lip[on])
                stretch[on], tilt[on], leak[on] = lip["stretch"], lip["tilt"], lip["leak"]
                resting[on] = lip["resting"][:, self.lip_vertex]
        measured = np.isfinite(leak)
        vacuum = np.zeros(count)
        vacuum[measured] = vacuum_force(leak[measured], self.cup)
        return stretch, d_lip, tilt, leak, vacuum, resting
