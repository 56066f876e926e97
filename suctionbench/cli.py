"""The `suctionbench` command line: parse, call the library, print (rich) or --json.

Contract (DESIGN.md): with --json, the last stdout line is exactly one JSON object and human
output goes to stderr; exit 0 on success, 2 on bad input (one line naming the input and the
problem), 1 on an internal failure. Long work shows a progress bar on a terminal only.
"""

from __future__ import annotations

import json
import os
import sys
import time
import traceback
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, ProgressColumn, TextColumn, TimeRemainingColumn
from rich.table import Table
from rich.text import Text

from suctionbench import __version__
from suctionbench.errors import InputError


class ContractGroup(typer.core.TyperGroup):
    """Top-level command group that keeps the CLI contract for usage errors too.

    Click reports a bad option before any command runs; here such errors still exit 2 and, under
    --json, still end stdout with a JSON object.
    """

    def main(self, args: Any = None, *pargs: Any, standalone_mode: bool = True, **kwargs: Any) -> Any:
        argv = list(sys.argv[1:] if args is None else args)
        try:
            rv = super().main(argv, *pargs, standalone_mode=False, **kwargs)
        except typer.core._click.exceptions.ClickException as exc:
            exc.show()
            _emit({"ok": False, "error": exc.format_message()}, "--json" in argv)
            rv = exc.exit_code
        except typer.exceptions.Abort:  # Ctrl-C, or a closed pipe under --help
            err.print("aborted")
            rv = 1
        code = rv if isinstance(rv, int) else 0
        if not standalone_mode:
            return code
        sys.exit(code)


app = typer.Typer(
    cls=ContractGroup,
    add_completion=False,
    no_args_is_help=True,
    help="Robust suction grasp labels, datasets, GQ-CNN policies and a MuJoCo benchmark.",
)
bench_app = typer.Typer(no_args_is_help=True, help="Speed figures, each timed against its reference in one run.")
app.add_typer(bench_app, name="bench")
objects_app = typer.Typer(no_args_is_help=True, help="Object sets: list, show, build, import, generate the corpus.")
app.add_typer(objects_app, name="objects")
dataset_app = typer.Typer(no_args_is_help=True, help="Inspect generated datasets.")
app.add_typer(dataset_app, name="dataset")

err = Console(stderr=True, soft_wrap=True)  # soft wrap: one error, one line

JsonOpt = Annotated[bool, typer.Option("--json", help="Print one JSON object on the last stdout line.")]
SeedOpt = Annotated[int, typer.Option("--seed", help="Seed of every random draw.")]

MAX_GRASP_OFFSET = 0.005
"""A --grasp point farther than this (m) from the mesh surface is rejected as a typo."""


def _emit(result: dict[str, Any], as_json: bool) -> None:
    if as_json:
        print(json.dumps(result, sort_keys=False))


def _run(as_json: bool, body: Callable[[], dict[str, Any]]) -> None:
    """Run a command body under the CLI contract (exit codes, JSON on the last line)."""
    try:
        result = body()
    except InputError as exc:
        err.print(f"[bold red]error:[/] {exc}", highlight=False)
        _emit({"ok": False, "error": str(exc)}, as_json)
        raise typer.Exit(2) from None
    except typer.Exit:
        raise
    except Exception as exc:  # an internal failure: say so, with the traceback on stderr
        err.print(f"[bold red]internal error:[/] {type(exc).__name__}: {exc}", highlight=False)
        traceback.print_exc(file=sys.stderr)
        _emit({"ok": False, "error": f"internal: {type(exc).__name__}: {exc}"}, as_json)
        raise typer.Exit(1) from None
    _emit({"ok": True, **result}, as_json)


class _RateColumn(ProgressColumn):
    """Items per second of a progress task."""

    def render(self, task: Any) -> Text:
        return Text(f"{task.speed:,.0f}/s" if task.speed else "-/s")


@contextmanager
def _progress(total: int, label: str, enabled: bool) -> Iterator[Callable[[int], None]]:
    """A rich progress bar on an interactive stderr; a no-op callback otherwise."""
    if not enabled or not err.is_terminal:
        yield lambda _n: None
        return
    columns = (TextColumn(label), BarColumn(), MofNCompleteColumn(), _RateColumn(), TimeRemainingColumn())
    with Progress(*columns, console=err, transient=True) as bar:
        task = bar.add_task(label, total=total)
        yield lambda n: bar.advance(task, n)


