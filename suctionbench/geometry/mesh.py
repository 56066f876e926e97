"""Mesh loading and validation: every mesh entering suctionbench passes through `load_mesh`.

Bad meshes are rejected with an `InputError` that names the file and the problem; meshes that are
usable but imperfect (not watertight) load with a warning, because the seal model's hole test
sees real holes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import trimesh

from suctionbench.errors import InputError

SUPPORTED_SUFFIXES = (".obj", ".stl", ".ply", ".off", ".glb", ".gltf")
"""File types suctionbench reads (through trimesh)."""

UNIT_SCALES = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
"""Metres per unit for the `units` argument."""

AUTO_UNITS = {".stl": ("m", "mm")}
"""The readings ``units="auto"`` (the default) tries in turn, per format; the first whose size is
plausible wins. An STL file carries no units, and two conventions write them: robotics packages
(ROS, URDF) metres, CAD and 3D printing millimetres. No size is plausible in both (5 mm - 1 m read
as metres is 0.005-1 unit, read as millimetres 5-1000 units), so the choice is never ambiguous.
Every other format is read as metres: glTF by its specification; OBJ, PLY and OFF have no
convention (Blender writes metres, Maya centimetres, 3ds Max inches), so a wrong size there is
rejected with the units it would fit, never guessed."""

MIN_EXTENT = 0.005
"""Smallest plausible object size (m): below this the units are almost certainly wrong."""

MAX_EXTENT = 1.0
"""Largest plausible object size (m) for a 15 mm suction cup on a tabletop."""


@dataclass
class MeshInfo:
    """A validated mesh in metres plus what validation noticed."""

    mesh: trimesh.Trimesh
    """The mesh, in metres."""

    source: str
    """Where it came from (path or a description), for messages."""

    watertight: bool
    """True when the surface is closed and consistently oriented (volume and centre of mass valid)."""

    warnings: list[str] = field(default_factory=list)
    """Non-fatal problems, one line each, naming the mesh."""

    units: str = "m"
    """The units the file was read in (``load_mesh`` resolves "auto" to one of `UNIT_SCALES`)."""

    @property
    def center_mass(self) -> np.ndarray:
        """Centre of mass for uniform density; the area-weighted centroid if not watertight."""
        if self.watertight:
            return np.asarray(self.mesh.center_mass, dtype=float)
        return np.asarray(self.mesh.centroid, dtype=float)


def resolve_units(path: str | Path, units: str, size: float) -> str:
    """The units a file whose largest extent is `size` file units (times any extra scale) is read
    in: `units` itself unless it is "auto" (see `AUTO_UNITS`); InputError naming the units that
    would fit where the size is implausible as read. `units` is lower case and valid."""
    candidates = AUTO_UNITS.get(Path(path).suffix.lower(), ("m",)) if units == "auto" else (units,)
    fits = [u for u in UNIT_SCALES if MIN_EXTENT <= size * UNIT_SCALES[u] <= MAX_EXTENT]
    for candidate in candidates:
        if candidate in fits:
            return candidate
    read = ", ".join(f"{size:.4g} {u} read in {u}" for u in candidates)
    hint = f"it fits read in {' or '.join(fits)}" if fits else "no unit (m, cm, mm, in) fits it"
    raise InputError(
        f"mesh '{path}': absurd scale (largest extent {read}; expected {MIN_EXTENT:g}-{MAX_EXTENT:g} m; "
        f"{hint}); pass the file's units (--units) or a scale factor (--scale)"
    )


def mesh_scale(units: str = "m", scale: float = 1.0) -> float:
    """Metres per file unit: the unit's length times an extra factor (a URDF ``scale``, say)."""
    if units.lower() not in UNIT_SCALES:
        raise InputError(f"units '{units}' is unknown (known: {', '.join(UNIT_SCALES)})")
    try:
        factor = float(scale)
    except (TypeError, ValueError):
        raise InputError(f"scale {scale!r}: not a number") from None
    if not (math.isfinite(factor) and factor > 0):
        raise InputError(f"scale {scale!r}: must be a positive, finite factor")
    return UNIT_SCALES[units.lower()] * factor


