"""`suctionbench bench label|episode|bin|agreement|generate|plan|import|train`: speed and agreement figures."""

from __future__ import annotations

from typing import Annotated, Any

import typer

from suctionbench.cli.common import (
    JsonOpt,
    SeedOpt,
    UnitsOpt,
    bench_app,
    print_kv,
    print_rows,
    resolve_workers,
    run_command,
)
from suctionbench.errors import InputError


def _run_bench(as_json: bool, title: str, function: str, **kwargs: Any) -> None:
    """Run `suctionbench.bench.<function>(**kwargs)` as the command: its result printed as key-values
    under `title` (or as the JSON line). The module is imported only when the command runs."""

    def body() -> dict[str, Any]:
        from suctionbench import bench

        result = getattr(bench, function)(**kwargs)
        if not as_json:
            print_kv(title, result)
        return result

    run_command(as_json, body)


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

    _run_bench(as_json, "bench label: vectorised vs reference", "bench_label", mesh=mesh, mass=mass, grasps=grasps,
               reference_grasps=reference_grasps, samples=samples, memory_grasps=memory_grasps, cores=cores,
               seed=seed)


@bench_app.command("bin")
def bench_bin_cmd(
    counts: Annotated[str, typer.Option(help="Bin sizes to time, comma-separated object counts.")] = "3,6,10,15",
    policy: Annotated[str, typer.Option(help="Policy planning the attempts.")] = "planarity-centroid",
    attempts: Annotated[int, typer.Option(help="Attempts timed per bin size.")] = 3,
    cores: Annotated[int, typer.Option(help="CPU cores the process may use (0 = all).")] = 1,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """A pick in clutter: seconds per attempt and to fill the bin, per object count, against a
    single-object pick of the same policy in the same run."""

    def body() -> dict[str, Any]:
        from suctionbench.bench import bench_bin

        try:
            sizes = [int(c) for c in counts.split(",") if c.strip()]
        except ValueError:
            raise InputError(f"--counts '{counts}': expected comma-separated integers") from None
        result = bench_bin(counts=sizes, policy=policy, attempts=attempts, seed=seed, cores=cores)
        if not as_json:
            print_rows(f"bench bin ({policy}, {result['cores']} core(s))", result["rows"])
        return result

    run_command(as_json, body)


@bench_app.command("episode")
def bench_episode_cmd(
    object_key: Annotated[str, typer.Option("--object", help="Object SET/NAME.")] = "basic/box_tea",
    episodes: Annotated[int, typer.Option(help="Episodes to run (drop placement, analytic policy).")] = 10,
    cores: Annotated[int, typer.Option(help="CPU cores the process may use (0 = all).")] = 1,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Pick episodes per second (rendering the observation included), sim/wall time, render time."""

    _run_bench(as_json, "bench episode", "bench_episode", object_key=object_key, episodes=episodes, cores=cores,
               seed=seed)


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
        result = run_agreement(sets=names, trials=trials, seed=seed, threshold=threshold,
                               workers=resolve_workers(workers))
        if not as_json:
            for name, figures in {"all sets": result["overall"], **result["sets"]}.items():
                print_kv(f"analytic rwr > {threshold} vs simulated success ({name})",
                          {k: v for k, v in figures.items() if k != "per_trial"})
        return result

    run_command(as_json, body)


@bench_app.command("generate")
def bench_generate_cmd(
    objects: Annotated[str, typer.Option(help="Object set or directory.")] = "typical",
    datapoints: Annotated[int, typer.Option(help="Datapoints per run.")] = 3000,
    workers: Annotated[int, typer.Option(help="Workers of the parallel run (0 = all cores).")] = 0,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Dataset generation datapoints/s and shard assembly s (all cores vs one, same shards), render ms/frame,
    label ms/grasp, memory."""

    _run_bench(as_json, "bench generate", "bench_generate", objects=objects, datapoints=datapoints,
               workers=resolve_workers(workers), seed=seed)


@bench_app.command("plan")
def bench_plan_cmd(
    policies: Annotated[str, typer.Option(help="Comma-separated image policies.")] = (
        "random,centroid,planarity,planarity-centroid,gqcnn,fc-gqcnn"
    ),
    model: Annotated[str | None, typer.Option(help="GQ-CNN model directory (default: the shipped one).")] = None,
    scenes: Annotated[int, typer.Option(help="Rendered scenes (typical objects) per policy.")] = 5,
    cores: Annotated[int, typer.Option(help="CPU cores the process may use (0 = all).")] = 0,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Seconds per planned grasp for each policy (gqcnn also against unbatched network calls,
    fc-gqcnn against scoring every window of its lattices)."""

    def body() -> dict[str, Any]:
        from suctionbench.bench import bench_plan

        if scenes < 1:
            raise InputError(f"--scenes {scenes}: must be at least 1")
        names = [p.strip() for p in policies.split(",") if p.strip()]
        if not names:
            raise InputError(f"--policies '{policies}': name at least one policy")
        if model is not None:
            from suctionbench.learning.checkpoint import load_model

            load_model(model)  # a missing or corrupt model fails before any timing
        result = bench_plan(policies=names, model=model, scenes=scenes, seed=seed,
                            cores=cores)
        if not as_json:
            print_kv("bench plan", result)
        return result

    run_command(as_json, body)


@bench_app.command("import")
def bench_import_cmd(
    mesh: Annotated[str, typer.Argument(help="Mesh file to import (OBJ, STL, PLY, OFF, GLB, GLTF).")],
    units: UnitsOpt = "auto",
    scale: Annotated[float, typer.Option(help="Extra scale factor on top of --units.")] = 1.0,
    cores: Annotated[int, typer.Option(help="CPU cores the process may use (0 = all).")] = 0,
    as_json: JsonOpt = False,
) -> None:
    """Seconds to import a mesh with the convex decomposition's tries side by side against one
    after another (the reference), in one run, and whether both give the same object."""

    _run_bench(as_json, "bench import: side by side vs one by one", "bench_import", mesh=mesh, units=units,
               scale=scale, cores=cores)


@bench_app.command("train")
def bench_train_cmd(
    archs: Annotated[str, typer.Option(help="Comma-separated networks to time.")] = "dn3,context-pose",
    datapoints: Annotated[int, typer.Option(help="Random thumbnails written and trained on `--device`.")] = 20000,
    reference_datapoints: Annotated[int, typer.Option(help="Of those, the ones the CPU reference trains on.")] = 5000,
    device: Annotated[str, typer.Option(help="Device timed against the CPU: cuda (bfloat16) or cpu.")] = "cuda",
    batch_size: Annotated[int, typer.Option(help="Datapoints per SGD step (gqcnn: 64).")] = 64,
    cores: Annotated[int, typer.Option(help="CPU cores the process may use (0 = all).")] = 0,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Training images/s of each network on the GPU (bfloat16) against the CPU (float32) in one
    run, and the hours the Dex-Net 3.0 schedule (25 epochs of 2.8 M datapoints) takes at each."""

    names = [a.strip() for a in archs.split(",") if a.strip()]
    _run_bench(as_json, "bench train: --device vs cpu", "bench_train", archs=names, datapoints=datapoints,
               reference_datapoints=reference_datapoints, device=device, batch_size=batch_size, seed=seed,
               cores=cores)
