"""Quasi-static spring seal formation (Dex-Net 3.0, "Details of Quasi-Static Spring Seal Formation Model").

The cup is a right pyramid of springs: n perimeter vertices v_i on a regular n-gon of circumradius
r, an apex a at height h. Perimeter springs join v_i and v_i+1, flexion springs v_i and v_i+2,
cone springs v_i and a. For a grasp (p, v):

1. Perimeter: the n-gon is placed in the plane orthogonal to v through p and every perimeter
   point is projected along v onto the mesh (first hit), so the ring keeps its shape seen along v.
   Each perimeter spring's deformed length is the length of its path on the surface inside the
   prism face, measured through `edge_samples` extra surface points per spring.
2. Apex: on the approach line, at the height that keeps the mean displacement along v between apex
   and vertices equal to h, and never beyond the surface: a = p_s + t* v with
   t* = min(mean_i (v_i - p_s).v - h, 0), where p_s is the target projected onto the surface along
   v. (The paper prints a* = p - t* v, which with this t* would put the apex inside the object;
   its own constraint v.(a - p) <= 0 fixes the sign used here.)
3. Feasible iff: every perimeter point lands on the outside of the surface (else the lip hangs in
   the air: `ring_off_surface`); no ray inside the ring passes through a gap in the surface
   (`hole`: a miss or a hit on a back face); the surface inside the footprint nowhere rises above
   the pyramid's triangular cone faces (a, v_i, v_i+1) (`cone_collision`: anything the faces would
   have to pass through, during the approach along v or in contact); and every spring's relative
   change in length is within the stretch limit (`stretch`).

Depths below are distances along v beyond the plane orthogonal to v through p.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from suctionbench.config import CupConfig, SealConfig
from suctionbench.geometry.raycast import RayCaster

FAILURES = ("none", "ring_off_surface", "hole", "cone_collision", "stretch")
"""Seal failure reasons, in the order they are reported (the first that applies wins)."""

RING_OFF_SURFACE, HOLE, CONE_COLLISION, STRETCH = 1, 2, 3, 4

Gate = Callable[[np.ndarray, np.ndarray], np.ndarray]
"""gate(indices, ring_centres) -> bool mask: a cheap test that lets later ray casts be skipped."""


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
    """Largest relative length change of the perimeter springs."""

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

    @property
    def failure_names(self) -> list[str | None]:
        """Failure reason per grasp as a string, None where sealed."""
        return [None if f == 0 else FAILURES[f] for f in self.failure]


class SealModel:
    """The spring seal model for one mesh and cup; vectorised over grasps."""

    def __init__(self, caster: RayCaster, cup: CupConfig, config: SealConfig | None = None):
        self.caster = caster
        self.cup = cup
        self.config = config or SealConfig()
        n, m, r = cup.n_vertices, self.config.edge_samples, cup.radius
        angles = 2.0 * math.pi * np.arange(n) / n
        self.vertices_xy = r * np.stack([np.cos(angles), np.sin(angles)], axis=1)
        s = np.arange(m + 1) / (m + 1)
        nxt = np.roll(self.vertices_xy, -1, axis=0)
        # Perimeter points, edge by edge: vertex k then its m edge samples.
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
        n, cup, tol = self.cup.n_vertices, self.cup, self.config.collision_tolerance
        approach = frames[:, :, 2]
        staged = gate is not None

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
        if staged:
            alive &= ~hole
            idx = np.flatnonzero(alive)
            alive[idx] = gate(idx, ring_centre[idx]) & (np.maximum(flexion, cone)[idx] <= cup.stretch_limit)

        # Stage B: the perimeter paths.
        idx = np.flatnonzero(alive) if staged else np.arange(count)
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
        perimeter[ring_off] = np.inf
        max_stretch = np.maximum(perimeter, np.maximum(flexion, cone))
        max_stretch[ring_off] = np.inf
        stretch_fail = ~(max_stretch <= cup.stretch_limit)
        if staged:
            alive &= ~ring_off & ~hole & ~stretch_fail

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
                + f * (1.0 - s) * d_vert[idx][:, k]
                + f * s * d_vert[idx][:, (k + 1) % n]
            )
            collision[idx] = (np.isfinite(d_in) & (d_in < face - tol)).any(axis=1)
            if not staged:
                probed = np.concatenate([d_per[idx], d_in], axis=1) - d_axis[idx, None]
                planarity[idx] = np.sqrt(np.mean(probed**2, axis=1))

        if staged:
            return alive & ~hole & ~collision

        failure = np.zeros(count, dtype=np.int8)
        for code, flag in ((STRETCH, stretch_fail), (CONE_COLLISION, collision), (HOLE, hole),
                           (RING_OFF_SURFACE, ring_off)):
            failure[flag] = code
        surface = np.where(np.isfinite(d_axis)[:, None], points + d_axis[:, None] * approach, np.nan)
        planarity[~np.isfinite(planarity)] = np.inf
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
        )