def read_mesh(path: str | Path) -> trimesh.Trimesh:
    """The triangles of a mesh file as written (no merging, no processing), or an InputError that
    names the file and its format: missing, unsupported, unreadable (garbage, truncated, a
    format trimesh cannot parse) or without triangles."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"mesh '{path}': file not found")
    if not path.is_file():
        raise InputError(f"mesh '{path}': not a regular file")
    kind = path.suffix.lower()
    if kind not in SUPPORTED_SUFFIXES:
        raise InputError(
            f"mesh '{path}': unsupported format '{path.suffix or '(none)'}' "
            f"(supported: {', '.join(SUPPORTED_SUFFIXES)})"
        )
    kind = kind[1:]
    try:
        # process=False: trimesh's processing silently drops NaN vertices; validate first.
        with np.errstate(all="ignore"):
            loaded = trimesh.load(str(path), force="mesh", process=False)
    except Exception as exc:  # trimesh raises many exception types for malformed files
        reason = " ".join(str(exc).split())[:120] or type(exc).__name__
        raise InputError(f"mesh '{path}': not a readable mesh (format {kind}: {reason})") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise InputError(f"mesh '{path}': not a readable mesh (format {kind}: no triangles in the file)")
    faces = np.asarray(loaded.faces)
    if faces.min() < 0 or faces.max() >= len(loaded.vertices):
        raise InputError(f"mesh '{path}': not a readable mesh (format {kind}: faces name missing vertices)")
    return loaded


def load_mesh(path: str | Path, units: str = "auto", scale: float = 1.0) -> MeshInfo:
    """Read a mesh file, convert it to metres (`units` times `scale`; "auto": see `AUTO_UNITS`) and
    validate it (see `validate_mesh`). The units it was read in are the result's `units`."""
    units = units.lower()
    mesh_scale("m" if units == "auto" else units, scale)  # bad units or scale fail before the file is read
    loaded = read_mesh(path)
    if not np.all(np.isfinite(loaded.vertices)):
        raise InputError(f"mesh '{path}': vertices contain NaN or infinite coordinates")
    loaded.process(validate=False)
    units = resolve_units(path, units, float(loaded.extents.max()) * scale)  # extents: referenced vertices only
    factor = mesh_scale(units, scale)
    if factor != 1.0:
        loaded.apply_scale(factor)
    info = validate_mesh(loaded, source=str(path))
    info.units = units
    return info


def validate_mesh(mesh: trimesh.Trimesh, source: str = "mesh") -> MeshInfo:
    """Check a mesh (in metres) for the problems that would make labels meaningless.

    Rejects: no faces, non-finite vertices, zero area, a flat or line-like shape (zero extent along
    some axis), sizes outside [MIN_EXTENT, MAX_EXTENT]. Warns: not watertight.
    """
    vertices = np.asarray(mesh.vertices)
    if len(mesh.faces) == 0 or len(vertices) == 0:
        raise InputError(f"mesh '{source}': empty (no faces)")
    if not np.all(np.isfinite(vertices)):
        raise InputError(f"mesh '{source}': vertices contain NaN or infinite coordinates")
    mesh = mesh.copy()
    mesh.merge_vertices()
    cleaned = mesh.copy()
    cleaned.update_faces(cleaned.nondegenerate_faces())
    cleaned.remove_unreferenced_vertices()
    if cleaned.is_watertight or not mesh.is_watertight:  # never open a closed mesh to drop slivers
        mesh = cleaned
    if len(mesh.faces) == 0 or mesh.area <= 0.0:
        raise InputError(f"mesh '{source}': degenerate (all faces have zero area)")
    extents = mesh.extents
    largest = float(extents.max())
    if float(extents.min()) <= 1e-9 * max(largest, 1e-12):
        raise InputError(f"mesh '{source}': degenerate (flat: zero extent along one axis)")
    if largest < MIN_EXTENT or largest > MAX_EXTENT:
        raise InputError(
            f"mesh '{source}': absurd scale (largest extent {largest:.4g} m, expected "
            f"{MIN_EXTENT:g}-{MAX_EXTENT:g} m); pass the file's units (mm, cm, m, in) or a scale factor"
        )
    watertight = bool(mesh.is_watertight and mesh.is_winding_consistent)
    warnings: list[str] = []
    if watertight:
        if mesh.volume < 0:
            mesh.invert()
        if mesh.volume <= 1e-15:
            raise InputError(f"mesh '{source}': degenerate (zero volume)")
    else:
        warnings.append(
            f"mesh '{source}' is not watertight: labels treat open edges as holes and the centre "
            "of mass is the surface centroid"
        )
    return MeshInfo(mesh=mesh, source=source, watertight=watertight, warnings=warnings)
