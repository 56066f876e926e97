"""`suctionbench objects list|show|build|stats|import|generate`."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table

from suctionbench.cli.common import (
    JsonOpt,
    SeedOpt,
    UnitsOpt,
    console,
    err,
    objects_app,
    print_kv,
    print_rows,
    progress_bar,
    record_row,
    resolve_workers,
    run_command,
)
from suctionbench.errors import InputError
from suctionbench.validate import BYTES_PER_CORPUS_OBJECT, BYTES_PER_OBJECT, output_dir, require_disk


@objects_app.command("list")
def objects_list(
    set_name: Annotated[str | None, typer.Option("--set", help="Only this set.")] = None,
    as_json: JsonOpt = False,
) -> None:
    """List built objects (evaluation sets and user sets)."""

    def body() -> dict[str, Any]:
        from suctionbench.objects.registry import list_objects

        rows = [record_row(r) for r in list_objects(set_name)]
        if not as_json:
            print_rows(f"objects{' in ' + set_name if set_name else ''}", rows)
        return {"count": len(rows), "objects": rows}

    run_command(as_json, body)


@objects_app.command("show")
def objects_show(
    key: Annotated[str, typer.Argument(help="SET/NAME, e.g. basic/box_cereal.")],
    as_json: JsonOpt = False,
) -> None:
    """Show one object's record (object.toml)."""

    def body() -> dict[str, Any]:
        from suctionbench.objects.registry import load_object

        record = load_object(key)
        data = record.to_toml()
        if not as_json:
            table = Table(title=key, show_header=False)
            for k, v in data.items():
                if k == "stable_poses":
                    v = ", ".join(f"{p['probability']:.3f}" for p in v)
                table.add_row(k, str(v))
            console().print(table)
        return {"key": key, "directory": str(record.directory), **data}

    run_command(as_json, body)


@objects_app.command("build")
def objects_build(
    set_name: Annotated[str | None, typer.Option("--set", help="Only this evaluation set.")] = None,
    out: Annotated[Path | None, typer.Option(help="Root to build into (default: the shipped assets).")] = None,
    workers: Annotated[int, typer.Option(help="Parallel processes.")] = 2,
    reuse_parts: Annotated[bool, typer.Option(
        help="Keep the convex parts of objects whose mesh is unchanged (mass-only rebuilds skip CoACD).")] = False,
    as_json: JsonOpt = False,
) -> None:
    """Regenerate evaluation-set objects (meshes, stable poses, convex parts) deterministically."""

    def body() -> dict[str, Any]:
        from suctionbench.objects.batch import build_specs
        from suctionbench.objects.registry import assets_root, eval_specs

        sets = eval_specs()
        if set_name is not None and set_name not in sets:
            raise InputError(f"object set '{set_name}' is unknown (known: {', '.join(sets)})")
        specs = [s for name, group in sets.items() if set_name in (None, name) for s in group]
        root = output_dir(out or assets_root(), "--out")
        require_disk(root, len(specs) * BYTES_PER_OBJECT, f"{len(specs)} objects")
        start = time.perf_counter()
        with progress_bar(len(specs), "building", not as_json) as advance:
            records = build_specs(specs, root, workers=workers, reuse_parts=reuse_parts, progress=advance)
        rows = [record_row(r) for r in records]
        if not as_json:
            print_rows("built", rows)
        return {"built": len(records), "seconds": round(time.perf_counter() - start, 1), "objects": rows}

    run_command(as_json, body, output=f"--out '{out}'" if out is not None else "the shipped assets")


