"""Small deterministic shape generators used by the demo, the benchmarks and the tests."""

from __future__ import annotations

import numpy as np
import trimesh


def superellipsoid(
    extents: tuple[float, float, float], exponent: float = 0.3, count: int = 72
) -> trimesh.Trimesh:
    """A rounded box: the unit sphere mapped by x -> a sign(x) |x|^e per axis (watertight).

    exponent 1 gives an ellipsoid, towards 0 a box with ever sharper edges; `count` sets the
    tessellation (about 2 count^2 faces).
    """
    sphere = trimesh.creation.uv_sphere(radius=1.0, count=[count, count])
    v = np.asarray(sphere.vertices)
    half = np.asarray(extents, dtype=float) / 2.0
    mapped = half * np.sign(v) * np.abs(v) ** exponent
    mesh = trimesh.Trimesh(mapped, sphere.faces, process=True)
    mesh.fix_normals()
    return mesh
