"""`suctionbench train`, `suctionbench model show` and `suctionbench model score`."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

from suctionbench.cli.common import (
    JsonOpt,
    RateColumn,
    SeedOpt,
    app,
    err,
    model_app,
    print_kv,
    print_rows,
    run_command,
)


@contextmanager
def _train_progress(enabled: bool) -> Iterator[Callable[[Any], None]]:
    """A rich progress bar over training images with the epoch, loss and accuracy; a no-op off a terminal."""
    if not enabled or not err.is_terminal:
        yield lambda _update: None
        return
    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), RateColumn(),
               TimeRemainingColumn())
    with Progress(*columns, console=err, transient=True) as bar:
        task = bar.add_task("training", total=None)

        def update(u: Any) -> None:
            bar.update(task, total=u.images_total, completed=u.images_done,
                       description=f"epoch {u.epoch}/{u.epochs} loss {u.loss:.4f} acc {u.accuracy:.3f}")

        yield update


def train_command(dataset: Path | str, out: Path | str, config: Any) -> str:
    """The `suctionbench train` command line that runs `config` (a TrainConfig made from this
    command's options) on `dataset` into `out`, every option spelled out, defaults included: the
    model card's command reproduces the run even if defaults change. The exception is
    --learning-rate, named only off gqcnn's rate (TrainConfig's default), so a default run's
    command reads as it did before the option existed."""
    import shlex

    from suctionbench.learning.train_config import TrainConfig

    return shlex.join([
        "suctionbench", "train", "--dataset", str(dataset), "--out", str(out), "--arch", config.arch, "--epochs",
        str(config.epochs), "--device", config.device, "--split", config.split, "--batch-size", str(config.batch_size),
        *(["--max-datapoints", str(config.max_train_datapoints)] if config.max_train_datapoints else []),
        *(["--max-objects", str(config.max_train_objects)] if config.max_train_objects else []),
        *(["--train-objects", config.train_objects] if config.train_objects is not None else []),
        *(["--max-val-datapoints", str(config.max_val_datapoints)] if config.max_val_datapoints else []),
        "--augment" if config.augment.enabled else "--no-augment",
        *(["--no-augment-noise"] if config.augment.enabled and not config.augment.noise else []),
        "--target", config.target,
        "--seed", str(config.seed),
        *(["--init", config.init] if config.init else []),
        *(["--learning-rate", str(config.learning_rate)] if config.learning_rate != TrainConfig.learning_rate else []),
        *(["--average", str(config.average)] if config.average is not None else []),
        "--load-threads", str(config.load_threads),
    ])


@app.command("train")
def train_cmd(
    dataset: Annotated[Path, typer.Option(help="Dataset directory (from `suctionbench generate`).")],
    out: Annotated[Path, typer.Option(help="Output directory: model.safetensors, model.json, checkpoints.")],
    arch: Annotated[str, typer.Option(help="Network: dn3 (Dex-Net 3.0 GQ-CNN), compact (CPU friendly), "
                                           "context / context-wide (also read the context thumbnail), or "
                                           "context-pose (context, plus the object context in metres; "
                                           "context-pose-wide: twice its widths).")] = "dn3",
    epochs: Annotated[int, typer.Option(help="Training epochs (gqcnn: 25).")] = 25,
    device: Annotated[str, typer.Option(help="cpu, or cuda (bfloat16 mixed precision).")] = "cpu",
    split: Annotated[str, typer.Option(help="Split: image_wise or object_wise.")] = "image_wise",
    batch_size: Annotated[int, typer.Option(help="Training batch size (gqcnn: 64).")] = 64,
    max_datapoints: Annotated[int | None, typer.Option(help="Train on a random subset of this many.")] = None,
    max_objects: Annotated[int | None, typer.Option(
        help="Train only on the datapoints of a random subset of this many training objects (before "
             "--max-datapoints: with both, object diversity at a fixed datapoint count).")] = None,
    train_objects: Annotated[str | None, typer.Option(
        help="Train only on the training objects whose key matches this shell pattern, e.g. '*household*' "
             "(before --max-objects and --max-datapoints; the held-out side is not filtered).")] = None,
    max_val_datapoints: Annotated[int | None, typer.Option(
        help="Validate on a random subset of this many (after every epoch).")] = None,
    augment: Annotated[bool, typer.Option(help="Noise and symmetrisation augmentation (gqcnn's).")] = True,
    augment_noise: Annotated[bool, typer.Option(help="With --augment: the paper's noise on every training image "
                                                     "too (--no-augment-noise: flips only, for data rendered with "
                                                     "`generate --noise sensor`).")] = True,
    target: Annotated[str, typer.Option(help="What the loss fits: binary (gqcnn's: robust label > threshold) or "
                                             "soft (the robust label itself, as a probability).")] = "binary",
    init: Annotated[str | None, typer.Option(help="Fine-tune: start from this trained model's weights and input "
                                                  "normalisation (same --arch, or a wider one of its layout, "
                                                  "which grows it keeping its function: Net2Net).")] = None,
    learning_rate: Annotated[float, typer.Option(
        help="Base learning rate, decayed by gqcnn's staircase (gqcnn: 0.01); with --init, e.g. the rate the "
             "model's own run ended at.")] = 0.01,
    average: Annotated[float | None, typer.Option(help="Score and save an exponential moving average of the weights "
                                                       "with this decay per step (e.g. 0.9995); default: the last "
                                                       "iterate.")] = None,
    load_threads: Annotated[int, typer.Option(help="Threads reading the dataset's shards (more keep a GPU fed; "
                                                   "the data order and the weights do not change).")] = 1,
    overwrite: Annotated[bool, typer.Option(help="Discard a run already in --out instead of resuming it.")] = False,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Train a GQ-CNN on a dataset; resumes a run of the same configuration found in --out."""

    def body() -> dict[str, Any]:
        from suctionbench.dataset.verify import check_dataset, record_check
        from suctionbench.learning.data import AUGMENT_FLIPS, AUGMENT_GQCNN, AUGMENT_OFF
        from suctionbench.learning.train import train
        from suctionbench.learning.train_config import TrainConfig

        checked = check_dataset(dataset)  # never train on a damaged dataset or NaN labels

        config = TrainConfig(arch=arch, epochs=epochs, device=device, split=split, batch_size=batch_size,
                             max_train_datapoints=max_datapoints, max_train_objects=max_objects,
                             train_objects=train_objects,
                             max_val_datapoints=max_val_datapoints,
                             augment=(AUGMENT_GQCNN if augment_noise else AUGMENT_FLIPS) if augment else AUGMENT_OFF,
                             target=target, seed=seed,
                             init=init, learning_rate=learning_rate, average=average,
                             load_threads=load_threads)
        with _train_progress(not as_json) as update:
            metrics = train(dataset, out, config, progress=update, command=train_command(dataset, out, config),
                            overwrite=overwrite)
        record_check(dataset, checked)
        if not as_json:
            keys = ("arch", "epochs", "train_accuracy", "val_accuracy", "val_ap", "train_images_per_s", "out")
            print_rows("trained", [{k: metrics[k] for k in keys}])
        return metrics

    run_command(as_json, body)



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
            print_kv(str(directory), summary)
        return summary

    run_command(as_json, body)


