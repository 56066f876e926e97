"""Does the object stay where it lies while the cup presses on it? The touch-down's statics.

A seal forms while the cup is pressed onto the object: the episode's guarded approach stops once
the bellows has compressed by `PerturbationConfig.press_compression`, so the object then carries
the bellows' spring force P = k_a x, on top of its weight, until the vacuum holds it. Every other
test of the labeller takes the object to be at rest in its labelled pose; it is only if the table
and the lip's friction hold it there. A light cylinder pressed on its flank far from its top rolls
away before the lip closes (an empty 14.5 g water bottle lying on its side, pressed along its
surface normal 54-55 deg off the vertical, rolls 40 mm in the simulation and never seals).

The object is a rigid body on a rigid table. It carries its weight W at its centre of mass c and
the lip's force f = N d + t at the grasp point p: N along the press direction d (the approach,
into the object), and a tangential part t, |t| <= mu_l N, that the lip's friction mu_l can add
(the lip holds on to the surface it presses; the bellows' lateral stiffness carries t).

- Tipping about an edge of the footprint's convex outline (`Footprint`; a point q on it, u its
  direction, oriented so the weight over the footprint turns the object back) starts when the
  moment u . ((p - q) x f + (c - q) x W) is positive for every t the lip can give: the least is
  N u . (r x d) - mu_l N |(u x r) - ((u x r) . d) d| + u . ((c - q) x W), r = p - q
  (u . (r x t) = t . (u x r), smallest with t against the part of u x r across d). On a cylinder
  lying on its side (the footprint a line) this says: the lip's force can pass through the line
  of support only if the grasp lies within 2 atan(mu_l) of the top (53 deg at mu_l = 0.5; the
  chord from the grasp to the support line leaves the radius at half the grasp's angle).
- Sliding caps the press: the object slides along the table, pushed by the cup, once the lip's
  force, tilted towards the vertical by up to atan(mu_l) from d, has a horizontal part beyond the
  table's friction mu_t times the vertical load. The lip then goes on pressing at that force;
  the object slides with it (harmless to the seal), and the tipping test uses
  N = min(P, N_slide), N_slide = mu_t w cos(delta) / (sin(beta) - mu_t cos(beta)), w = |W|, alpha
  the angle of d from the vertical, delta = min(alpha, atan mu_l) the lip's tilt of the force and
  beta = alpha - delta (no cap where the denominator is not positive).

Left out: the lip's normal force is taken along the approach, not the surface normal the bellows
tilts towards (the two differ by at most the approach tolerance); each edge is tested with its own
best t; the table's and the object's compliance, which spread a line or point of support over a
small patch (a cylinder on its side rests on one facet of its mesh).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

FOOTPRINT_TOLERANCE = 1e-4
"""Hull vertices within this height (m) of the lowest, along gravity, are the footprint: where a
rigid object touches a rigid table. Far below a lip's millimetres, above a mesh's rounding (the
next ring of a 64-sided cylinder of 33 mm radius lies 0.16 mm above its resting facet)."""

INSIDE_TOLERANCE = 1e-6
"""A footprint narrower than this (m) is a line or a point (rounding only)."""


class Footprint:
    """The convex outline of an object's footprint on the table, seen along gravity: its edges as
    tipping axes."""

    def __init__(self, hull: np.ndarray, gravity: np.ndarray, tolerance: float = FOOTPRINT_TOLERANCE):
        down = np.asarray(gravity, dtype=float)
        down = down / max(float(np.linalg.norm(down)), 1e-12)
        hull = np.asarray(hull, dtype=float)
        depth = hull @ down
        points = hull[depth >= depth.max() - tolerance]
        origin = points.mean(axis=0)
        basis = np.linalg.svd(np.eye(3) - np.outer(down, down))[0][:, :2]
        flat = (points - origin) @ basis
        starts, directions = _outline_edges(flat)
        self.edge_points = origin + starts @ basis.T
        """(E, 3) a point q of each edge (m, mesh frame)."""
        axes = directions @ basis.T
        # Orient each edge so that the weight acting over the footprint's centre turns the object
        # back about it (the weight of the object at rest restores it).
        back = np.einsum("ei,ei->e", axes, np.cross(origin - self.edge_points, down))
        self.edge_axes = np.where((back > 0.0)[:, None], -axes, axes)
        """(E, 3) unit direction u of each edge, oriented so a positive moment about it tips."""


def _outline_edges(flat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Edges (points (E, 2), unit directions (E, 2)) of the convex outline of 2-D points: a
    polygon's sides; a line's own line (both ways) and its ends' perpendiculars; a point's
    horizontal axes at eight bearings."""
    try:
        ring = flat[ConvexHull(flat).vertices]
        side = np.roll(ring, -1, axis=0) - ring
        return ring, side / np.linalg.norm(side, axis=1, keepdims=True)
    except (QhullError, ValueError):
        pass
    spread = flat - flat.mean(axis=0)
    if len(flat) > 1 and np.abs(spread).max() > INSIDE_TOLERANCE:
        along = np.linalg.svd(spread, full_matrices=False)[2][0]
        s = spread @ along
        ends = flat.mean(axis=0) + np.outer([s.min(), s.max()], along)
        across = np.array([-along[1], along[0]])
        return (np.array([ends[0], ends[0], ends[0], ends[1]]),
                np.array([along, -along, across, across]))
    bearings = np.linspace(0.0, 2.0 * np.pi, 8, endpoint=False)
    return np.repeat(flat.mean(axis=0)[None], 8, axis=0), np.column_stack([np.cos(bearings), np.sin(bearings)])


