"""`suctionbench label`: robust suction labels on a mesh."""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.table import Table
from rich.text import Text

from suctionbench.cli.common import (
    JsonOpt,
    SeedOpt,
    UnitsOpt,
    app,
    console,
    err,
    parse_vector,
    progress_bar,
    run_command,
)
from suctionbench.errors import InputError
from suctionbench.validate import (
    BYTES_PER_LABEL,
    MAX_GRASP_OFFSET,
    grasp_near_surface,
    label_memory,
    output_file,
    require_disk,
    require_memory,
)


@app.command()
def label(
    mesh: Annotated[str, typer.Argument(help="Mesh file (OBJ, STL, PLY, OFF, GLB).")],
    grasp: Annotated[
        str | None, typer.Option(help="One grasp 'x,y,z,vx,vy,vz': target point and unit approach.")
    ] = None,
    grasps: Annotated[int | None, typer.Option(help="Sample N grasp candidates on the surface.")] = None,
    mass: Annotated[float, typer.Option(help="Object mass in kg (the paper assumes 1.0 when unknown).")] = 1.0,
    com: Annotated[str | None, typer.Option(help="Centre of mass 'x,y,z' (default: from the mesh).")] = None,
    units: UnitsOpt = "auto",
    cup: Annotated[str, typer.Option(help="Cup preset: default or paper.")] = "default",
    samples: Annotated[int, typer.Option(help="Monte-Carlo samples J per grasp.")] = 50,
    out: Annotated[Path | None, typer.Option(help="With --grasps: write labels to this .npz.")] = None,
    top: Annotated[int, typer.Option(help="With --grasps: rows in the table of best grasps.")] = 10,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Label suction grasps on a mesh with the Dex-Net 3.0 compliant suction contact model."""

    def body() -> dict[str, Any]:
        from suctionbench.config import LabelConfig, PerturbationConfig, cup_preset
        from suctionbench.contact import SuctionLabeller
        from suctionbench.contact.summary import batch_summary, grasp_record, save_labels
        from suctionbench.geometry.mesh import load_mesh
        from suctionbench.geometry.sampling import sample_surface_grasps

        if (grasp is None) == (grasps is None):
            raise InputError("give exactly one of --grasp x,y,z,vx,vy,vz or --grasps N")
        if out is not None and grasps is None:
            raise InputError("--out needs --grasps (a single --grasp is printed, not written)")
        if out is not None:
            output_file(out, "--out")
            if out.suffix != ".npz":  # never write labels over a file of another kind
                raise InputError(f"--out '{out}': expected a .npz file name")
            require_disk(out, grasps * BYTES_PER_LABEL + 2**16, f"--grasps {grasps} --out")
        require_memory(label_memory(grasps or 1, samples), f"--grasps {grasps or 1} x --samples {samples}")
        config = LabelConfig(
            cup=cup_preset(cup), perturbation=replace(PerturbationConfig(), num_samples=samples)
        )
        info = load_mesh(mesh, units=units.lower())
        com_vec = parse_vector(com, 3, "--com") if com is not None else None
        if com_vec is not None:
            low, high = info.mesh.bounds
            if np.any(com_vec < low - MAX_GRASP_OFFSET) or np.any(com_vec > high + MAX_GRASP_OFFSET):
                raise InputError(f"--com {com_vec.tolist()}: outside the bounding box of '{mesh}' "
                                 f"({low.round(4).tolist()} to {high.round(4).tolist()} m)")
        labeller = SuctionLabeller(info, config, mass=mass, com=com_vec)
        warnings = list(info.warnings)
        if mass > config.cup.payload_kg:
            warnings.append(
                f"mass {mass:g} kg exceeds the '{config.cup.name}' cup's vacuum payload "
                f"{config.cup.payload_kg:.3g} kg: no grasp can hold it (pass --mass)"
            )

        def warn() -> None:  # after every input is checked: a refused input prints its one error line only
            for line in warnings:
                err.print(Text.assemble(("warning:", "yellow"), " ", line), highlight=False)

        if grasp is not None:
            values = parse_vector(grasp, 6, "--grasp")
            point, approach = values[:3], values[3:]
            norm = float(np.linalg.norm(approach))
            if abs(norm - 1.0) > 1e-3:
                raise InputError(f"--grasp approach {approach.tolist()}: length {norm:.4g}, must be a unit vector")
            approach = approach / norm
            grasp_near_surface(info.mesh, point, "--grasp point", f"'{mesh}'")
            warn()
            labels = labeller.label(point[None], approach[None], seed)
            record = grasp_record(labels, 0)
            if not as_json:
                _print_record(record)
            return {**record, "mass": mass, "cup": config.cup.name, "samples": samples,
                    "seed": seed, "warnings": warnings}

        warn()
        rng = np.random.default_rng(seed)
        points, approaches = sample_surface_grasps(info.mesh, grasps, rng)
        start = time.perf_counter()
        with progress_bar(grasps, "labelling", not as_json) as advance:
            labels = labeller.label(points, approaches, seed, progress=advance)
        elapsed = time.perf_counter() - start
        summary = batch_summary(labels)
        summary["seconds"] = round(elapsed, 3)
        summary["grasps_per_second"] = round(grasps / elapsed, 1)
        if out is not None:
            save_labels(out, labels)
            summary["out"] = str(out)
        if not as_json:
            _print_batch(labels, summary, top, mesh)
        return {**summary, "mass": mass, "cup": config.cup.name, "seed": seed, "warnings": warnings}

    run_command(as_json, body)


def _print_record(record: dict[str, Any]) -> None:
    table = Table(title="suction grasp label", show_header=False)
    for key, value in record.items():
        if isinstance(value, float):
            value = f"{value:.4g}"
        elif isinstance(value, list):
            value = ", ".join("-" if v is None else f"{v:.4g}" for v in value)
        table.add_row(key, str(value))
    console().print(table)


def _print_batch(labels: Any, summary: dict[str, Any], top: int, mesh: str) -> None:
    screen = console()
    head = Table(title=f"labels for {mesh}", show_header=False)
    for key, value in summary.items():
        head.add_row(key, f"{value:.3f}" if isinstance(value, float) else str(value))
    screen.print(head)
    if top == 0:
        return
    order = np.lexsort((-labels.score("ss"), -labels.rwr))[:top]
    best = Table(title=f"top {len(order)} grasps by robust wrench resistance")
    for col in ("#", "point (mm)", "approach", "seal", "stretch", "wr", "rwr", "pc3d"):
        best.add_column(col, justify="right")
    for i in order:
        p, v = labels.points[i] * 1e3, labels.approaches[i]
        best.add_row(
            str(i),
            f"{p[0]:.1f},{p[1]:.1f},{p[2]:.1f}",
            ",".join(f"{round(c, 2) + 0.0:.2f}" for c in v),
            "yes" if labels.seal.seal[i] else (labels.seal.failure_names[i] or ""),
            f"{labels.seal.max_stretch[i]:.3f}",
            "yes" if labels.wr[i] else "no",
            f"{labels.rwr[i]:.2f}",
            f"{labels.score('pc3d')[i]:.2f}",
        )
    screen.print(best)
