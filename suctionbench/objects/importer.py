"""Import a user's own mesh (OBJ / STL / PLY / GLB ...) as an object: read, scale, validate, make
one closed solid, or separate closed pieces of one rigid body (see `suctionbench.objects.repair`),
decompose, compute stable poses."""

from __future__ import annotations

import os
import re
from pathlib import Path

from suctionbench.errors import InputError
from suctionbench.geometry.mesh import load_mesh
from suctionbench.objects.build import ObjectRecord, build_object
from suctionbench.objects.decompose import IMPORT_OPTIONS, IMPORT_SCHEDULE
from suctionbench.objects.ownership import check_replaceable_objects
from suctionbench.objects.registry import set_dir
from suctionbench.objects.repair import solidify
from suctionbench.objects.spec import SETS, ObjectSpec

NAME_PATTERN = re.compile(r"^[a-z0-9][a-z0-9_\-]{0,63}$")
"""Object and set names: lower case letters, digits, '_' and '-'."""


def import_target(set_name: str, name: str, *, root: Path | None = None, overwrite: bool = False) -> Path:
    """The object directory an import of `name` into `set_name` writes (under `root`, default the
    user object root), after checking the names and that the import may write there: an existing
    object only with `overwrite`, and only one suctionbench wrote (InputError otherwise)."""
    for what, value in (("--set", set_name), ("--name", name)):
        if not NAME_PATTERN.match(value):
            raise InputError(f"{what} '{value}': use lower-case letters, digits, '_' and '-' (max 64)")
    if set_name in SETS:
        raise InputError(f"--set '{set_name}': evaluation sets are generated, not imported; use e.g. 'custom'")
    out_dir = (root / set_name if root else set_dir(set_name)) / name
    if out_dir.exists() and not overwrite:
        raise InputError(f"object '{set_name}/{name}' already exists at {out_dir} (pass --overwrite)")
    check_replaceable_objects([out_dir])  # before loading and repairing the mesh
    return out_dir


def import_mesh(
    path: str | Path,
    *,
    set_name: str,
    name: str,
    units: str = "auto",
    scale: float = 1.0,
    mass: float | None = None,
    try_repair: bool = True,
    overwrite: bool = False,
    root: Path | None = None,
    coacd_parallel: int | None = None,
) -> ObjectRecord:
    """Import a mesh file into SET/NAME under the user object root (or `root`).

    The file is read as written, scaled to metres (`units` times `scale`; "auto" reads an STL in
    metres or millimetres, whichever size is plausible: `geometry.mesh.AUTO_UNITS`), validated, made one
    closed solid (`suctionbench.objects.repair.solidify`: seams merged, duplicated faces removed,
    touching or overlapping pieces united, small holes closed, stray open sheets dropped; pieces
    further apart kept as one rigid body, named in ``params["warnings"]``), then
    built (mass, stable poses, convex parts). What was repaired is kept in the record's
    ``params["repairs"]``. An object heavier than the default cup carries is imported all the same
    (a lighter print variant where one fits, else the lightest; a given `mass` as given), named in
    ``params["warnings"]``: other cups carry more, and an unliftable object is a fair test. With
    ``try_repair=False`` a mesh that needs any repair beyond merging
    seams is rejected instead. `coacd_parallel`: the convex decomposition's tries run at once
    (`build.decompose_mesh`; None: one per core this process may use, as the user waits).
    """
    out_dir = import_target(set_name, name, root=root, overwrite=overwrite)
    info = load_mesh(path, units=units, scale=scale)
    solid = solidify(info.mesh, source=str(path))
    if solid.notes and not try_repair:
        raise InputError(f"mesh '{path}': needs repair ({solid.notes[0]}) and repairs are off (--no-repair)")
    params = {"units": info.units, "scale": float(scale), "repairs": solid.notes}
    if solid.warnings:
        params["warnings"] = list(solid.warnings)
    spec = ObjectSpec(name=name, set=set_name, generator="import", params=params, description=f"imported from {path}")
    return build_object(
        solid.mesh,
        spec,
        out_dir,
        source=str(path),
        units=info.units,
        scale=scale,
        mass=mass,
        coacd=(IMPORT_SCHEDULE, IMPORT_OPTIONS),
        coacd_parallel=coacd_parallel or len(os.sched_getaffinity(0)),
        cavities=solid.cavities,
        keep_above_cap=True,
        assembly=True,  # solidify leaves one body, or separate pieces it warns of
    )
