"""`suctionbench generate` (datasets) and `suctionbench dataset show`."""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from suctionbench.cli.common import (
    JsonOpt,
    SeedOpt,
    app,
    dataset_app,
    note,
    print_kv,
    print_rows,
    progress_bar,
    resolve_workers,
    run_command,
)
from suctionbench.errors import InputError
from suctionbench.io import bytes_under
from suctionbench.validate import BYTES_PER_DATAPOINT, label_memory, output_dir, require_disk, require_memory

LOADS = ("episode", "static")
"""What `generate --load` accepts."""


def label_config(cup: Any, load: str) -> Any:
    """The labels' configuration for `generate --load`: the episode's loads or the paper's static one."""
    from suctionbench.config import LabelConfig

    if load not in LOADS:
        raise InputError(f"--load '{load}': unknown (known: {', '.join(LOADS)})")
    return LabelConfig.for_episode(cup) if load == "episode" else LabelConfig(cup=cup)


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
    grasps_per_image: Annotated[int, typer.Option(help="At most this many of an image's visible candidates "
                                                       "recorded, drawn at random (0 = all): many candidates "
                                                       "per object, spread over many images.")] = 0,
    cup: Annotated[str, typer.Option(help="Cup preset: default or paper.")] = "default",
    load: Annotated[str, typer.Option(help="Loads the labels test: episode (the pick's inertial load, its "
                                           "arrivals and the touch-down's press: what the benchmark scores) or "
                                           "static (the paper's quasi-static gravity).")] = "episode",
    scene: Annotated[str, typer.Option(help="table (one object in a stable pose, the paper's) or bin (a cluttered "
                                            "bin per 1,000 datapoints: grasps labelled on their own object, "
                                            "0 where the gripper's path meets a neighbour or a wall).")] = "table",
    noise: Annotated[str, typer.Option(help="Image noise: paper (Dex-Net's: a ~3 % scale error and a correlated "
                                            "~4 mm field), sensor (the simulated camera's per-pixel noise, "
                                            "what the benchmark's robot sees) or none (an ideal sensor; "
                                            "otherwise the sensor dataset's twin).")] = "paper",
    thumbnail_sampling: Annotated[str, typer.Option(help="What a grasp thumbnail pixel holds: point (the depth at "
                                                         "its 3 x 3 block's centre, gqcnn's) or mean (the block's "
                                                         "mean depth).")] = "point",
    thumbnail_crop: Annotated[int, typer.Option(help="Image pixels the 32 x 32 grasp thumbnail spans (gqcnn's 96: "
                                                     "3 image pixels a thumbnail pixel; 64 or 32 see the cup's "
                                                     "~13 px footprint finer, in a smaller field).")] = 96,
    max_images_per_object: Annotated[int, typer.Option(help="An object whose visible candidates cannot fill its "
                                                            "share of --datapoints stops after this many images "
                                                            "(the dataset is then smaller; a note says so).")] = 400,
    proposals: Annotated[Path | None, typer.Option(help="A trained model's directory: label its dense policy's best "
                                                       "grasps on every image too (on-policy data).")] = None,
    proposals_per_image: Annotated[int, typer.Option(help="With --proposals: the policy's best grasps per image "
                                                          "(at least 1 cm apart).")] = 8,
    holdout_like: Annotated[Path | None, typer.Option(help="Another dataset of the same objects, or a model "
                                                          "trained on one: hold out its held-out objects "
                                                          "(object-wise split) rather than draw new ones, so both "
                                                          "can train one model.")] = None,
    resume: Annotated[bool, typer.Option(help="Continue an interrupted run with the same configuration.")] = False,
    overwrite: Annotated[bool, typer.Option(help="Replace an existing dataset.")] = False,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Generate a Dex-Net-style dataset: rendered noisy depth thumbnails with robust labels."""

    def body() -> dict[str, Any]:
        from suctionbench.config import cup_preset
        from suctionbench.dataset.generate import GenerationConfig, generate_dataset
        from suctionbench.objects.registry import resolve_objects
        from suctionbench.sensing.thumbnails import SAMPLINGS, THUMBNAIL_GQCNN

        label = label_config(cup_preset(cup), load)
        if thumbnail_sampling not in SAMPLINGS:
            raise InputError(f"--thumbnail-sampling '{thumbnail_sampling}': unknown (known: {', '.join(SAMPLINGS)})")
        if proposals is not None and scene != "table":
            raise InputError(f"--proposals with --scene {scene}: on-policy grasps are proposed on table scenes only")
        output_dir(out, "--out")
        held = bytes_under(out) if resume else 0  # a resumed run keeps (or rewrites in place) what is there
        require_disk(out, max(datapoints * BYTES_PER_DATAPOINT - held, 0), f"--datapoints {datapoints}")
        require_memory(label_memory(grasps_per_object, label.perturbation.num_samples)
                       * resolve_workers(workers), f"--grasps-per-object {grasps_per_object} x --workers")
        records = resolve_objects(objects)
        try:
            thumbnail = dataclasses.replace(THUMBNAIL_GQCNN, crop_size=thumbnail_crop, sampling=thumbnail_sampling)
        except InputError as exc:
            raise InputError(f"--thumbnail-crop {thumbnail_crop} with --thumbnail-sampling {thumbnail_sampling}: "
                             f"{exc}") from None
        config = GenerationConfig(
            datapoints=datapoints, seed=seed, grasps_per_object=grasps_per_object,
            grasps_per_image=grasps_per_image,
            label=label, scene=scene, noise_model=noise, thumbnail=thumbnail,
            proposals=None if proposals is None else str(proposals.resolve()),
            proposals_per_image=proposals_per_image, max_images_per_object=max_images_per_object,
        )
        start = time.perf_counter()
        with progress_bar(datapoints, "generating", not as_json) as advance:
            card = generate_dataset(
                out, [str(r.directory) for r in records], [r.key for r in records], camera, config,
                engine=engine, workers=resolve_workers(workers), address=address, resume=resume,
                overwrite=overwrite, progress=advance, holdout_like=holdout_like,
            )
        elapsed = time.perf_counter() - start
        summary = {k: card[k] for k in ("datapoints", "shards", "positive_rate", "fingerprint")}
        summary.update(out=str(out), seconds=round(elapsed, 2), datapoints_per_s=round(card["datapoints"] / elapsed, 1),
                       regenerated_corrupt_units=len(card.get("regenerated_corrupt_units", [])))
        summary["short_units"] = len(card.get("short_units", []))
        if not as_json:
            print_rows("dataset", [summary])
        if card["datapoints"] < datapoints:
            note(short_dataset_note(card, datapoints, max_images_per_object))
        return summary

    run_command(as_json, body)


def short_dataset_note(card: dict[str, Any], requested: int, max_images: int) -> str:
    """The note a dataset smaller than asked gets: how much, which units stopped short, the remedy."""
    short = card.get("short_units", [])
    names = ", ".join(f"{u['object'] or 'bin ' + str(u['unit'])} {u['datapoints']:,} of {u['quota']:,}"
                      for u in short[:5]) + (f" and {len(short) - 5} more" if len(short) > 5 else "")
    head = f"the dataset holds {card['datapoints']:,} of the {requested:,} datapoints asked for: "
    if card.get("config", {}).get("scene") == "bin":
        return head + f"{len(short)} bin(s) showed fewer visible grasps than their share ({names})"
    return (head + f"{len(short)} object(s) stopped at --max-images-per-object {max_images} short of their "
            f"share ({names}); raise it, or --grasps-per-image, for more")


@dataset_app.command("show")
def dataset_show(
    directory: Annotated[Path, typer.Argument(help="Dataset directory.")],
    thumbnails: Annotated[
        Path | None, typer.Option(help="Save 16 thumbnails (all, if fewer) with labels to this PNG.")
    ] = None,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Counts, positive rate, camera, image noise, grasp-thumbnail cut and objects of a dataset;
    optionally a thumbnail sheet."""

    def body() -> dict[str, Any]:
        from suctionbench.dataset.storage import DatasetReader, read_card
        from suctionbench.dataset.verify import check_dataset, record_check
        from suctionbench.learning.data import dataset_noise_model, dataset_thumbnail, label_threshold
        from suctionbench.sensing.thumbnails import describe_thumbnail

        checked = check_dataset(directory)  # manifests, hashes, shapes, finite labels, splits: else exit 2
        card = read_card(directory)
        reader = DatasetReader(directory)
        summary = {
            "datapoints": reader.num_datapoints, "shards": reader.num_shards,
            "positive_rate": card.get("positive_rate"), "camera": card.get("camera", {}).get("name"),
            "objects": len(card.get("objects", [])), "status": card.get("status"),
            "threshold": label_threshold(card), "noise": dataset_noise_model(card),
            "grasp_thumbnail": describe_thumbnail(dataset_thumbnail(card, f"dataset '{directory}'")),
        }
        generation = card.get("generation") or {}  # time and size (datasets generated since it was recorded)
        summary.update({f"generation_{key}": generation.get(key) for key in
                        ("recorded_seconds", "datapoints_per_s", "untimed_units", "bytes")})
        if thumbnails is not None:
            from suctionbench.sensing.image import save_png
            from suctionbench.sensing.thumbnails import to_uint8_grid

            shard = reader.shard(0)
            rng = np.random.default_rng(seed)
            size = len(shard["robust_suction_wrench_resistance"])
            pick = rng.choice(size, size=min(16, size), replace=False)  # a dataset may hold fewer than 16
            labels = shard["robust_suction_wrench_resistance"][pick] > summary["threshold"]
            save_png(thumbnails, to_uint8_grid(shard["depth_ims_tf_table"][pick, ..., 0], labels))
            summary["thumbnails"] = str(thumbnails)
        record_check(directory, checked)
        if not as_json:
            print_kv(str(directory), summary)  # one dataset: a row per fact, readable at 80 columns
        return summary

    run_command(as_json, body)
