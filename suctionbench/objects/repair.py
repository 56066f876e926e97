"""Make one closed solid out of a mesh as third-party tools write it.

Meshes users bring are rarely the single closed, consistently oriented surface that mass
properties, stable poses and convex decomposition need, but most are one in disguise. `solidify`
undoes the usual disguises, in this order, and says what it did:

1. *Seams.* Textured OBJ/GLB loaders split a vertex wherever its UV or normal changes, so a closed
   surface looks open along every seam. Vertices are merged by position alone.
2. *Duplicated faces* (the same triangle written twice, same orientation) are removed.
3. *Non-manifold edges* (an edge of three or more faces). Where pieces touch along an edge or a
   face, the faces round the edge are paired by angle (each solid wedge from the face where it
   starts to the face where it ends), which separates the pieces again; an edge whose faces do not
   pair that way (a dangling fin, an inner wall) is cut, leaving its odd faces as open bodies.
4. *Bodies.* The faces fall into connected bodies; each is oriented outwards and small holes are
   closed (trimesh's triangle/quad fill, then a fan for any hole no wider than HOLE_FILL_MAX of
   the body). Bodies that stay open enclose no volume: if they are a small share of the surface
   (a label sleeve, a stray sheet, an inner wall) they are dropped, otherwise the mesh is rejected.
5. *Self-intersection.* A closed body whose surface passes through itself counts the overlap
   twice in its volume (and so mass and inertia); the generalised winding number at sample
   points finds it and the mesh is rejected.
6. *Pieces.* Several closed bodies (pieces that touch face to face, or overlap) are united with
   manifold3d; the result must be one body. Overlap would otherwise be counted twice in the volume.

Every rejection is an `InputError` naming the mesh and the defect class; every repair adds a note.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from suctionbench.errors import InputError

HOLE_FILL_MAX = 0.3
"""Holes (boundary loops) up to this share of their body's largest extent across are closed by a
fan; wider ones are real openings (a cup, a half shell) that no fill would restore faithfully."""

OPEN_DROP_MAX = 0.4
"""Open bodies beside a closed one are dropped when together they are at most this share of the
surface area; more than that is too much of the object to throw away."""

OVERLAP_NOTE = 1e-3
"""Pieces whose union is smaller than their summed volume by more than this share overlapped."""

SELF_INTERSECTION_SAMPLES = 512
"""Points at which the winding number of a closed body is evaluated (a jittered 8x8x8 grid)."""

SELF_INTERSECTION_MAX = 0.005
"""Share of a body's volume that may be counted twice (winding number 2, or -1) before it is rejected."""


@dataclass
class Solid:
    """A closed, outward-oriented, single-body mesh and what was done to get it."""

    mesh: trimesh.Trimesh
    notes: list[str] = field(default_factory=list)
    """One line per repair (what was wrong and what was done)."""


