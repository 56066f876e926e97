"""`suctionbench eval` (the benchmark) and `suctionbench report`."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from suctionbench.cli.common import (
    JsonOpt,
    app,
    console,
    note,
    print_rows,
    progress_bar,
    resolve_workers,
    run_command,
)
from suctionbench.cli.plan import PolicyArgOpt
from suctionbench.errors import InputError


@app.command("eval")
def eval_cmd(
    policy: Annotated[
        str, typer.Option(help="Policy: gqcnn, planarity-centroid, centroid, planarity, random, analytic, "
                               "analytic-image, analytic-image-uniform, random-surface, an installed plug-in's name, "
                               "PATH.py:FACTORY or package.module:FACTORY.")
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
    camera: Annotated[
        str, typer.Option(help="Camera preset (suctionbench cameras) or intrinsics TOML.")
    ] = "primesense",
    policy_arg: PolicyArgOpt = None,
    seed: Annotated[int | None, typer.Option(help="Base seed of the trials (default: the task's).")] = None,
    masks: Annotated[str, typer.Option(help="Bin tasks: object regions from 'depth' segmentation or the "
                                            "renderer's 'oracle' instance masks.")] = "depth",
    resume: Annotated[bool, typer.Option(help="Finish an interrupted run (OUT.incomplete) of the same "
                                              "configuration, keeping its finished trials. With none there, "
                                              "the run starts afresh and says so: a 'note:' line on stderr "
                                              "and \"resumed\": false in the JSON (so the same command can "
                                              "be rerun until the run is done).")] = False,
    overwrite: Annotated[bool, typer.Option(help="Replace a run already in --out (or an interrupted one).")] = False,
    as_json: JsonOpt = False,
) -> None:
    """Run the benchmark: seeded trials in simulation, one MCAP log each, and the paper-style table.

    The run appears in --out only when every trial is logged (until then it is OUT.incomplete)."""

    def body() -> dict[str, Any]:
        from suctionbench.evaluation.runner import run_eval
        from suctionbench.evaluation.tasks import Task, is_bin_task, load_task
        from suctionbench.policies.plugins import parse_policy_args

        options = parse_policy_args(policy_arg or [])
        if (set_name is None) == (task is None):
            raise InputError("give exactly one of --set S or --task T")
        if task is not None and is_bin_task(task):
            return _bin_eval(task, policy, out, model=model, trials=trials, seed=seed, workers=workers, engine=engine,
                             address=address, masks=masks, cup=cup, camera=camera, options=options,
                             overwrite=overwrite, resume=resume, as_json=as_json)
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
            with progress_bar(count, f"{policy} {m if len(metrics) > 1 else ''}".strip(), not as_json) as advance:
                runs[m] = run_eval(the_task, policy, run_dir, model=model, trials=trials, seed=seed,
                                   workers=resolve_workers(workers), engine=engine, address=address,
                                   metric=m, cup=cup, camera=camera, policy_args=options, resume=resume,
                                   overwrite=overwrite, progress=advance, notify=note)
        if not as_json:
            known = bool(the_task.metrics)  # the paper's known-objects table: accuracy and Spearman too
            pct = _percent  # percentages and short headers: 80 columns hold the table
            rows = [{"policy": r["label"], "set": r["set"], "n": r["trials"], "AP%": pct(r["ap"]),
                     "succ%": pct(r["success_rate"]),
                     **({"acc%": pct(r["accuracy_q"]), "rho": r["spearman_q"]} if known else {}),
                     "prec%": pct(r["label_precision"]), "picks/h": r["picks_per_hour"],
                     "inv": r["invalid"]} for m, r in runs.items()]
            print_rows(f"eval {the_task.name}", rows)
            console().print("n: trials; AP%: average precision of q; succ%: success rate; "
                            + ("acc%: accuracy of q > 0.5; rho: Spearman of q; " if known else "")
                            + "prec%: success among grasps labelled robust (rwr > 0.5); picks/h: picks per hour "
                            "(simulated motion + modelled compute); inv: invalid trials", highlight=False)
            if known and policy != "analytic":  # executed grasps scored by each 3D metric
                print_rows("3D metrics against simulated success",
                            [{"metric": m, **stats} for r in runs.values() for m, stats in r["by_metric"].items()])
        return {"out": str(out), "runs": runs} if len(runs) > 1 else {"out": str(out), **next(iter(runs.values()))}

    run_command(as_json, body)


def _bin_eval(task: str, policy: str, out: Path, *, model: str | None, trials: int | None, seed: int | None,
              workers: int, engine: str, address: str | None, masks: str, cup: str, camera: str,
              options: dict[str, Any], overwrite: bool, resume: bool, as_json: bool) -> dict[str, Any]:
    """`eval --task bin-*`: the cluttered-bin benchmark (suctionbench.clutter)."""
    from suctionbench.clutter.benchmark import run_bin_eval
    from suctionbench.clutter.tasks import load_bin_task

    if resume:
        raise InputError("--resume: bin runs are written whole; rerun with --overwrite")
    the_task = load_bin_task(task)
    count = trials or the_task.trials
    with progress_bar(count, f"{policy} bins", not as_json) as advance:
        run = run_bin_eval(the_task, policy, out, model=model, trials=trials, seed=seed,
                           workers=resolve_workers(workers), engine=engine, address=address, masks=masks, cup=cup,
                           camera=camera, policy_args=options, overwrite=overwrite, progress=advance)
    if not as_json:
        m = run["metrics"]
        print_rows(f"eval {the_task.name} ({masks} masks)", [{
            "policy": policy, "bins": m["bins"], "objects": m["objects"], "clear%": _percent(m["clearance"]),
            "att": m["attempts"], "succ%": _percent(m["success_per_attempt"]), "att/obj": m["attempts_per_object"],
            "picks/h": m["picks_per_hour"], "prec%": _percent(m["label_precision"])}])
        console().print("clear%: objects removed; succ%: successful attempts; att/obj: attempts per object "
                        "removed; picks/h: objects removed per hour (simulated motion + modelled compute); "
                        "prec%: success among grasps labelled robust", highlight=False)
        print_rows("failure reasons", [{"reason": k, "attempts": v} for k, v in m["failures"].items()])
    return run


def _percent(value: float | None) -> str:
    return "-" if value is None else f"{100 * value:.1f}"


@app.command()
def report(
    run_dirs: Annotated[
        list[Path], typer.Argument(help="Run directories from `suctionbench eval`, or directories holding runs.")
    ],
    out: Annotated[Path, typer.Option(help="Report directory (index.html, report.md, figures).")],
    allow_incomplete: Annotated[bool, typer.Option(help="Report interrupted runs, marked incomplete, instead of "
                                                        "refusing them.")] = False,
    as_json: JsonOpt = False,
) -> None:
    """HTML + Markdown report of eval runs: tables, PR and success-attempt curves, failures."""

    def body() -> dict[str, Any]:
        from suctionbench.evaluation.report import build_report

        result = build_report(run_dirs, out, allow_incomplete=allow_incomplete)
        if not as_json:
            for title, rows in result["tables"].items():
                print_rows(title, rows)
            console().print(f"report -> {out / 'index.html'}")
        return result

    run_command(as_json, body)