@model_app.command("score")
def model_score(
    directory: Annotated[Path, typer.Argument(help="Model directory (model.json + model.safetensors).")],
    dataset: Annotated[Path, typer.Option(help="Dataset directory to score it on (from `suctionbench generate`).")],
    split: Annotated[str, typer.Option(help="Split: image_wise or object_wise.")] = "object_wise",
    part: Annotated[str, typer.Option(help="Side of the split: val (held out) or train.")] = "val",
    max_datapoints: Annotated[int | None, typer.Option(help="Score a random subset of this many (it thins each "
                                                            "image's grasps, and so the top-grasp figures).")] = None,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Held-out accuracy and AP of a trained model on a dataset's split, against the dataset's own
    label (metric > its threshold): the training run's figures, recomputed for any model and data.
    Beside them, what the policies act on: the label of each image's highest-q grasp
    (`learning.metrics.top_grasp_success`), with its ceiling and a random pick's."""

    def body() -> dict[str, Any]:
        import numpy as np

        from suctionbench.dataset.storage import read_card
        from suctionbench.learning.checkpoint import load_model
        from suctionbench.learning.data import label_threshold
        from suctionbench.learning.metrics import top_grasp_success
        from suctionbench.learning.train import score_model

        model = load_model(directory)
        threshold = label_threshold(read_card(dataset))
        data = model.split_data(dataset, split, part, max_datapoints=max_datapoints,
                                subset_rng=np.random.default_rng(seed))
        scored = score_model(model, data, threshold)
        result = {"model": str(directory), "dataset": str(dataset), "split": f"{split}/{part}",
                  "datapoints": data.num_datapoints, "target": model.target, "label_threshold": threshold,
                  "decision_threshold": scored["decision_threshold"], "accuracy": scored["accuracy"],
                  "accuracy_at_half": scored["accuracy_at_half"], "ap": scored["ap"],
                  "positive_rate": scored["positive_rate"], "loss": scored["loss"]}
        result.update(top_grasp_success(scored["labels"], scored["scores"], data.values("image_labels")))
        if not as_json:
            print_kv(str(directory), result)
        return result

    run_command(as_json, body)