def merge_by_position(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """The mesh's triangles with vertices merged by position only (UVs and normals dropped)."""
    merged = trimesh.Trimesh(np.asarray(mesh.vertices), np.asarray(mesh.faces), process=False)
    merged.merge_vertices(merge_tex=True, merge_norm=True)
    merged.update_faces(merged.nondegenerate_faces())
    merged.remove_unreferenced_vertices()
    return merged


def _canonical(faces: np.ndarray) -> np.ndarray:
    """Faces rotated so that their smallest vertex index comes first (orientation kept)."""
    shift = np.argmin(faces, axis=1)
    rows = np.arange(len(faces))[:, None]
    return faces[rows, (shift[:, None] + np.arange(3)) % 3]


def remove_duplicate_faces(mesh: trimesh.Trimesh) -> int:
    """Drop repeated copies of a triangle with the same orientation; returns how many went.

    Copies with opposite orientation are kept: they are where two pieces touch face to face,
    which `bodies` separates and `solidify` unites.
    """
    _, first = np.unique(_canonical(np.asarray(mesh.faces)), axis=0, return_index=True)
    removed = len(mesh.faces) - len(first)
    if removed:
        keep = np.zeros(len(mesh.faces), dtype=bool)
        keep[first] = True
        mesh.update_faces(keep)
        mesh.remove_unreferenced_vertices()
    return removed


def _pair_around_edge(vertices: np.ndarray, faces: np.ndarray, edge: tuple[int, int], members: np.ndarray):
    """Pairs of faces (i, j) that bound one solid wedge round a non-manifold `edge`, or None.

    Faces round the edge are sorted by angle about it. A face holding the edge as u->v (u < v) has
    its outward normal towards increasing angle, so it ends a wedge of solid; a face holding v->u
    starts one. Each start pairs with the next face round, which must be an end. At equal angles
    (pieces touching face to face) ends sort first, so no wedge of zero thickness is made.
    """
    u, v = edge
    axis = vertices[v] - vertices[u]
    axis /= np.linalg.norm(axis)
    others = np.array([[w for w in faces[f] if w != u and w != v][0] for f in members])
    offsets = vertices[others] - vertices[u]
    offsets -= np.outer(offsets @ axis, axis)
    ref = offsets[0] / np.linalg.norm(offsets[0])
    angles = np.arctan2(offsets @ np.cross(axis, ref), offsets @ ref) % (2 * np.pi)
    angles = np.round(angles, 9) % np.round(2 * np.pi, 9)
    ends = np.array([any(faces[f, k] == u and faces[f, (k + 1) % 3] == v for k in range(3)) for f in members])
    if ends.sum() * 2 != len(members):
        return None
    order = np.lexsort((~ends, angles))  # by angle, ends before starts at equal angles
    pairs = []
    for k, position in enumerate(order):
        if not ends[position]:
            nxt = order[(k + 1) % len(order)]
            if not ends[nxt]:
                return None
            pairs.append((members[position], members[nxt]))
    return pairs


def bodies(mesh: trimesh.Trimesh) -> tuple[list[np.ndarray], int, int]:
    """Face indices of each body, the number of non-manifold edges, and how many of those were cut.

    Faces are joined across every edge they share with exactly one other face, and across a
    non-manifold edge only with the face they pair with (`_pair_around_edge`).
    """
    faces = np.asarray(mesh.faces)
    vertices = np.asarray(mesh.vertices, dtype=float)
    half = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    owner = np.repeat(np.arange(len(faces)), 3)
    keys = np.sort(half, axis=1)
    _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    order = np.argsort(inverse, kind="stable")
    starts = np.concatenate([[0], np.cumsum(counts)])
    manifold = np.flatnonzero(counts == 2)
    first, second = order[starts[manifold]], order[starts[manifold] + 1]
    links = [np.stack([owner[first], owner[second]], axis=1)]
    nonmanifold = np.flatnonzero(counts > 2)
    cut = 0
    for e in nonmanifold:
        members = owner[order[starts[e] : starts[e + 1]]]
        pairs = _pair_around_edge(vertices, faces, tuple(keys[order[starts[e]]]), members)
        if pairs is None:
            cut += 1
        else:
            links.append(np.array(pairs).reshape(-1, 2))
    link = np.concatenate(links)
    graph = coo_matrix((np.ones(len(link)), (link[:, 0], link[:, 1])), shape=(len(faces), len(faces)))
    n, labels = connected_components(graph, directed=False)
    groups = [np.flatnonzero(labels == i) for i in range(n)]
    return sorted(groups, key=len, reverse=True), len(nonmanifold), cut


def _boundary_loops(mesh: trimesh.Trimesh) -> list[list[int]] | None:
    """Vertex loops of the boundary (in the faces' direction), or None if a vertex is pinched."""
    half = np.asarray(mesh.faces)[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    single = trimesh.grouping.group_rows(np.sort(half, axis=1), require_count=1)
    following: dict[int, int] = {}
    for a, b in half[single]:
        if a in following:
            return None
        following[int(a)] = int(b)
    loops = []
    while following:
        start, loop = next(iter(following)), []
        vertex = start
        while vertex in following:
            loop.append(vertex)
            vertex = following.pop(vertex)
        if vertex != start:
            return None
        loops.append(loop)
    return loops


def close_holes(mesh: trimesh.Trimesh) -> tuple[trimesh.Trimesh, int, float]:
    """Close what holes can be closed: trimesh's fill (triangles, quads), then a fan from each
    remaining loop's centroid for loops no wider than HOLE_FILL_MAX of the body.

    Returns the mesh, the number of holes left open and the widest of those (m, 0 if none).
    """
    mesh = mesh.copy()
    trimesh.repair.fill_holes(mesh)
    if mesh.is_watertight:
        return mesh, 0, 0.0
    loops = _boundary_loops(mesh)
    if loops is None:
        return mesh, 1, float(mesh.extents.max())
    limit = HOLE_FILL_MAX * float(mesh.extents.max())
    vertices, faces = [np.asarray(mesh.vertices)], [np.asarray(mesh.faces)]
    count, left, widest = len(mesh.vertices), 0, 0.0
    for loop in loops:
        points = mesh.vertices[loop]
        width = float(np.ptp(points, axis=0).max())
        if width > limit or len(loop) < 3:
            left, widest = left + 1, max(widest, width)
            continue
        vertices.append(points.mean(axis=0, keepdims=True))
        nxt = np.roll(loop, -1)
        faces.append(np.stack([nxt, loop, np.full(len(loop), count)], axis=1))  # reversed: pairs with the rim
        count += 1
    filled = trimesh.Trimesh(np.vstack(vertices), np.vstack(faces), process=False)
    return filled, left, widest


def winding_numbers(mesh: trimesh.Trimesh, points: np.ndarray, chunk: int = 2_000_000) -> np.ndarray:
    """Generalised winding number of the closed surface at each point (van Oosterom-Strackee)."""
    triangles = np.asarray(mesh.triangles, dtype=float)
    out = np.zeros(len(points))
    step = max(1, chunk // max(len(triangles), 1))
    for s in range(0, len(points), step):
        rel = triangles[None, :, :, :] - points[s : s + step, None, None, :]
        a, b, c = rel[:, :, 0], rel[:, :, 1], rel[:, :, 2]
        la, lb, lc = (np.linalg.norm(x, axis=-1) for x in (a, b, c))
        det = np.einsum("pfi,pfi->pf", a, np.cross(b, c))
        den = la * lb * lc + np.einsum("pfi,pfi->pf", a, b) * lc
        den += np.einsum("pfi,pfi->pf", b, c) * la + np.einsum("pfi,pfi->pf", c, a) * lb
        out[s : s + step] = np.arctan2(det, den).sum(axis=1) / (2 * np.pi)
    return out


def doubled_share(mesh: trimesh.Trimesh) -> float:
    """How much a self-intersecting surface overstates its volume: the volume counted more than once
    (winding number 2, or -1 where the surface turns inside out) over the volume enclosed at all,
    both estimated at a jittered grid of SELF_INTERSECTION_SAMPLES points in the bounding box."""
    rng = np.random.default_rng(0)
    n = round(SELF_INTERSECTION_SAMPLES ** (1 / 3))
    lo, hi = mesh.bounds
    cells = np.stack(np.meshgrid(*[np.arange(n)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    points = lo + (cells + rng.uniform(size=cells.shape)) / n * (hi - lo)
    w = np.rint(winding_numbers(mesh, points))
    inside = np.count_nonzero(w != 0)
    return float(np.abs(w - np.clip(w, 0, 1)).sum()) / max(inside, 1)


def solidify(mesh: trimesh.Trimesh, source: str) -> Solid:
    """One closed solid from `mesh` (metres) or an InputError naming `source` and the defect.

    The notes say what was repaired, one line each, without the mesh's name."""
    notes: list[str] = []
    tag = f"mesh '{source}'"
    mesh = merge_by_position(mesh)
    duplicates = remove_duplicate_faces(mesh)
    if duplicates:
        notes.append(f"{duplicates} duplicated faces removed")
    if len(mesh.faces) == 0:
        raise InputError(f"{tag}: degenerate (all faces have zero area)")
    groups, nonmanifold, cut = bodies(mesh)
    if nonmanifold:
        how = f"{cut} cut where faces dangle or walls sit inside" if cut else "pieces separated where they touch"
        notes.append(f"{nonmanifold} non-manifold edges (3 or more faces on an edge): {how}")
    closed, open_parts = [], []
    for group in groups:
        body = trimesh.Trimesh(mesh.vertices, mesh.faces[group], process=False)
        body.remove_unreferenced_vertices()
        trimesh.repair.fix_winding(body)
        holes, widest = 0, 0.0
        if not body.is_watertight:
            filled, holes, widest = close_holes(body)
            if holes == 0:
                trimesh.repair.fix_winding(filled)
                notes.append(f"{_count(_boundary_loops(body), 'small hole')} closed")
                body = filled
        volume = float(body.volume) if body.is_watertight and body.is_winding_consistent else 0.0
        scale = float(np.prod(np.maximum(body.extents, 1e-12)))
        if abs(volume) <= 1e-9 * scale:
            open_parts.append((body, holes, widest))
            continue
        if volume < 0:
            body.invert()
        closed.append(body)
    if open_parts:
        area = sum(float(b.area) for b, _, _ in open_parts)
        share = area / (area + sum(float(b.area) for b in closed))
        faces = sum(len(b.faces) for b, _, _ in open_parts)
        if not closed:
            body, holes, widest = max(open_parts, key=lambda p: p[0].area)
            if cut and not holes:
                raise InputError(f"{tag}: {cut} non-manifold edges (3 or more faces on an edge) leave no closed body")
            raise InputError(
                f"{tag}: not watertight: {_count(holes, 'hole')} up to {widest * 1000:.3g} mm across could not be "
                f"closed (holes wider than {HOLE_FILL_MAX:.0%} of the object are openings, not defects)"
            )
        if share > OPEN_DROP_MAX:
            raise InputError(
                f"{tag}: {_count(len(open_parts), 'open body', 'open bodies')} ({faces} faces, {share:.0%} of the "
                f"surface) beside {_count(len(closed), 'closed body', 'closed bodies')}: close or remove "
                f"{'it' if len(open_parts) == 1 else 'them'}"
            )
        notes.append(
            f"{_count(len(open_parts), 'open body', 'open bodies')} dropped ({faces} faces, "
            f"{share:.1%} of the surface: sheets or inner faces that enclose no volume)"
        )
    for i, body in enumerate(closed):
        doubled = doubled_share(body)
        if doubled > SELF_INTERSECTION_MAX:
            which = f" (body {i + 1} of {len(closed)})" if len(closed) > 1 else ""
            raise InputError(
                f"{tag}: self-intersecting surface{which}: it encloses about {doubled:.0%} of its volume twice "
                "(or inside out), so volume, mass and inertia would be wrong"
            )
    if len(closed) == 1:
        return Solid(closed[0], notes)
    summed = sum(float(b.volume) for b in closed)
    united = trimesh.boolean.union(closed, engine="manifold")
    pieces = len(united.split(only_watertight=False)) if len(united.faces) else 0
    if pieces != 1:
        raise InputError(f"{tag}: {pieces} disconnected bodies (pieces that neither touch nor overlap), expected one")
    if float(united.volume) < (1 - OVERLAP_NOTE) * summed:
        notes.append(
            f"{len(closed)} pieces overlap: united (volume {united.volume * 1e6:.4g} cm^3 instead of "
            f"{summed * 1e6:.4g} cm^3 counted twice)"
        )
    else:
        notes.append(f"{len(closed)} pieces that touch face to face united into one body")
    return Solid(united, notes)


def _count(n: int | list | None, singular: str, plural: str | None = None) -> str:
    n = len(n) if isinstance(n, list) else int(n or 0)
    return f"{n} {singular if n == 1 else (plural or singular + 's')}"