@objects_app.command("stats")
def objects_stats(
    set_name: Annotated[str | None, typer.Option("--set", help="Only this set.")] = None,
    grasps: Annotated[int, typer.Option(help="Surface grasps per object.")] = 300,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Per-set difficulty: share of surface grasps that seal and that are robust (rwr > 0.2); per
    object its known-state pickability (stable-pose share with a grasp of rwr > 0.5 within the image
    policies' 60 deg of straight down) and mass; and the mass cap with its derivation."""

    def body() -> dict[str, Any]:
        from suctionbench.config import LabelConfig
        from suctionbench.objects.registry import list_objects
        from suctionbench.objects.spec import SETS
        from suctionbench.objects.stats import pick_criteria, set_stats, stats_rows
        from suctionbench.validate import label_memory, require_memory

        if grasps < 1:
            raise InputError(f"--grasps {grasps}: must be at least 1")
        require_memory(label_memory(grasps, LabelConfig().perturbation.num_samples), f"--grasps {grasps}")
        sets = [set_name] if set_name else list(SETS)
        result = {}
        for name in sets:
            records = list_objects(name)
            with progress_bar(len(records), name, not as_json) as advance:
                result[name] = set_stats(records, grasps, seed, progress=advance)
        criteria = pick_criteria()
        if not as_json:
            set_rows, object_rows = stats_rows(result)
            print_rows("object sets", set_rows)
            print_rows("known-state pickability (flag: no_surface / load)", object_rows)
            print_kv("criteria", {"robust": f"rwr > {criteria['pick_threshold_rwr']:g}",
                                  "approach cone": f"{criteria['approach_cone_deg']:g} deg from straight down",
                                  "mass cap": criteria["mass_cap"]["derivation"]})
        return {"grasps_per_object": grasps, "seed": seed, "criteria": criteria, "sets": result}

    run_command(as_json, body)


@objects_app.command("import")
def objects_import(
    path: Annotated[str, typer.Argument(help="Mesh file: OBJ, STL, PLY, OFF, GLB, GLTF.")],
    set_name: Annotated[str, typer.Option("--set", help="User set to add it to.")] = "custom",
    name: Annotated[str, typer.Option(help="Object name (lower case, digits, _ and -).")] = "",
    units: UnitsOpt = "auto",
    scale: Annotated[float, typer.Option(help="Extra scale factor on top of --units (e.g. a URDF mesh scale).")] = 1.0,
    mass: Annotated[float | None, typer.Option(
        help="Mass in kg (default: a PLA print); above the cup's mass cap it imports with a warning.")] = None,
    repair: Annotated[
        bool, typer.Option(help="Repair duplicated faces, touching or overlapping pieces, small holes, stray sheets.")
    ] = True,
    overwrite: Annotated[bool, typer.Option(help="Replace an existing object of that name.")] = False,
    root: Annotated[Path | None, typer.Option(help="Object root (default: $SUCTIONBENCH_HOME/objects).")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Import your own mesh: read, scale, make one closed solid (seams merged, pieces united, small
    holes closed; pieces apart kept as one rigid body, with a warning; each defect it cannot repair
    named), decompose, compute stable poses."""

    def body() -> dict[str, Any]:
        from suctionbench.objects.importer import import_mesh, import_target

        object_name = name or Path(path).stem.lower()
        if root is not None:
            output_dir(root, "--root")
        target = import_target(set_name, object_name, root=root, overwrite=overwrite)
        size = Path(path).stat().st_size if Path(path).is_file() else 0
        what = "--root" if root is not None else "object directory"
        require_disk(output_dir(target, what), 3 * size + BYTES_PER_OBJECT, f"mesh '{path}' imported")
        record = import_mesh(
            path, set_name=set_name, name=object_name, units=units, scale=scale, mass=mass,
            try_repair=repair, overwrite=overwrite, root=root,
        )
        row = record_row(record)
        repairs = record.params.get("repairs", [])
        warnings = record.params.get("warnings", [])
        if not as_json:
            print_rows("imported", [row])
            for note in repairs:
                err.print(f"repaired: {note}", highlight=False)
            for note in warnings:
                err.print(f"warning: {note}", highlight=False)
        if units.lower() == "auto" and record.units != "m" and not as_json:
            err.print(f"read in {record.units}: its size is plausible only in {record.units} (--units auto)",
                      highlight=False)
        return {**row, "directory": str(record.directory), "units": record.units, "scale": record.scale,
                "repairs": repairs, "warnings": warnings}

    run_command(as_json, body, output=f"--root '{root}'" if root is not None else "the user object root")


@objects_app.command("generate")
def objects_generate(
    count: Annotated[int, typer.Option(help="Number of training objects.")] = 1500,
    out: Annotated[Path, typer.Option(help="Corpus directory (objects are cached there).")] = Path("corpus"),
    workers: Annotated[int, typer.Option(help="Parallel processes (0 = all cores).")] = 0,
    masses: Annotated[str, typer.Option(help="Object masses: 'material' (each shape's own material), "
                                             "'prior' (the training mass prior: carton, print, wood, plastic, "
                                             "full container, metal) or 'filled' (material, with bottles, jugs "
                                             "and cans part-filled with liquids or a paste).")] = "material",
    sizes: Annotated[str, typer.Option(help="Object sizes: 'family' (each shape family's own range) or 'items' "
                                            "(generic shapes scaled to real items' 4-24.5 cm).")] = "family",
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Generate (or complete) the training corpus; evaluation objects never appear in it."""

    def body() -> dict[str, Any]:
        from suctionbench.objects.corpus_build import generate_corpus
        from suctionbench.objects.corpus_priors import check_mass_mode, check_size_mode

        if count < 1:
            raise InputError(f"--count {count}: must be at least 1")
        check_mass_mode(masses)  # before --out is touched
        check_size_mode(sizes)
        output_dir(out, "--out")
        train = out / "train"
        cached = sum(1 for p in train.iterdir() if not p.name.startswith(".")) if train.is_dir() else 0
        require_disk(out, max(count - cached, 0) * BYTES_PER_CORPUS_OBJECT, f"--count {count}")
        with progress_bar(count, "generating", not as_json) as advance:
            summary = generate_corpus(count, seed, out, workers=resolve_workers(workers), progress=advance,
                                      masses=masses, sizes=sizes)
        if not as_json:
            print_rows("corpus", [{k: v for k, v in summary.items() if not isinstance(v, dict)}])
        return summary

    run_command(as_json, body, output=f"--out '{out}'")
