"""Import a user's own mesh (OBJ / STL / PLY / GLB ...) as an object: validate, repair small
holes, decompose, compute stable poses."""

from __future__ import annotations

import re
from pathlib import Path

import trimesh

from suctionbench.errors import InputError
from suctionbench.geometry.mesh import load_mesh
from suctionbench.objects.build import ObjectRecord, build_object
from suctionbench.objects.registry import set_dir
from suctionbench.objects.spec import SETS, ObjectSpec

NAME_PATTERN = re.compile(r"^[a-z0-9][a-z0-9_\-]{0,63}$")
"""Object and set names: lower case letters, digits, '_' and '-'."""


def repair(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """Close small holes and make winding and normals consistent (trimesh's repair tools)."""
    mesh = mesh.copy()
    trimesh.repair.fix_winding(mesh)
    trimesh.repair.fill_holes(mesh)
    trimesh.repair.fix_normals(mesh)
    return mesh


def import_mesh(
    path: str | Path,
    *,
    set_name: str,
    name: str,
    units: str = "m",
    mass: float | None = None,
    try_repair: bool = True,
    overwrite: bool = False,
    root: Path | None = None,
) -> ObjectRecord:
    """Import a mesh file into SET/NAME under the user object root (or `root`)."""
    for what, value in (("--set", set_name), ("--name", name)):
        if not NAME_PATTERN.match(value):
            raise InputError(f"{what} '{value}': use lower-case letters, digits, '_' and '-' (max 64)")
    if set_name in SETS:
        raise InputError(f"--set '{set_name}': evaluation sets are generated, not imported; use e.g. 'custom'")
    out_dir = (root / set_name if root else set_dir(set_name)) / name
    if out_dir.exists() and not overwrite:
        raise InputError(f"object '{set_name}/{name}' already exists at {out_dir} (pass --overwrite)")
    info = load_mesh(path, units=units)
    mesh = info.mesh
    if not info.watertight and try_repair:
        mesh = repair(mesh)
    if not (mesh.is_watertight and mesh.is_winding_consistent):
        raise InputError(f"mesh '{path}': not watertight and could not be repaired (holes too large?)")
    spec = ObjectSpec(name=name, set=set_name, generator="import", params={}, description=f"imported from {path}")
    return build_object(mesh, spec, out_dir, source=str(path), units=units, mass=mass)
