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
   A closed body written inside out (facing inwards) within another is a sealed *cavity* the author
   modelled (a closed bottle with its wall, a housing): it is kept apart, not turned outwards and
   united (which would fill it and overstate the mass by the cavity's share), and the solid is the
   outer surface with the cavity's material taken out of its mass (`Solid.cavities`).
5. *Self-intersection.* A closed body whose surface passes through itself counts the overlap
   twice in its volume (and so mass and inertia); the generalised winding number at sample
   points finds it and the mesh is rejected.
6. *Pieces.* Several closed bodies (pieces that touch face to face, or overlap) are united with
   manifold3d; overlap would otherwise be counted twice in the volume. Pieces left apart by a gap
   that a made part could close (`assembly_clearance`: twice the ISO 2768-m general tolerance at
   the object's size, e.g. 0.6 mm at 30-120 mm; V-HACD decompositions leave micrometres, CAD
   assemblies drawn clearances) are snapped across it and united; sealed voids the union encloses
   between overlapping pieces are filled up to LOOSE_MAX of the volume (more is kept hollow, as the
   pieces leave it, like a cavity modelled facing inwards); loose crumbs of at most LOOSE_MAX of the
   volume are dropped. Pieces further apart that hold more are kept, apart, as one rigid body
   (ASSEMBLY), with a warning: a mesh file is one object as its author meant it, and a robot link's
   parts (a board on its standoffs, a bicycle's pedal parts) are fastened by screws and brackets its
   mesh does not draw, one rigid body in MuJoCo, Drake or pybullet as here; a cup sealing on one
   piece lifts them all.
7. *Cracks.* Render meshes are often patches that do not meet (cracks and T-junctions between
   them, no shared vertices), or solids with a face the exporter left out. Where steps 3-4 leave
   no closed body, or too much open surface to drop, the solid the surface bounds is rebuilt from
   its generalised winding number (Jacobson, Kavan and Sorkine-Hornung, "Robust inside-outside
   segmentation using generalized winding numbers", SIGGRAPH 2013), which is 1 inside and 0
   outside a closed surface and stays near them across small cracks: the number is evaluated on a
   grid (libigl's fast winding number, Barill et al., SIGGRAPH 2018), the 1/2 level set is
   triangulated (marching cubes) and its vertices are snapped back onto the original surface. A
   surface that does not decide inside from outside (a cup's opening, a lone sheet: the number
   between 1/4 and 3/4 over more than AMBIGUOUS_MAX of the volume) is rejected as before
   (`objects.winding`).
8. *Pinches.* Where united pieces touch only along an edge, the result holds two vertices at one
   position; they are moved apart by 1e-5 of the object's size so that readers that merge vertices
   by position (validation, MuJoCo, STL) still see a closed surface.

Every rejection is an `InputError` naming the mesh and the defect class; every repair adds a note.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from suctionbench.errors import InputError
from suctionbench.objects.winding import AMBIGUOUS_MAX, WINDING_GRID, rebuild_from_winding, winding_numbers

HOLE_FILL_MAX = 0.3
"""Holes (boundary loops) up to this share of their body's largest extent across are closed by a
fan; wider ones are real openings (a cup, a half shell) that no fill would restore faithfully."""

OPEN_DROP_MAX = 0.4
"""Open bodies beside a closed one are dropped when together they are at most this share of the
surface area; more than that is too much of the object to throw away."""

OVERLAP_NOTE = 1e-3
"""Pieces whose union is smaller than their summed volume by more than this share overlapped."""

GAP_MAX = 1e-3
"""Closed pieces whose surfaces are at most this share of the object's largest extent apart are
always joined (the gap bridged): convex decompositions (V-HACD) and CAD exports leave micrometre
gaps between pieces meant to touch (`assembly_clearance` joins wider ones, drawn clearances)."""

GENERAL_TOLERANCE = ((0.006, 1e-4), (0.030, 2e-4), (0.120, 3e-4), (0.400, 5e-4), (1.0, 8e-4), (2.0, 1.2e-3),
                     (4.0, 2e-3))
"""ISO 2768-1 general tolerances for linear dimensions, class m ("medium", the class most drawings
state, as "ISO 2768-mK"): (nominal size up to, m; permitted deviation +-, m). A made part may lie
this far from its drawing without any tolerance written on it."""


def assembly_clearance(size: float) -> float:
    """Widest gap (m) between two pieces of an object of largest extent `size` that are joined as
    touching: each of the two facing surfaces may sit its ISO 2768-m general tolerance at that size
    towards the other (`GENERAL_TOLERANCE`), so in a made part a nominal gap up to twice it can be
    closed: a CAD assembly's parts drawn with clearance (a board on its heat sink, a plate on its
    frame), one rigid link. Never below GAP_MAX of the size (numerical gaps)."""
    deviation = next((t for upto, t in GENERAL_TOLERANCE if size <= upto), GENERAL_TOLERANCE[-1][1])
    return max(2.0 * deviation, GAP_MAX * size)


LOOSE_MAX = 0.01
"""Pieces apart from the main body that together hold at most this share of the volume are dropped
as crumbs (a scan's specks, stray bits); more is a second object and the mesh is rejected."""

SELF_INTERSECTION_SAMPLES = 512
"""Points at which the winding number of a closed body is evaluated (a jittered 8x8x8 grid)."""

SELF_INTERSECTION_MAX = 0.005
"""Share of the object's volume that one closed body may count twice (winding number 2, or -1) before
the mesh is rejected."""


@dataclass
class Solid:
    """A closed, outward-oriented, single-body mesh and what was done to get it."""

    mesh: trimesh.Trimesh
    notes: list[str] = field(default_factory=list)
    """One line per repair (what was wrong and what was done)."""
    warnings: list[str] = field(default_factory=list)
    """What the user should know about the solid that is not a repair (it is kept as a rigid
    assembly of separate pieces, say)."""
    cavities: trimesh.Trimesh | None = None
    """Sealed cavities inside `mesh` as the mesh modelled them (closed surfaces facing inwards, so
    their volume is negative), or None. The object's surface, collision and grasps are `mesh`'s;
    its mass and inertia are those of `mesh` with the cavities taken out (`objects.build.build_object`)."""


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


def solidify(mesh: trimesh.Trimesh, source: str, rebuild: bool = True) -> Solid:
    """One closed solid from `mesh` (metres) or an InputError naming `source` and the defect.

    The notes say what was repaired, one line each, without the mesh's name. With `rebuild`, a
    surface that leaves no closed body, or too much open surface beside one, is rebuilt from its
    winding number (module docstring, step 7) before it is rejected."""
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
    closed, open_parts, inward = [], [], []
    holes_closed = 0
    scale = float(np.prod(np.maximum(mesh.extents, 1e-12)))  # the object's box: what "no volume" is relative to
    for group in groups:
        body = trimesh.Trimesh(mesh.vertices, mesh.faces[group], process=False)
        body.remove_unreferenced_vertices()
        trimesh.repair.fix_winding(body)
        holes, widest = 0, 0.0
        if not body.is_watertight:
            filled, holes, widest = close_holes(body)
            if holes == 0:
                trimesh.repair.fix_winding(filled)
                holes_closed += len(_boundary_loops(body) or [None])
                body = filled
        volume = float(body.volume) if body.is_watertight and body.is_winding_consistent else 0.0
        if abs(volume) <= 1e-9 * scale:  # encloses nothing (a flat pair of back-to-back faces, a sheet)
            open_parts.append((body, holes, widest))
            continue
        if volume < 0:
            body.invert()
        closed.append(body)
        inward.append(volume < 0)
    if holes_closed:
        notes.append(f"{_count(holes_closed, 'small hole')} closed")
    if open_parts:
        area = sum(float(b.area) for b, _, _ in open_parts)
        share = area / (area + sum(float(b.area) for b in closed))
        faces = sum(len(b.faces) for b, _, _ in open_parts)
        if not closed or share > OPEN_DROP_MAX:
            rebuilt, ambiguous = rebuild_from_winding(mesh) if rebuild else (None, None)
            undecided = (f"; its winding number leaves {ambiguous:.0%} of the volume undecided (at most "
                         f"{AMBIGUOUS_MAX:.0%} is rebuilt)") if ambiguous is not None else ""
            if rebuilt is not None:
                try:
                    solid = solidify(rebuilt, source, rebuild=False)
                except InputError as exc:
                    reason = str(exc).removeprefix(f"{tag}: ")
                    undecided = f"; rebuilt from its winding number it is still no solid ({reason})"
                else:
                    what = "no closed body" if not closed else f"{share:.0%} of the surface open"
                    note = (f"{what} (patches that do not meet): rebuilt as the solid the surface bounds "
                            f"(generalised winding number, {WINDING_GRID} cells across; {ambiguous:.1%} of the "
                            f"volume ambiguous)")
                    return Solid(solid.mesh, [note, *solid.notes], solid.warnings, solid.cavities)
        if not closed:
            body, holes, widest = max(open_parts, key=lambda p: p[0].area)
            if cut and not holes:
                raise InputError(f"{tag}: {cut} non-manifold edges (3 or more faces on an edge) leave no closed "
                                 f"body{undecided}")
            raise InputError(
                f"{tag}: not watertight: {_count(holes, 'hole')} up to {widest * 1000:.3g} mm across could not be "
                f"closed (holes wider than {HOLE_FILL_MAX:.0%} of the object are openings, not defects){undecided}"
            )
        if share > OPEN_DROP_MAX:
            raise InputError(
                f"{tag}: {_count(len(open_parts), 'open body', 'open bodies')} ({faces} faces, {share:.0%} of the "
                f"surface) beside {_count(len(closed), 'closed body', 'closed bodies')}: close or remove "
                f"{'it' if len(open_parts) == 1 else 'them'}{undecided}"
            )
        notes.append(
            f"{_count(len(open_parts), 'open body', 'open bodies')} dropped ({faces} faces, "
            f"{share:.1%} of the surface: sheets or inner faces that enclose no volume)"
        )
    closed, cavities = _separate_cavities(closed, inward)
    total = sum(float(body.volume) for body in closed)
    for i, body in enumerate(closed):
        # what counts is the volume counted twice as a share of the object's: a sliver body of a
        # billionth of it is no error in mass or inertia, whatever share of itself it doubles
        doubled = doubled_share(body) * float(body.volume) / total
        if doubled > SELF_INTERSECTION_MAX:
            which = f" (body {i + 1} of {len(closed)})" if len(closed) > 1 else ""
            raise InputError(
                f"{tag}: self-intersecting surface{which}: it encloses about {doubled:.0%} of the object's volume "
                "twice (or inside out), so volume, mass and inertia would be wrong"
            )
    solid = Solid(unpinch(closed[0]), notes) if len(closed) == 1 else _unite(closed, notes, tag)
    if cavities:
        hollow = -sum(_volume(c) for c in cavities)
        solid.cavities = trimesh.util.concatenate(cavities if solid.cavities is None else [solid.cavities, *cavities])
        solid.notes.append(
            f"{_count(len(cavities), 'sealed cavity', 'sealed cavities')} modelled inside "
            f"({hollow / _volume(solid.mesh):.2%} of the volume within the outer surface): kept hollow, "
            "no material there in the mass")
    return solid


def _separate_cavities(closed: list[trimesh.Trimesh], inward: list[bool]) -> tuple[list[trimesh.Trimesh], list]:
    """(solid bodies, cavities): a body the mesh wrote facing inwards that lies inside a body facing
    outwards (every vertex of a sample of up to 64 spread over it inside) is a cavity, returned facing
    inwards again (negative volume); every other body is solid (one facing inwards on its own is a
    solid written inside out; one that crosses the outer surface is no cavity)."""
    outward = [b for b, flipped in zip(closed, inward, strict=True) if not flipped]
    bodies, cavities = [], []
    for body, flipped in zip(closed, inward, strict=True):
        points = np.asarray(body.vertices[:: max(1, len(body.vertices) // 32)])
        if flipped and any(_volume(o) > _volume(body) and bool((winding_numbers(o, points) > 0.5).all())
                           for o in outward):
            cavity = body.copy()
            cavity.invert()
            cavities.append(cavity)
        else:
            bodies.append(body)
    return bodies, cavities


def _volume(mesh: trimesh.Trimesh) -> float:
    with np.errstate(all="ignore"):
        return float(mesh.volume) if len(mesh.faces) else 0.0


def _pieces(mesh: trimesh.Trimesh) -> list[trimesh.Trimesh]:
    """The closed pieces of a union's result, largest first: each outer surface with the surfaces of
    the cavities inside it (they come out of a split as pieces of negative volume), without the
    zero-volume slivers that boolean operations leave where surfaces coincide (they enclose nothing)."""
    if len(mesh.faces) == 0:
        return []
    parts = mesh.split(only_watertight=False)
    floor = 1e-9 * float(np.prod(np.maximum(mesh.extents, 1e-12)))
    outer = [p for p in parts if _volume(p) > floor]
    cavities = [p for p in parts if _volume(p) < -floor]
    members: list[list[trimesh.Trimesh]] = [[p] for p in outer]
    for cavity in cavities:
        point = np.asarray(cavity.vertices[:1])
        owners = [i for i, p in enumerate(outer) if winding_numbers(p, point)[0] > 0.5]
        if owners:  # the innermost (smallest) outer surface round it
            members[min(owners, key=lambda i: _volume(outer[i]))].append(cavity)
    pieces = [trimesh.util.concatenate(group) if len(group) > 1 else group[0] for group in members]
    return sorted(pieces, key=_volume, reverse=True)


def unpinch(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """The closed mesh with vertices that sit at the same position but belong to different sheets of
    the surface (where two pieces of a union touch along an edge, or a filled hole meets itself)
    moved apart into their own sheets, the k-th copy of a position by k x 1e-5 of the object's size,
    so that merging vertices by position (as every later reader does) does not turn the touching
    edge into a non-manifold one."""
    vertices = np.asarray(mesh.vertices, dtype=float)
    step = 1e-5 * float(mesh.extents.max())
    neighbours = None
    for _ in range(3):
        _, inverse = trimesh.grouping.unique_rows(vertices, digits=8)[0:2]
        order = np.argsort(inverse, kind="stable")
        counts = np.bincount(inverse)
        if counts.max() == 1:
            break
        neighbours = neighbours or mesh.vertex_neighbors
        rank = np.empty(len(vertices), dtype=int)
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        rank[order] = np.arange(len(vertices)) - np.repeat(starts, counts)
        moved = vertices.copy()
        for v in np.flatnonzero(counts[inverse] > 1):
            ring = vertices[neighbours[v]].mean(axis=0) - vertices[v]
            length = np.linalg.norm(ring)
            if length > 0:
                moved[v] += (rank[v] + 1) * step * ring / length
        vertices = moved
    if np.array_equal(vertices, mesh.vertices):
        return mesh
    return trimesh.Trimesh(vertices, np.asarray(mesh.faces), process=False)


def _nearest_on_surface(mesh: trimesh.Trimesh, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Squared distance, face index and closest point on `mesh`'s surface of each point: libigl's
    AABB tree, O(log faces) time and constant memory per point (see `gap`)."""
    import igl

    return igl.point_mesh_squared_distance(np.asarray(points, dtype=float), np.asarray(mesh.vertices, dtype=float),
                                           np.asarray(mesh.faces, dtype=np.int64))


def gap(a: trimesh.Trimesh, b: trimesh.Trimesh, limit: float) -> float:
    """Distance between the surfaces of `a` and `b` (closest vertex of either to the other's
    surface), or inf where their bounding boxes are more than `limit` apart.

    libigl's AABB tree answers each point in O(log faces) time and O(1) memory; trimesh's
    `closest_point` gathers every triangle whose box is near a point at once, 6.9 GB for the
    100 k vertices of a 86 k-face render mesh against another piece (a process the kernel kills,
    with no error line)."""
    if np.any(a.bounds[0] > b.bounds[1] + limit) or np.any(b.bounds[0] > a.bounds[1] + limit):
        return np.inf
    near = []
    for x, y in ((a, b), (b, a)):
        points = np.asarray(x.vertices)
        inside = np.all((points >= y.bounds[0] - limit) & (points <= y.bounds[1] + limit), axis=1)
        if inside.any():
            near.append(float(np.sqrt(_nearest_on_surface(y, points[inside])[0].min())))
    return float(min(near)) if near else np.inf


def _snap(a: trimesh.Trimesh, b: trimesh.Trimesh, tolerance: float, depth: float) -> trimesh.Trimesh:
    """`a` with each vertex within `tolerance` of `b`'s surface moved across the gap onto `b` and
    `depth` into it, so that the two overlap and a union joins them."""
    points = np.asarray(a.vertices, dtype=float).copy()
    inside = np.all((points >= b.bounds[0] - tolerance) & (points <= b.bounds[1] + tolerance), axis=1)
    idx = np.flatnonzero(inside)
    if len(idx) == 0:
        return a
    squared, triangle, closest = _nearest_on_surface(b, points[idx])
    distance = np.sqrt(squared)
    near = distance <= tolerance
    idx, closest, distance, triangle = idx[near], closest[near], distance[near], triangle[near]
    direction = -np.asarray(b.face_normals)[triangle]  # into b
    points[idx] = closest + depth * direction
    return trimesh.Trimesh(points, np.asarray(a.faces), process=False)


def _union(bodies: list[trimesh.Trimesh], tag: str) -> trimesh.Trimesh:
    """manifold3d's union of closed bodies; an InputError where it refuses one as not a volume."""
    try:
        return trimesh.boolean.union(bodies, engine="manifold")
    except ValueError as exc:  # manifold3d: "Not all meshes are volumes!"
        raise InputError(
            f"{tag}: pieces that are closed but not manifold volumes (an edge used twice in one direction, "
            f"or a surface pinched at a point) cannot be united ({exc})"
        ) from None


def _fill_voids(piece: trimesh.Trimesh, notes: list[str]) -> tuple[trimesh.Trimesh, trimesh.Trimesh | None]:
    """(`piece`'s outer surface, the sealed voids inside it kept hollow or None). Uniting overlapping
    pieces can enclose voids no piece covers: up to LOOSE_MAX of the volume they are filled
    (slivers of numerical union, or gaps the pieces were meant to close); larger ones are what the
    pieces describe, space no piece holds, and are kept hollow as cavities (`Solid.cavities`):
    the mass leaves them out, the surface is the outer one."""
    parts = piece.split(only_watertight=False)
    if len(parts) == 1:
        return piece, None
    outer = max(parts, key=_volume)
    voids = [p for p in parts if p is not outer]
    share = -sum(_volume(p) for p in voids) / _volume(outer)
    if share <= LOOSE_MAX:
        notes.append(f"{_count(len(voids), 'sealed void')} between united pieces filled ({share:.2%} of the volume)")
        return outer, None
    notes.append(
        f"{_count(len(voids), 'sealed void')} between united pieces ({share:.1%} of the volume within the outer "
        "surface): kept hollow, as the pieces leave them (no material there in the mass; give --mass if the "
        "object is solid there)")
    return outer, trimesh.util.concatenate(voids)


def _unite(closed: list[trimesh.Trimesh], notes: list[str], tag: str) -> Solid:
    """Unite closed bodies (pieces that touch, overlap, or lie within `assembly_clearance` of each
    other) into one; loose pieces of at most LOOSE_MAX of the volume are dropped; anything else is
    an InputError."""
    summed = sum(_volume(b) for b in closed)
    pieces = _pieces(_union(closed, tag))
    merged = len(pieces) < len(closed)  # some touched or overlapped
    if not pieces:
        raise InputError(f"{tag}: its closed bodies unite into nothing (degenerate)")
    size = max(float(np.ptp(np.vstack([p.vertices for p in pieces]), axis=0).max()), 1e-12)
    tolerance = assembly_clearance(size)
    depth = 0.5 * GAP_MAX * size  # how far a snapped vertex reaches into the other piece
    gaps = []
    if len(pieces) > 1:
        n = len(pieces)
        links = [(i, j, gap(pieces[i], pieces[j], tolerance)) for i in range(n) for j in range(i + 1, n)]
        near = [(i, j, d) for i, j, d in links if d <= tolerance]
        if near:
            graph = coo_matrix((np.ones(len(near)), ([i for i, _, _ in near], [j for _, j, _ in near])), shape=(n, n))
            _, labels = connected_components(graph, directed=False)
            snapped = list(pieces)
            for i, j, d in near:
                snapped[j] = _snap(snapped[j], pieces[i], tolerance, depth)
                snapped[i] = _snap(snapped[i], pieces[j], tolerance, depth)
                gaps.append(d)
            groups = [np.flatnonzero(labels == k) for k in np.unique(labels)]
            joined = []
            for group in groups:
                if len(group) == 1:
                    joined.append(pieces[group[0]])
                    continue
                # a sliver thinner than the snap turns inside out: it stays as it was (and, apart, a crumb)
                members = [snapped[k] if snapped[k].is_volume else pieces[k] for k in group]
                united = _pieces(_union(members, tag))
                joined.extend(united)
            pieces = sorted(joined, key=_volume, reverse=True)
    loose, warnings = [], []
    if len(pieces) > 1:
        total = sum(_volume(p) for p in pieces)
        share = sum(_volume(p) for p in pieces[1:]) / total
        if share <= LOOSE_MAX:
            loose, pieces = pieces[1:], pieces[:1]
        else:
            warnings.append(_assembly_warning(pieces, tolerance))
    filled = [_fill_voids(p, notes) for p in pieces]
    united = trimesh.util.concatenate([f for f, _ in filled]) if len(filled) > 1 else filled[0][0]
    hollow = [v for _, v in filled if v is not None]
    voids = trimesh.util.concatenate(hollow) if hollow else None
    if gaps:
        notes.append(
            f"{_count(len(gaps), 'gap')} of up to {max(gaps) * 1000:.2g} mm between pieces closed "
            f"(up to {tolerance * 1000:.2g} mm, twice the ISO 2768-m general tolerance at this size, pieces "
            "meant to touch: numerical gaps of convex decompositions, clearances of CAD assemblies)"
        )
    if float(united.volume) < (1 - OVERLAP_NOTE) * (summed - sum(_volume(p) for p in loose)):
        notes.append(
            f"{len(closed)} pieces overlap: united (volume {united.volume * 1e6:.4g} cm^3 instead of "
            f"{summed * 1e6:.4g} cm^3 counted twice)"
        )
    elif merged and not gaps:
        into = "one body" if len(pieces) == 1 else f"{len(pieces)} bodies"
        notes.append(f"{len(closed)} pieces that touch face to face united into {into}")
    if loose:
        dropped = sum(_volume(p) for p in loose)
        notes.append(
            f"{_count(len(loose), 'loose piece')} dropped ({dropped / (_volume(united) + dropped):.2%} "
            f"of the volume, apart from the body: crumbs, not part of the object)"
        )
    return Solid(unpinch(united), notes, warnings, voids)


def _assembly_warning(pieces: list[trimesh.Trimesh], tolerance: float) -> str:
    """The warning for pieces kept apart as one rigid body (ASSEMBLY in the module docstring)."""
    apart = min(gap(pieces[0], p, np.inf) for p in pieces[1:])
    return (
        f"{len(pieces)} separate pieces (the nearest {apart * 1000:.3g} mm from the largest, beyond the "
        f"{tolerance * 1000:.2g} mm a made part this size closes) kept as one rigid body, as a robot link's parts "
        "are fastened by what its mesh does not draw: a grasp on one lifts them all; to import them as separate "
        "objects, split the file"
    )


def _count(n: int | list | None, singular: str, plural: str | None = None) -> str:
    n = len(n) if isinstance(n, list) else int(n or 0)
    return f"{n} {singular if n == 1 else (plural or singular + 's')}"
