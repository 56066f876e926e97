"""Generalised winding numbers of a surface, and the solid a cracked surface bounds.

The winding number of a closed, outward surface is 1 inside and 0 outside; across small cracks
and T-junctions between patches that do not meet it stays near those values (Jacobson, Kavan and
Sorkine-Hornung, "Robust inside-outside segmentation using generalized winding numbers",
SIGGRAPH 2013). `objects.repair` reads it twice: to find volume a self-intersecting surface counts
twice, and to rebuild a render mesh whose patches do not meet as the solid they bound
(`rebuild_from_winding`). Both sums come from libigl (the exact one, and Barill et al.'s fast
one, SIGGRAPH 2018).
"""

from __future__ import annotations

import numpy as np
import trimesh

WINDING_GRID = 96
"""Cells of the winding-number grid along the object's largest extent (a crack rebuild resolves
about 1 % of the object; its vertices are then snapped back onto the original surface)."""

AMBIGUOUS_MAX = 0.15
"""Largest share of the rebuilt volume where the winding number is between 1/4 and 3/4 (the volume,
and so the mass, any threshold in that range could add or remove); more is an opening, not a crack.
Measured (eval/import/README.md): 0-1.3 % for most cracked render meshes and links without a joint
face, 6-11 % for a hand shell and links with inner patches, over 100 % for a shell open on one side."""


def winding_numbers(mesh: trimesh.Trimesh, points: np.ndarray) -> np.ndarray:
    """Generalised winding number of the surface at each point, exact (libigl's sum of the triangles'
    signed solid angles, van Oosterom-Strackee)."""
    import igl

    return igl.winding_number(np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int64),
                              np.asarray(points, dtype=float))


def rebuild_from_winding(mesh: trimesh.Trimesh) -> tuple[trimesh.Trimesh | None, float]:
    """The solid a cracked surface bounds (`objects.repair`'s docstring, step 7) and the share of its volume the
    surface leaves ambiguous; (None, share) where that share is over AMBIGUOUS_MAX or nothing is
    inside.

    The faces keep the orientation they were written with (a surface turned inwards throughout is
    read the other way round). The 1/2 level set of the winding number on a grid of WINDING_GRID
    cells along the largest extent is triangulated by marching cubes; each of its vertices then
    moves to the nearest point of the original surface where that point is within one cell and
    faces the same way (normals within 45 deg), so flat faces come back flat and inner walls or
    stray sheets do not pull the surface in."""
    import igl

    vertices, faces = np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int64)
    lo, hi = mesh.bounds
    cell = float((hi - lo).max()) / WINDING_GRID
    lo = lo - 2.382 * cell  # a grid plane on a face (the bounds' own) would put 1/2 exactly at its points
    counts = (np.ceil((hi + 2.0 * cell - lo) / cell).astype(int) + 1).tolist()
    z, y, x = np.meshgrid(*[lo[i] + cell * np.arange(counts[i]) for i in (2, 1, 0)], indexing="ij")
    grid = np.column_stack([x.ravel(), y.ravel(), z.ravel()])  # x fastest: marching_cubes' order
    # the exact sum costs (points x faces), the fast one (points x log faces) with a large constant:
    # equal at about 400 faces (measured on 2 cores, 0.9 M points: 0.9 s exact at 128 faces, 2.9 s fast)
    winding = (igl.winding_number if len(faces) <= 400 else igl.fast_winding_number)(vertices, faces, grid)
    sign = 1.0 if winding[np.abs(winding) > 0.5].sum() >= 0 else -1.0
    winding = sign * winding
    inside = np.count_nonzero(winding > 0.5)
    ambiguous = np.count_nonzero((winding > 0.25) & (winding < 0.75)) / max(inside, 1)
    if inside == 0 or ambiguous > AMBIGUOUS_MAX:
        return None, ambiguous
    level_v, level_f, _ = igl.marching_cubes(winding, grid, *counts, 0.5)
    rebuilt = trimesh.Trimesh(level_v, level_f, process=True)
    if rebuilt.volume < 0:
        rebuilt.invert()
    distance_sq, nearest_face, nearest = igl.point_mesh_squared_distance(np.asarray(rebuilt.vertices), vertices, faces)
    normals = sign * np.asarray(mesh.face_normals)[nearest_face]
    agree = np.einsum("ij,ij->i", normals, np.asarray(rebuilt.vertex_normals)) > np.cos(np.pi / 4)
    move = (distance_sq <= cell**2) & agree
    level = np.asarray(rebuilt.vertices)
    triangles = np.asarray(rebuilt.faces)
    before = np.cross(*(level[triangles[:, k]] - level[triangles[:, 0]] for k in (1, 2)))
    while True:  # a vertex stays put where its move would collapse or fold a face (at sharp edges)
        snapped = np.where(move[:, None], nearest, level)
        after = np.cross(*(snapped[triangles[:, k]] - snapped[triangles[:, 0]] for k in (1, 2)))
        bad = (np.linalg.norm(after, axis=1) <= 1e-6 * cell**2) | (np.einsum("ij,ij->i", after, before) <= 0)
        if not move[triangles[bad]].any():
            break
        move[triangles[bad].ravel()] = False
    return trimesh.Trimesh(snapped, triangles, process=False), ambiguous