def parse_vector(text: str, size: int, what: str) -> np.ndarray:
    """Parse 'a,b,c' into a finite float vector of `size`, or raise InputError naming `what`."""
    try:
        values = np.array([float(x) for x in text.split(",")], dtype=float)
    except ValueError:
        raise InputError(f"{what} '{text}': expected {size} comma-separated numbers") from None
    if values.shape != (size,):
        raise InputError(f"{what} '{text}': expected {size} comma-separated numbers, got {len(values)}")
    if not np.all(np.isfinite(values)):
        raise InputError(f"{what} '{text}': values must be finite")
    return values


@app.command()
def version(as_json: JsonOpt = False) -> None:
    """Print the suctionbench version."""
    _run(as_json, lambda: {"version": __version__})
    if not as_json:
        print(__version__)


@app.command()
def label(
    mesh: Annotated[str, typer.Argument(help="Mesh file (OBJ, STL, PLY, OFF, GLB).")],
    grasp: Annotated[
        str | None, typer.Option(help="One grasp 'x,y,z,vx,vy,vz': target point and unit approach.")
    ] = None,
    grasps: Annotated[int | None, typer.Option(help="Sample N grasp candidates on the surface.")] = None,
    mass: Annotated[float, typer.Option(help="Object mass in kg (the paper assumes 1.0 when unknown).")] = 1.0,
    com: Annotated[str | None, typer.Option(help="Centre of mass 'x,y,z' (default: from the mesh).")] = None,
    units: Annotated[str, typer.Option(help="Units of the mesh file: m, cm or mm.")] = "m",
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
        if grasps is not None and grasps < 1:
            raise InputError(f"--grasps {grasps}: must be at least 1")
        if out is not None and grasps is None:
            raise InputError("--out needs --grasps (a single --grasp is printed, not written)")
        if top < 0:
            raise InputError(f"--top {top}: must be >= 0")
        config = LabelConfig(
            cup=cup_preset(cup), perturbation=replace(PerturbationConfig(), num_samples=samples)
        )
        info = load_mesh(mesh, units=units.lower())
        com_vec = parse_vector(com, 3, "--com") if com is not None else None
        labeller = SuctionLabeller(info, config, mass=mass, com=com_vec)
        warnings = list(info.warnings)
        if mass > config.cup.payload_kg:
            warnings.append(
                f"mass {mass:g} kg exceeds the '{config.cup.name}' cup's vacuum payload "
                f"{config.cup.payload_kg:.3g} kg: no grasp can hold it (pass --mass)"
            )
        for line in warnings:
            err.print(f"[yellow]warning:[/] {line}", highlight=False)

        if grasp is not None:
            values = parse_vector(grasp, 6, "--grasp")
            point, approach = values[:3], values[3:]
            norm = float(np.linalg.norm(approach))
            if abs(norm - 1.0) > 1e-3:
                raise InputError(f"--grasp approach {approach.tolist()}: length {norm:.4g}, must be a unit vector")
            approach = approach / norm
            _, distance, _ = info.mesh.nearest.on_surface(point[None])
            if distance[0] > MAX_GRASP_OFFSET:
                raise InputError(
                    f"--grasp point {point.tolist()} is {distance[0] * 1e3:.1f} mm from the surface of "
                    f"'{mesh}' (at most {MAX_GRASP_OFFSET * 1e3:g} mm)"
                )
            labels = labeller.label(point[None], approach[None], seed)
            record = grasp_record(labels, 0)
            if not as_json:
                _print_record(record)
            return {**record, "mass": mass, "cup": config.cup.name, "samples": samples,
                    "seed": seed, "warnings": warnings}

        rng = np.random.default_rng(seed)
        points, approaches = sample_surface_grasps(info.mesh, grasps, rng)
        start = time.perf_counter()
        with _progress(grasps, "labelling", not as_json) as advance:
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

    _run(as_json, body)


def _print_record(record: dict[str, Any]) -> None:
    table = Table(title="suction grasp label", show_header=False)
    for key, value in record.items():
        if isinstance(value, float):
            value = f"{value:.4g}"
        elif isinstance(value, list):
            value = ", ".join("-" if v is None else f"{v:.4g}" for v in value)
        table.add_row(key, str(value))
    Console().print(table)


def _print_batch(labels: Any, summary: dict[str, Any], top: int, mesh: str) -> None:
    console = Console()
    head = Table(title=f"labels for {mesh}", show_header=False)
    for key, value in summary.items():
        head.add_row(key, f"{value:.3f}" if isinstance(value, float) else str(value))
    console.print(head)
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
    console.print(best)


@app.command()
def pick(
    object_key: Annotated[str, typer.Option("--object", help="Object SET/NAME, e.g. basic/box_tea.")],
    grasp: Annotated[
        str | None, typer.Option(help="Grasp 'x,y,z,vx,vy,vz' in the object's own frame (default: --policy).")
    ] = None,
    policy: Annotated[
        str, typer.Option(help="Policy when no --grasp: analytic, random-surface (known state) or an image policy "
                               "(random, centroid, planarity, planarity-centroid, gqcnn).")
    ] = "analytic",
    model: Annotated[str | None, typer.Option(help="GQ-CNN model directory (gqcnn policy).")] = None,
    metric: Annotated[str, typer.Option(help="3D metric of the analytic policy: rwr, wr, ss, pc3d.")] = "rwr",
    placement: Annotated[str, typer.Option(help="drop (random orientation) or stable (most probable pose).")] = "drop",
    cup: Annotated[str, typer.Option(help="Cup preset: default or paper.")] = "default",
    camera: Annotated[str, typer.Option(help="Camera preset or intrinsics TOML.")] = "primesense",
    render: Annotated[Path | None, typer.Option(help="Save the overhead colour view before the pick (PNG).")] = None,
    log: Annotated[Path | None, typer.Option(help="Write the episode to this MCAP file (Foxglove).")] = None,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Run one simulated pick episode with the YuMi and report its outcome."""

    def body() -> dict[str, Any]:
        from suctionbench.config import cup_preset
        from suctionbench.sim.pick import PickRequest, PickRunner

        values = None
        if grasp is not None:
            values = parse_vector(grasp, 6, "--grasp")
            if abs(np.linalg.norm(values[3:]) - 1.0) > 1e-3:
                raise InputError(f"--grasp approach {values[3:].tolist()}: must be a unit vector")
        request = PickRequest(
            object_key, seed=seed, grasp=values, policy=policy, placement=placement, cup=cup_preset(cup),
            camera=camera, model=model, metric=metric,
        )
        if log is not None and log.suffix != ".mcap":
            raise InputError(f"--log '{log}': expected a .mcap file name")
        result = PickRunner(request).run(render=render, log=log)
        if not as_json:
            _print_kv(f"pick {object_key}", result)
        return result

    _run(as_json, body)


@app.command()
def view(
    object_key: Annotated[str, typer.Option("--object", help="Object SET/NAME.")] = "basic/box_tea",
    seed: SeedOpt = 0,
) -> None:
    """Open the scene in MuJoCo's interactive viewer (needs a display)."""

    def body() -> dict[str, Any]:
        if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
            raise InputError("view: no display found (set DISPLAY); use `pick --render FILE.png` on a server")
        import mujoco.viewer

        from suctionbench.sim.pick import PickRequest, PickRunner

        runner = PickRunner(PickRequest(object_key, seed=seed))
        runner.episode.reset(np.random.default_rng(seed))
        mujoco.viewer.launch(runner.scene.model, runner.episode.data)
        return {}

    _run(False, body)


@app.command()
def generate(
    objects: Annotated[str, typer.Option(help="Object set (basic, typical, adversarial) or a directory (corpus).")],
    datapoints: Annotated[int, typer.Option(help="Number of datapoints.")],
    out: Annotated[Path, typer.Option(help="Dataset directory.")],
    camera: Annotated[str, typer.Option(help="Camera preset or intrinsics TOML.")] = "primesense",
    engine: Annotated[str, typer.Option(help="local (process pool) or ray.")] = "local",
    workers: Annotated[int, typer.Option(help="Worker processes (0 = all cores).")] = 0,
    address: Annotated[str | None, typer.Option(help="Ray cluster address (engine ray).")] = None,
    grasps_per_object: Annotated[int, typer.Option(help="Grasp candidates per object.")] = 200,
    cup: Annotated[str, typer.Option(help="Cup preset: default or paper.")] = "default",
    resume: Annotated[bool, typer.Option(help="Continue an interrupted run with the same configuration.")] = False,
    overwrite: Annotated[bool, typer.Option(help="Replace an existing dataset.")] = False,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Generate a Dex-Net-style dataset: rendered noisy depth thumbnails with robust labels."""

    def body() -> dict[str, Any]:
        from suctionbench.config import LabelConfig, cup_preset
        from suctionbench.dataset.generate import GenerationConfig, generate_dataset
        from suctionbench.objects.registry import resolve_objects

        if grasps_per_object < 1:
            raise InputError(f"--grasps-per-object {grasps_per_object}: must be at least 1")
        records = resolve_objects(objects)
        config = GenerationConfig(
            datapoints=datapoints, seed=seed, grasps_per_object=grasps_per_object,
            label=LabelConfig(cup=cup_preset(cup)),
        )
        start = time.perf_counter()
        with _progress(datapoints, "generating", not as_json) as advance:
            card = generate_dataset(
                out, [str(r.directory) for r in records], [r.key for r in records], camera, config,
                engine=engine, workers=_workers(workers), address=address, resume=resume,
                overwrite=overwrite, progress=advance,
            )
        elapsed = time.perf_counter() - start
        summary = {k: card[k] for k in ("datapoints", "shards", "positive_rate", "fingerprint")}
        summary.update(out=str(out), seconds=round(elapsed, 2), datapoints_per_s=round(card["datapoints"] / elapsed, 1),
                       regenerated_corrupt_units=len(card.get("regenerated_corrupt_units", [])))
        if not as_json:
            _print_rows("dataset", [summary])
        return summary

    _run(as_json, body)


@dataset_app.command("show")
def dataset_show(
    directory: Annotated[Path, typer.Argument(help="Dataset directory.")],
    thumbnails: Annotated[Path | None, typer.Option(help="Save 16 thumbnails with labels to this PNG.")] = None,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Counts, positive rate, camera and objects of a dataset; optionally a thumbnail sheet."""

    def body() -> dict[str, Any]:
        from suctionbench.dataset.storage import DatasetReader, read_card
        from suctionbench.learning.data import label_threshold

        card = read_card(directory)
        reader = DatasetReader(directory)
        summary = {
            "datapoints": reader.num_datapoints, "shards": reader.num_shards,
            "positive_rate": card.get("positive_rate"), "camera": card.get("camera", {}).get("name"),
            "objects": len(card.get("objects", [])), "status": card.get("status"),
            "threshold": label_threshold(card),
        }
        if thumbnails is not None:
            from suctionbench.sensing.image import save_png
            from suctionbench.sensing.thumbnails import to_uint8_grid

            shard = reader.shard(0)
            rng = np.random.default_rng(seed)
            pick = rng.choice(len(shard["robust_suction_wrench_resistance"]), size=16, replace=False)
            labels = shard["robust_suction_wrench_resistance"][pick] > summary["threshold"]
            save_png(thumbnails, to_uint8_grid(shard["depth_ims_tf_table"][pick, ..., 0], labels))
            summary["thumbnails"] = str(thumbnails)
        if not as_json:
            _print_rows(str(directory), [summary])
        return summary

    _run(as_json, body)


@app.command("eval")
def eval_cmd(
    policy: Annotated[
        str, typer.Option(help="Policy: gqcnn, planarity-centroid, centroid, planarity, random, analytic.")
    ],
    out: Annotated[Path, typer.Option(help="Run directory (trials/*.mcap, run.json).")],
    set_name: Annotated[str | None, typer.Option("--set", help="Object set (instead of --task).")] = None,
    task: Annotated[str | None, typer.Option(help="Task name (tasks/*.toml) or TOML path.")] = None,
    model: Annotated[str | None, typer.Option(help="GQ-CNN model directory (default: the shipped one).")] = None,
    trials: Annotated[int | None, typer.Option(help="Number of trials (default: the task's).")] = None,
    workers: Annotated[int, typer.Option(help="Parallel workers (0 = all cores).")] = 0,
    engine: Annotated[str, typer.Option(help="local or ray.")] = "local",
    address: Annotated[str | None, typer.Option(help="Ray cluster address.")] = None,
    metric: Annotated[
        str | None, typer.Option(help="3D metric of the analytic policy (default: each of the task's, else rwr).")
    ] = None,
    cup: Annotated[str, typer.Option(help="Cup preset: default or paper.")] = "default",
    seed: Annotated[int | None, typer.Option(help="Base seed of the trials (default: the task's).")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Run the benchmark: seeded trials in simulation, one MCAP log each, and the paper-style table."""

    def body() -> dict[str, Any]:
        from suctionbench.evaluation.runner import run_eval
        from suctionbench.evaluation.tasks import Task, load_task

        if (set_name is None) == (task is None):
            raise InputError("give exactly one of --set S or --task T")
        the_task = load_task(task) if task else Task(name=set_name, set=set_name, trials=trials or 25)
        runs = {}
        if metric is not None:
            metrics = (metric,)
        elif the_task.metrics and policy == "analytic":
            metrics = the_task.metrics  # one run per metric, in out/METRIC
        else:
            metrics = ("rwr",)
        for m in metrics:
            run_dir = out / m if len(metrics) > 1 else out
            count = trials or the_task.trials
            with _progress(count, f"{policy} {m if len(metrics) > 1 else ''}".strip(), not as_json) as advance:
                runs[m] = run_eval(the_task, policy, run_dir, model=model, trials=trials, seed=seed,
                                   workers=_workers(workers), engine=engine, address=address,
                                   metric=m, cup=cup, progress=advance)
        if not as_json:
            known = bool(the_task.metrics)  # the paper's known-objects table: accuracy and Spearman too
            rows = [{"policy": r["label"], "set": r["set"],
                     "trials": r["trials"], "AP": r["ap"], "success": r["success_rate"],
                     **({"accuracy": r["accuracy_q"], "spearman": r["spearman_q"]} if known else {}),
                     "label_precision": r["label_precision"], "picks_per_hour": r["picks_per_hour"],
                     "invalid": r["invalid"]} for m, r in runs.items()]
            _print_rows(f"eval {the_task.name}", rows)
            if known and policy != "analytic":  # executed grasps scored by each 3D metric
                _print_rows("3D metrics against simulated success",
                            [{"metric": m, **stats} for r in runs.values() for m, stats in r["by_metric"].items()])
        return {"out": str(out), "runs": runs} if len(runs) > 1 else {"out": str(out), **next(iter(runs.values()))}

    _run(as_json, body)


@app.command()
def report(
    run_dirs: Annotated[
        list[Path], typer.Argument(help="Run directories from `suctionbench eval`, or directories holding runs.")
    ],
    out: Annotated[Path, typer.Option(help="Report directory (index.html, report.md, figures).")],
    as_json: JsonOpt = False,
) -> None:
    """HTML + Markdown report of eval runs: tables, PR and success-attempt curves, failures."""

    def body() -> dict[str, Any]:
        from suctionbench.evaluation.report import build_report

        result = build_report(run_dirs, out)
        if not as_json:
            for title, rows in result["tables"].items():
                _print_rows(title, rows)
            Console().print(f"report -> {out / 'index.html'}")
        return result

    _run(as_json, body)


@bench_app.command("label")
def bench_label(
    mesh: Annotated[str | None, typer.Option(help="Mesh to label (default: the shipped ~10k-face soap bar).")] = None,
    mass: Annotated[float, typer.Option(help="Object mass in kg.")] = 0.15,
    grasps: Annotated[int, typer.Option(help="Grasps labelled by the fast path.")] = 1000,
    reference_grasps: Annotated[int, typer.Option(help="Of those, grasps also labelled by the reference.")] = 20,
    samples: Annotated[int, typer.Option(help="Monte-Carlo samples J per grasp.")] = 50,
    memory_grasps: Annotated[int, typer.Option(help="Grasps in the peak-memory run.")] = 10000,
    cores: Annotated[int, typer.Option(help="CPU cores the process may use (0 = all).")] = 1,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Robust labels/s of the vectorised path vs the per-sample reference (one QP and one
    ray-cast pass per sample), their agreement, and peak memory."""

    def body() -> dict[str, Any]:
        from suctionbench.bench import bench_label as run_bench

        result = run_bench(
            mesh=mesh, mass=mass, grasps=grasps, reference_grasps=reference_grasps, samples=samples,
            memory_grasps=memory_grasps, cores=cores, seed=seed,
        )
        if not as_json:
            _print_kv("bench label: vectorised vs reference", result)
        return result

    _run(as_json, body)


def _workers(requested: int) -> int:
    """--workers: 0 means every core."""
    return requested or os.cpu_count() or 1


def _print_kv(title: str, result: dict[str, Any]) -> None:
    """A two-column table of a command's result (human output)."""
    table = Table(title=title, show_header=False)
    for key, value in result.items():
        table.add_row(key, f"{value:.4g}" if isinstance(value, float) else str(value))
    Console().print(table)


def _record_row(record: Any) -> dict[str, Any]:
    return {
        "key": record.key,
        "generator": record.generator,
        "faces": record.faces,
        "parts": len(record.parts),
        "mass": record.mass,
        "extents": record.extents,
        "stable_poses": len(record.stable_poses),
    }


def _print_rows(title: str, rows: list[dict[str, Any]]) -> None:
    if not rows:
        err.print(f"{title}: none")
        return
    table = Table(title=title)
    for col in rows[0]:
        table.add_column(col)
    for row in rows:
        table.add_row(*[
            f"{v:.4g}" if isinstance(v, float) else ",".join(f"{x:.3g}" for x in v) if isinstance(v, list) else str(v)
            for v in row.values()
        ])
    Console().print(table)


@objects_app.command("list")
def objects_list(
    set_name: Annotated[str | None, typer.Option("--set", help="Only this set.")] = None,
    as_json: JsonOpt = False,
) -> None:
    """List built objects (evaluation sets and user sets)."""

    def body() -> dict[str, Any]:
        from suctionbench.objects.registry import list_objects

        rows = [_record_row(r) for r in list_objects(set_name)]
        if not as_json:
            _print_rows(f"objects{' in ' + set_name if set_name else ''}", rows)
        return {"count": len(rows), "objects": rows}

    _run(as_json, body)


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
            Console().print(table)
        return {"key": key, "directory": str(record.directory), **data}

    _run(as_json, body)


@objects_app.command("build")
def objects_build(
    set_name: Annotated[str | None, typer.Option("--set", help="Only this evaluation set.")] = None,
    out: Annotated[Path | None, typer.Option(help="Root to build into (default: the shipped assets).")] = None,
    workers: Annotated[int, typer.Option(help="Parallel processes.")] = 2,
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
        start = time.perf_counter()
        with _progress(len(specs), "building", not as_json) as advance:
            records = build_specs(specs, out or assets_root(), workers=workers, progress=advance)
        rows = [_record_row(r) for r in records]
        if not as_json:
            _print_rows("built", rows)
        return {"built": len(records), "seconds": round(time.perf_counter() - start, 1), "objects": rows}

    _run(as_json, body)


@objects_app.command("stats")
def objects_stats(
    set_name: Annotated[str | None, typer.Option("--set", help="Only this set.")] = None,
    grasps: Annotated[int, typer.Option(help="Surface grasps per object.")] = 300,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Per-set difficulty: share of surface grasps that seal and that are robust (rwr > 0.2)."""

    def body() -> dict[str, Any]:
        from suctionbench.objects.registry import list_objects
        from suctionbench.objects.spec import SETS
        from suctionbench.objects.stats import set_stats

        if grasps < 1:
            raise InputError(f"--grasps {grasps}: must be at least 1")
        sets = [set_name] if set_name else list(SETS)
        result = {}
        for name in sets:
            records = list_objects(name)
            with _progress(len(records), name, not as_json) as advance:
                result[name] = set_stats(records, grasps, seed, progress=advance)
        if not as_json:
            _print_rows("object sets", [{"set": k, **{c: v for c, v in r.items() if c != "per_object"}}
                                        for k, r in result.items()])
        return {"grasps_per_object": grasps, "seed": seed, "sets": result}

    _run(as_json, body)


@objects_app.command("import")
def objects_import(
    path: Annotated[str, typer.Argument(help="Mesh file: OBJ, STL, PLY, OFF, GLB.")],
    set_name: Annotated[str, typer.Option("--set", help="User set to add it to.")] = "custom",
    name: Annotated[str, typer.Option(help="Object name (lower case, digits, _ and -).")] = "",
    units: Annotated[str, typer.Option(help="Units of the file: m, cm or mm.")] = "m",
    mass: Annotated[float | None, typer.Option(help="Mass in kg (default: from density, capped).")] = None,
    repair: Annotated[bool, typer.Option(help="Try to close small holes.")] = True,
    overwrite: Annotated[bool, typer.Option(help="Replace an existing object of that name.")] = False,
    root: Annotated[Path | None, typer.Option(help="Object root (default: $SUCTIONBENCH_HOME/objects).")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Import your own mesh: validate, repair small holes, decompose, compute stable poses."""

    def body() -> dict[str, Any]:
        from suctionbench.objects.importer import import_mesh

        record = import_mesh(
            path, set_name=set_name, name=name or Path(path).stem.lower(), units=units, mass=mass,
            try_repair=repair, overwrite=overwrite, root=root,
        )
        row = _record_row(record)
        if not as_json:
            _print_rows("imported", [row])
        return {**row, "directory": str(record.directory)}

    _run(as_json, body)


@objects_app.command("generate")
def objects_generate(
    count: Annotated[int, typer.Option(help="Number of training objects.")] = 1500,
    out: Annotated[Path, typer.Option(help="Corpus directory (objects are cached there).")] = Path("corpus"),
    workers: Annotated[int, typer.Option(help="Parallel processes (0 = all cores).")] = 0,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Generate (or complete) the training corpus; evaluation objects never appear in it."""

    def body() -> dict[str, Any]:
        from suctionbench.objects.corpus_build import generate_corpus

        if count < 1:
            raise InputError(f"--count {count}: must be at least 1")
        with _progress(count, "generating", not as_json) as advance:
            summary = generate_corpus(count, seed, out, workers=_workers(workers), progress=advance)
        if not as_json:
            _print_rows("corpus", [{k: v for k, v in summary.items() if not isinstance(v, dict)}])
        return summary

    _run(as_json, body)


@bench_app.command("episode")
def bench_episode_cmd(
    object_key: Annotated[str, typer.Option("--object", help="Object SET/NAME.")] = "basic/box_tea",
    episodes: Annotated[int, typer.Option(help="Episodes to run (drop placement, analytic policy).")] = 10,
    cores: Annotated[int, typer.Option(help="CPU cores the process may use (0 = all).")] = 1,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Pick episodes per second (rendering the observation included), sim/wall time, render time."""

    def body() -> dict[str, Any]:
        from suctionbench.bench import bench_episode

        result = bench_episode(object_key=object_key, episodes=episodes, cores=cores, seed=seed)
        if not as_json:
            _print_kv("bench episode", result)
        return result

    _run(as_json, body)


@bench_app.command("agreement")
def bench_agreement_cmd(
    sets: Annotated[str, typer.Option("--sets", help="Comma-separated object sets.")] = "basic,typical,adversarial",
    trials: Annotated[int, typer.Option(help="Grasps in total, split over the sets (>= 1 per object).")] = 1000,
    threshold: Annotated[float, typer.Option(help="Analytic rwr above which success is predicted.")] = 0.5,
    workers: Annotated[int, typer.Option(help="Worker processes (0 = all cores).")] = 0,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Analytic labeller vs simulated cup on random reachable grasps: seal agreement, lift accuracy,
    precision / recall, AP and Spearman of rwr, disagreements by cause (report, never tune)."""

    def body() -> dict[str, Any]:
        from suctionbench.evaluation.agreement import run_agreement

        names = tuple(s.strip() for s in sets.split(",") if s.strip())
        if not names:
            raise InputError(f"--sets '{sets}': name at least one object set")
        result = run_agreement(sets=names, trials=trials, seed=seed, threshold=threshold, workers=_workers(workers))
        if not as_json:
            for name, figures in {"all sets": result["overall"], **result["sets"]}.items():
                _print_kv(f"analytic rwr > {threshold} vs simulated success ({name})",
                          {k: v for k, v in figures.items() if k != "per_trial"})
        return result

    _run(as_json, body)


@bench_app.command("generate")
def bench_generate_cmd(
    objects: Annotated[str, typer.Option(help="Object set or directory.")] = "typical",
    datapoints: Annotated[int, typer.Option(help="Datapoints per run.")] = 3000,
    workers: Annotated[int, typer.Option(help="Workers of the parallel run (0 = all cores).")] = 0,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Dataset generation datapoints/s (all cores vs one), render ms/frame, label ms/grasp, memory."""

    def body() -> dict[str, Any]:
        from suctionbench.bench import bench_generate

        result = bench_generate(objects=objects, datapoints=datapoints, workers=_workers(workers),
                                seed=seed)
        if not as_json:
            _print_kv("bench generate", result)
        return result

    _run(as_json, body)


@bench_app.command("plan")
def bench_plan_cmd(
    policies: Annotated[str, typer.Option(help="Comma-separated image policies.")] = (
        "random,centroid,planarity,planarity-centroid,gqcnn"
    ),
    model: Annotated[str | None, typer.Option(help="GQ-CNN model directory (default: the shipped one).")] = None,
    scenes: Annotated[int, typer.Option(help="Rendered scenes (typical objects) per policy.")] = 5,
    cores: Annotated[int, typer.Option(help="CPU cores the process may use (0 = all).")] = 0,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Seconds per planned grasp for each policy (gqcnn also against unbatched network calls)."""

    def body() -> dict[str, Any]:
        from suctionbench.bench import bench_plan

        if scenes < 1:
            raise InputError(f"--scenes {scenes}: must be at least 1")
        result = bench_plan(policies=[p for p in policies.split(",") if p], model=model, scenes=scenes, seed=seed,
                            cores=cores)
        if not as_json:
            _print_kv("bench plan", result)
        return result

    _run(as_json, body)


@contextmanager
def _train_progress(enabled: bool) -> Iterator[Callable[[Any], None]]:
    """A rich progress bar over training images with the epoch, loss and accuracy; a no-op off a terminal."""
    if not enabled or not err.is_terminal:
        yield lambda _update: None
        return
    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), _RateColumn(),
               TimeRemainingColumn())
    with Progress(*columns, console=err, transient=True) as bar:
        task = bar.add_task("training", total=None)

        def update(u: Any) -> None:
            bar.update(task, total=u.images_total, completed=u.images_done,
                       description=f"epoch {u.epoch}/{u.epochs} loss {u.loss:.4f} acc {u.accuracy:.3f}")

        yield update


@app.command("train")
def train_cmd(
    dataset: Annotated[Path, typer.Option(help="Dataset directory (from `suctionbench generate`).")],
    out: Annotated[Path, typer.Option(help="Output directory: model.safetensors, model.json, checkpoints.")],
    arch: Annotated[str, typer.Option(help="Network: dn3 (Dex-Net 3.0 GQ-CNN) or compact (CPU friendly).")] = "dn3",
    epochs: Annotated[int, typer.Option(help="Training epochs (gqcnn: 25).")] = 25,
    device: Annotated[str, typer.Option(help="cpu, or cuda (bfloat16 mixed precision).")] = "cpu",
    split: Annotated[str, typer.Option(help="Split: image_wise or object_wise.")] = "image_wise",
    batch_size: Annotated[int, typer.Option(help="Training batch size (gqcnn: 64).")] = 64,
    max_datapoints: Annotated[int | None, typer.Option(help="Train on a random subset of this many.")] = None,
    augment: Annotated[bool, typer.Option(help="Noise and symmetrisation augmentation (gqcnn's).")] = True,
    overwrite: Annotated[bool, typer.Option(help="Discard a run already in --out instead of resuming it.")] = False,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Train a GQ-CNN on a dataset; resumes a run of the same configuration found in --out."""

    def body() -> dict[str, Any]:
        import shlex

        from suctionbench.learning.data import AUGMENT_GQCNN, AUGMENT_OFF
        from suctionbench.learning.train import TrainConfig, train

        config = TrainConfig(arch=arch, epochs=epochs, device=device, split=split, batch_size=batch_size,
                             max_train_datapoints=max_datapoints, augment=AUGMENT_GQCNN if augment else AUGMENT_OFF,
                             seed=seed)
        # Every option spelled out, defaults included: the card's command reproduces the run even if defaults change.
        command = shlex.join([
            "suctionbench", "train", "--dataset", str(dataset), "--out", str(out), "--arch", arch, "--epochs",
            str(epochs), "--device", device, "--split", split, "--batch-size", str(batch_size),
            *(["--max-datapoints", str(max_datapoints)] if max_datapoints else []),
            "--augment" if augment else "--no-augment", "--seed", str(seed),
        ])
        with _train_progress(not as_json) as update:
            metrics = train(dataset, out, config, progress=update, command=command, overwrite=overwrite)
        if not as_json:
            keys = ("arch", "epochs", "train_accuracy", "val_accuracy", "val_ap", "train_images_per_s", "out")
            _print_rows("trained", [{k: metrics[k] for k in keys}])
        return metrics

    _run(as_json, body)


model_app = typer.Typer(no_args_is_help=True, help="Inspect trained GQ-CNN models.")
app.add_typer(model_app, name="model")


@model_app.command("show")
def model_show(
    directory: Annotated[Path, typer.Argument(help="Model directory (model.json + model.safetensors).")],
    as_json: JsonOpt = False,
) -> None:
    """Architecture, size, metrics, dataset, camera and cup of a trained model (weights are verified)."""

    def body() -> dict[str, Any]:
        from suctionbench.learning.checkpoint import load_model

        card = load_model(directory).card
        metrics, training, data = card.get("metrics", {}), card.get("training", {}), card.get("dataset", {})
        summary = {
            "arch": card["arch"], "parameters": card.get("parameters"), "macs_per_grasp": card.get("macs_per_grasp"),
            "status": training.get("status"), "epochs": training.get("epochs_completed"),
            "train_accuracy": metrics.get("train_accuracy"), "val_accuracy": metrics.get("val_accuracy"),
            "val_ap": metrics.get("val_ap"), "label_threshold": card.get("label", {}).get("threshold"),
            "dataset": data.get("path"), "split": data.get("split"), "num_train": data.get("num_train"),
            "num_val": data.get("num_val"), "camera": (data.get("camera") or {}).get("name"),
            "cup": (data.get("cup") or {}).get("name"), "train_seconds": training.get("train_seconds"),
            "train_images_per_s": training.get("train_images_per_s"), "device": training.get("device"),
            "command": card.get("command"), "versions": card.get("versions"),
        }
        if not as_json:
            _print_kv(str(directory), summary)
        return summary

    _run(as_json, body)


def main() -> None:
    """Console-script entry point."""
    app()


if __name__ == "__main__":
    main()
