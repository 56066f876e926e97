"""Adversarial parts: 3D-printable shapes whose surfaces offer few places a suction cup can seal.

In the spirit of the Dex-Net 3.0 adversarial objects and EGAD, every generator here builds a part
made mostly of surface the 15 mm cup cannot seal on - twisted ruled flanks, saddles, narrow ridges
and teeth, bumps, thin bars, tight tubes - while leaving a few small patches that can seal, so a
grasp policy has to find them. Sealable patches are nearly flat or evenly curved (the spring
model seals on any sphere: the lip lands at one depth all round) and only slightly wider than the
cup; what defeats the lip is curvature that differs between directions, and edges.

Shapes are built with manifold3d (extrusion, booleans, vertex warps), or as smooth radial
displacements of a finely tessellated sphere, or as a tube swept along a closed curve; all are
watertight, consistently wound single bodies. Parameters are plain keywords (metres, radians) and
every generator is deterministic.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import manifold3d as m3d
import numpy as np
import trimesh

from suctionbench.objects.mass import printed
from suctionbench.objects.shapes import generator
from suctionbench.objects.spec import ObjectSpec

# -- shared helpers --------------------------------------------------------------------------------


SLIVER_TOLERANCE = 1e-6
"""Boolean results can hold near-zero-area triangles (vertices a few nanometres apart where faces
meet); validation drops those and would open the mesh, so edges shorter than this (m, far below
any feature) are collapsed first."""


def to_trimesh(solid: m3d.Manifold) -> trimesh.Trimesh:
    """A manifold3d solid as a trimesh (manifold output is closed and outward wound).

    as_original() forgets which input each face came from, so simplify may collapse slivers on
    the seams between inputs too (it keeps those seams otherwise).
    """
    mesh = solid.as_original().simplify(SLIVER_TOLERANCE).to_mesh64()
    return trimesh.Trimesh(np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts), process=True)


def extrude(contours: list[np.ndarray], height: float, twist: float = 0.0, divisions: int = 0) -> m3d.Manifold:
    """Prism over 2D `contours` (counter-clockwise outer, clockwise holes) along z, centred on z = 0.

    `twist` (rad) turns the top against the bottom through `divisions` intermediate layers, which
    keeps the twisted flanks smooth (manifold3d interpolates linearly between layers).
    """
    section = m3d.CrossSection([np.asarray(c, dtype=float) for c in contours])
    solid = section.extrude(height, n_divisions=divisions, twist_degrees=math.degrees(twist))
    return solid.translate((0.0, 0.0, -height / 2.0))


def fibonacci_directions(count: int) -> np.ndarray:
    """`count` near-uniform unit vectors (Fibonacci sphere): deterministic bump placements."""
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    phi = math.pi * (3.0 - math.sqrt(5.0)) * k
    rho = np.sqrt(1.0 - z**2)
    return np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=1)


def radial_sphere(radius_of: Callable[[np.ndarray], np.ndarray], subdivisions: int = 4) -> trimesh.Trimesh:
    """A star-shaped solid: the icosphere vertex in unit direction d moved to radius_of(d) (m).

    As long as radius_of is positive the surface stays an embedding (one point per direction), so
    the result is watertight and outward wound whatever the displacement; `subdivisions` 4 gives
    5120 faces, fine enough for bumps a few millimetres wide.
    """
    sphere = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    directions = np.asarray(sphere.vertices)
    radii = np.asarray(radius_of(directions), dtype=float)
    if not np.all(radii > 0.0):
        raise ValueError("radial displacement must keep every radius positive")
    return trimesh.Trimesh(directions * radii[:, None], sphere.faces, process=True)


def sweep_tube(centres: np.ndarray, normals: np.ndarray, radius: float, sides: int) -> trimesh.Trimesh:
    """Closed tube of circular section `radius` around a closed polyline (S, 3).

    `normals` (S, 3) are unit vectors orthogonal to the curve, one per centre; they must be
    periodic (the caller picks a frame that closes) so the last ring joins the first untwisted.
    """
    count = len(centres)
    tangents = np.roll(centres, -1, axis=0) - np.roll(centres, 1, axis=0)
    tangents /= np.linalg.norm(tangents, axis=1, keepdims=True)
    normals = normals - np.einsum("ij,ij->i", normals, tangents)[:, None] * tangents
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    binormals = np.cross(tangents, normals)
    theta = 2.0 * math.pi * np.arange(sides) / sides
    rings = centres[:, None, :] + radius * (
        np.cos(theta)[None, :, None] * normals[:, None, :] + np.sin(theta)[None, :, None] * binormals[:, None, :]
    )
    i, j = np.meshgrid(np.arange(count), np.arange(sides), indexing="ij")
    a = i * sides + j
    b = ((i + 1) % count) * sides + j
    c = ((i + 1) % count) * sides + (j + 1) % sides
    d = i * sides + (j + 1) % sides
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    mesh = trimesh.Trimesh(rings.reshape(-1, 3), faces, process=True)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def star_polygon(points: int, outer_radius: float, inner_radius: float) -> np.ndarray:
    """Counter-clockwise star outline: `points` tips at outer_radius, notches at inner_radius."""
    angles = math.pi * np.arange(2 * points) / points
    radii = np.where(np.arange(2 * points) % 2 == 0, outer_radius, inner_radius)
    return np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)


def circle(radius: float, segments: int = 48, clockwise: bool = False) -> np.ndarray:
    """Polygon approximating a circle (clockwise for a hole in a cross-section)."""
    angles = 2.0 * math.pi * np.arange(segments) / segments
    points = radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    return points[::-1] if clockwise else points


# -- generators --------------------------------------------------------------------------------


@generator("twisted_star")
def twisted_star(
    points: int, outer_radius: float, inner_radius: float, height: float, twist: float, divisions: int = 24
) -> trimesh.Trimesh:
    """Star prism twisted about its axis: ridge-like tips and warped, ruled flanks.

    The twist turns each flank into a ruled surface whose lines rotate along the axis, so the lip
    stays within its stretch limit only on narrow bands of it (more twist, fewer bands); the caps
    seal only near their centre, where the star's inscribed disc is barely wider than the cup
    when inner_radius is close to the cup radius.
    """
    star = star_polygon(points, outer_radius, inner_radius)
    return to_trimesh(extrude([star], height, twist=twist, divisions=divisions))


@generator("ribbed_saddle")
def ribbed_saddle(
    size: float,
    thickness: float,
    curvature: float,
    rib_spacing: float,
    rib_width: float,
    rib_height: float,
    edge: float = 0.011,
) -> trimesh.Trimesh:
    """Hyperbolic-paraboloid slab z = curvature (x^2 - y^2) with a grid of ribs on both faces.

    The ribs cut both faces into cells of clear width rib_spacing - rib_width; only near the
    middle of a cell wider than the cup can the lip land without riding up a rib, and the saddle's
    opposite curvatures in x and y stretch the lip further. The square slab, ribs included, is
    built flat, refined to edges of at most `edge` (m) and then bent, so the bent surface stays
    smooth; refining finer multiplies the faces (0.011 keeps a 10 cm slab with 4 ribs a side
    within ~5000).
    """
    half = size / 2.0
    parts = [m3d.Manifold.cube((size, size, thickness), center=True)]
    offsets = np.arange(-half + rib_spacing / 2.0, half, rib_spacing)
    offsets = offsets - offsets.mean()
    # Ribs are sunk half the slab thickness into it and stop rib_width / 2 short of its rim: faces
    # that merely touch or lie flush make booleans leave coincident vertices (not a clean solid).
    length, depth = size - rib_width, rib_height + thickness / 2.0
    for side in (-1.0, 1.0):
        z = side * (thickness / 2.0 + rib_height - depth / 2.0)
        for o in offsets:
            parts.append(m3d.Manifold.cube((length, rib_width, depth), center=True).translate((0.0, o, z)))
            parts.append(m3d.Manifold.cube((rib_width, length, depth), center=True).translate((o, 0.0, z)))
    flat = m3d.Manifold.batch_boolean(parts, m3d.OpType.Add).refine_to_length(edge)

    def bend(v: np.ndarray) -> np.ndarray:
        v = np.array(v, dtype=float)
        v[:, 2] += curvature * (v[:, 0] ** 2 - v[:, 1] ** 2)
        return v

    return to_trimesh(flat.warp_batch(bend))


@generator("gear")
def gear(
    teeth: int,
    root_radius: float,
    tip_radius: float,
    tooth_width: float,
    thickness: float,
    hub_radius: float,
    hub_height: float,
    bore_radius: float,
) -> trimesh.Trimesh:
    """Spur-gear blank: narrow straight teeth, a raised hub on both faces and a bore through it.

    The teeth are narrower than the cup; the faces seal only on the ring between the hub and the
    tooth roots, and only where it is wider than the cup; the hub's top seals where its annulus
    around the bore is wide enough.
    """
    half_root = tooth_width / 2.0 / root_radius
    half_tip = tooth_width / 2.0 / tip_radius
    outline = []
    for k in range(teeth):
        a = 2.0 * math.pi * k / teeth
        for angle, radius in ((a - half_root, root_radius), (a - half_tip, tip_radius),
                              (a + half_tip, tip_radius), (a + half_root, root_radius)):
            outline.append((radius * math.cos(angle), radius * math.sin(angle)))
        mid = a + math.pi / teeth  # one root vertex between teeth keeps the root circle round
        outline.append((root_radius * math.cos(mid), root_radius * math.sin(mid)))
    bore = circle(bore_radius, clockwise=True)
    body = extrude([np.asarray(outline), bore], thickness)
    hub = extrude([circle(hub_radius), bore], hub_height)
    return to_trimesh(body + hub)


@generator("knobby_blob")
def knobby_blob(
    radius: float, bumps: int, bump_height: float, bump_width: float, subdivisions: int = 4
) -> trimesh.Trimesh:
    """Sphere covered with smooth Gaussian bumps at near-uniform (Fibonacci) directions.

    A bare sphere seals everywhere in the spring model; bumps of angular width `bump_width` (rad)
    leave sealable sphere only where the gap between neighbours is wider than the cup.
    """
    centres = fibonacci_directions(bumps)

    def radius_of(d: np.ndarray) -> np.ndarray:
        cos_angle = d @ centres.T
        return radius + bump_height * np.exp((cos_angle - 1.0) / bump_width**2).sum(axis=1)

    return radial_sphere(radius_of, subdivisions)


@generator("ball_truss")
def ball_truss(
    cells: list[int], cell_size: float, bar_radius: float, node_radius: float, diagonals: bool = True
) -> trimesh.Trimesh:
    """Space-frame lattice: ball nodes on a grid of cells joined by thin round bars.

    Bars thinner than the cup cannot seal; the balls can, but only on the caps facing away from
    every bar, so the sealable share falls as bars (and face diagonals) are added.
    """
    grid = np.stack(np.meshgrid(*[np.arange(n + 1) for n in cells], indexing="ij"), -1).reshape(-1, 3)
    nodes = (grid - np.asarray(cells) / 2.0) * cell_size
    steps = [np.eye(3, dtype=int)[k] for k in range(3)]
    if diagonals:  # one diagonal across every cell face, all parallel: braces the frame
        steps += [np.array(s) for s in ((1, 1, 0), (1, 0, 1), (0, 1, 1))]
    index = {tuple(g): i for i, g in enumerate(grid)}
    bars = [(index[tuple(g)], index[tuple(g + s)]) for g in grid for s in steps if tuple(g + s) in index]
    # Coarse tessellation (16-segment balls, octagonal bars) keeps 2 x 2 x 1 cells within ~6000 faces.
    parts = [m3d.Manifold.sphere(node_radius, 16).translate(tuple(p)) for p in nodes]
    parts += [_bar(nodes[i], nodes[j], bar_radius, segments=8) for i, j in bars]
    return to_trimesh(m3d.Manifold.batch_boolean(parts, m3d.OpType.Add))


def _bar(start: np.ndarray, end: np.ndarray, radius: float, segments: int) -> m3d.Manifold:
    """Round bar (cylinder) from `start` to `end`."""
    axis = end - start
    length = float(np.linalg.norm(axis))
    rotation = trimesh.geometry.align_vectors([0.0, 0.0, 1.0], axis / length)
    transform = rotation.copy()
    transform[:3, 3] = start
    return m3d.Manifold.cylinder(length, radius, circular_segments=segments).transform(transform[:3, :4])


@generator("torus_knot")
def torus_knot(
    p: int, q: int, major_radius: float, minor_radius: float, tube_radius: float,
    samples: int = 180, sides: int = 16,
) -> trimesh.Trimesh:
    """Tube swept along a (p, q) torus knot: a closed, tightly curved rod.

    A tube only slightly wider than the cup is curved across (1 / tube_radius) and, differently,
    along its length (the knot's bends), which stretches the lip beyond its limit almost
    everywhere; strands passing nearby block approaches too. Raises ValueError where the tube
    would pass through itself (see `torus_knot_clearance`).
    """
    clearance = torus_knot_clearance(p, q, major_radius, minor_radius, tube_radius)
    if clearance <= 0.0:
        raise ValueError(f"torus knot tube of radius {tube_radius} intersects itself (clearance {clearance:.4g} m)")
    centres, normals = _torus_knot_curve(p, q, major_radius, minor_radius, samples)
    return sweep_tube(centres, normals, tube_radius, sides)


def _torus_knot_curve(p: int, q: int, major_radius: float, minor_radius: float, samples: int):
    """Points on the knot and a periodic normal: the direction away from the torus's core circle."""
    t = 2.0 * math.pi * np.arange(samples) / samples
    ring = major_radius + minor_radius * np.cos(q * t)
    centres = np.stack([ring * np.cos(p * t), ring * np.sin(p * t), minor_radius * np.sin(q * t)], axis=1)
    core = major_radius * np.stack([np.cos(p * t), np.sin(p * t), np.zeros_like(t)], axis=1)
    return centres, centres - core


def torus_knot_clearance(p: int, q: int, major_radius: float, minor_radius: float, tube_radius: float) -> float:
    """Smallest gap (m) between the knot tube's surface and itself; negative where it self-intersects.

    Two limits: strands of the knot that pass each other (points more than a tube diameter apart
    along the curve must be more than a tube diameter apart in space) and the tightest bend
    (the tube radius must stay below the curve's radius of curvature).
    """
    samples = 720
    centres, _ = _torus_knot_curve(p, q, major_radius, minor_radius, samples)
    step = np.linalg.norm(np.roll(centres, -1, axis=0) - centres, axis=1)
    arc = np.concatenate([[0.0], np.cumsum(step)[:-1]])
    along = np.abs(arc[:, None] - arc[None, :])
    along = np.minimum(along, step.sum() - along)
    gap = np.linalg.norm(centres[:, None] - centres[None, :], axis=2)
    far = along > math.pi * tube_radius  # beyond half a turn around the tube's own section
    strands = float(gap[far].min()) - 2.0 * tube_radius if far.any() else math.inf
    d1 = (np.roll(centres, -1, axis=0) - np.roll(centres, 1, axis=0)) / 2.0
    d2 = np.roll(centres, -1, axis=0) - 2.0 * centres + np.roll(centres, 1, axis=0)
    curvature = np.linalg.norm(np.cross(d1, d2), axis=1) / np.linalg.norm(d1, axis=1) ** 3
    bend = 1.0 / float(curvature.max()) - tube_radius
    return min(strands, bend)


# -- the Adversarial set -----------------------------------------------------------------------


def _adversarial(name: str, generator_name: str, description: str, **params) -> ObjectSpec:
    """A spec of the adversarial set: a PLA print at the default skin and infill (objects.mass.printed)."""
    return ObjectSpec(name=name, set="adversarial", generator=generator_name, params=params, description=description,
                      mass=printed())


ADVERSARIAL_SPECS: list[ObjectSpec] = [
    _adversarial(
        "twisted_star", "twisted_star",
        "five-point star prism twisted 120 degrees: seals only on thin bands of its warped flanks",
        points=5, outer_radius=0.038, inner_radius=0.0105, height=0.09, twist=2.094395,
    ),
    _adversarial(
        "ribbed_saddle", "ribbed_saddle",
        "saddle slab with a rib grid on both faces: seals only mid-cell",
        size=0.1, thickness=0.008, curvature=12.0, rib_spacing=0.025, rib_width=0.003, rib_height=0.004,
        edge=0.011,
    ),
    _adversarial(
        "narrow_gear", "gear",
        "20-tooth gear blank with needle-thin teeth and a bored hub: seals on a thin ring only",
        teeth=20, root_radius=0.03, tip_radius=0.04, tooth_width=0.004, thickness=0.01, hub_radius=0.0135,
        hub_height=0.02, bore_radius=0.0055,
    ),
    _adversarial(
        "knobby_blob", "knobby_blob",
        "sphere with 48 smooth knobs: seals only in the gaps between knobs",
        radius=0.032, bumps=48, bump_height=0.005, bump_width=0.1,
    ),
    _adversarial(
        "trefoil_tube", "torus_knot",
        "trefoil-knot tube 11.3 mm in radius: too tightly curved across for the lip (a 15 mm cup needs"
        " R >= ~13 mm), so it seals only where the knot bends it into a saddle",
        p=2, q=3, major_radius=0.035, minor_radius=0.015, tube_radius=0.0113, samples=180,
    ),
]
"""The 5 Adversarial objects: 3-6 % of surface-uniform grasps seal (Basic and Typical objects: ~20-85 %)."""