def stays_put(points: np.ndarray, approaches: np.ndarray, com: np.ndarray, weight: np.ndarray,
              press_force: float, lip_friction: np.ndarray | float, table_friction: float,
              footprint: Footprint) -> np.ndarray:
    """bool (N,): whether the object stays at rest on its footprint while pressed with up to
    `press_force` (N) along each approach (N, 3) at each grasp point (N, 3), with its weight (N, 3)
    (N) at its centre of mass (N, 3) or (3,), the lip's friction (N,) or scalar and the
    object-table friction (module docstring)."""
    d = np.asarray(approaches, dtype=float)
    p = np.asarray(points, dtype=float)
    weight = np.broadcast_to(np.asarray(weight, dtype=float), p.shape)
    com = np.broadcast_to(np.asarray(com, dtype=float), p.shape)
    mu = np.broadcast_to(np.asarray(lip_friction, dtype=float), len(p))
    w = np.linalg.norm(weight, axis=1)
    down = weight / np.maximum(w, 1e-12)[:, None]
    alpha = np.arccos(np.clip(np.einsum("ni,ni->n", d, down), -1.0, 1.0))
    delta = np.minimum(alpha, np.arctan(mu))
    beta = alpha - delta
    excess = np.sin(beta) - table_friction * np.cos(beta)
    slide = np.where(excess > 0.0, table_friction * w * np.cos(delta) / np.maximum(excess, 1e-12), np.inf)
    force = np.minimum(press_force, slide)
    q, u = footprint.edge_points, footprint.edge_axes  # (E, 3)
    r = p[:, None, :] - q[None]  # (N, E, 3)
    u_r = np.cross(u[None], r)
    across = u_r - np.einsum("nei,ni->ne", u_r, d)[..., None] * d[:, None, :]
    press = np.einsum("nei,ni->ne", u_r, d) - mu[:, None] * np.linalg.norm(across, axis=2)  # u.(r x d) = d.(u x r)
    gravity = np.einsum("ei,nei->ne", u, np.cross(com[:, None, :] - q[None], weight[:, None, :]))
    return (force[:, None] * press + gravity <= 0.0).all(axis=1)
