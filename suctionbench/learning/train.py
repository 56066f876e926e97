"""GQ-CNN training: gqcnn's Dex-Net 3.0 recipe in PyTorch, deterministic and resumable.

Recipe (gqcnn cfg/train_dex-net_3.0.yaml): softmax cross-entropy on label = metric > 0.2, SGD with
momentum 0.9, base learning rate 0.01 decayed by 0.95 every 0.66 epoch (staircase), L2 5e-4,
batch 64, 25 epochs, 80/20 image-wise split, normalised inputs and Gamma / GP noise /
symmetrisation augmentation (`suctionbench.learning.data`). gqcnn adds ``l2 * sum(tf.nn.l2_loss(w))``
(= l2 * sum w^2 / 2) to the loss over all weights and biases; its gradient l2 * w is exactly SGD's
``weight_decay=l2``, which is what is used here. gqcnn's learning rate is
``base * 0.95 ** floor(examples_seen / (0.66 * num_train))``; `_StaircaseDecay` computes the same
from the step count.

Architectures. Every name in `ARCHITECTURES` trains here: dn3 and compact read the grasp
thumbnail, the context nets (context, context-wide) the grasp and the context thumbnail
(`suctionbench.learning.models.image_channels_of`). That channel count decides which dataset
fields `SplitData` loads (a dataset without ``context_ims_tf_table`` is refused for the context
nets), sizes the per-channel normalisation, and is recorded in the model card
(``image_channels``), which `suctionbench.learning.checkpoint.load_model` checks against the
architecture and the statistics. With `TrainConfig.init` naming a model of a narrower architecture
of the same layout (context-pose-wide -> context-pose-wide-fc, say), training starts from that
model grown into the wider one (`suctionbench.learning.grow`): the same predictions, more units.

Determinism. Every random draw comes from generators derived from `TrainConfig.seed` through
``numpy.random.SeedSequence(seed).spawn``: the optional training subset, the data order (numpy),
the weight initialisation and the augmentation (torch, CPU); nothing uses a global RNG. On the CPU
two runs with the same seed, data and thread count give bit-identical weights. On CUDA the run uses
bfloat16 autocast (mixed precision) and cuDNN's fastest kernels, which are not bit-reproducible.

Checkpoints. After every epoch the output directory gets, each written atomically: the model
(``model.safetensors`` + ``model.json``, usable for inference at once) and the resume state
(``train_state.pt``: model, optimiser, scheduler, both RNG states, history, normalisation
statistics). The validation precision-recall curve (``precision_recall.png``) is drawn at the end. `train` on a
directory holding a resume state of the same configuration (ignoring `epochs` and `device`)
continues after the last completed epoch and ends with the same weights an uninterrupted run
would have; more epochs than before extend a finished run (the decay schedule does not depend on
the epoch count). A different configuration is refused unless ``overwrite=True``.
"""

from __future__ import annotations

import math
import shlex
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F

from suctionbench.config import to_dict
from suctionbench.dataset.storage import DatasetReader, held_out_keys, read_card
from suctionbench.errors import InputError
from suctionbench.learning.checkpoint import (
    CARD_NAME,
    STATE_NAME,
    WEIGHTS_NAME,
    GQCNNModel,
    json_safe,
    load_train_state,
    save_model,
    save_train_state,
    versions,
)
from suctionbench.learning.data import (
    METRIC_FIELD,
    NormStats,
    SplitData,
    augment,
    dataset_noise_model,
    dataset_settings,
    dataset_thumbnail,
    label_threshold,
    labels_of,
    to_tensors,
)
from suctionbench.learning.metrics import (
    average_precision,
    plot_precision_recall,
    precision_recall_curve,
    top_grasp_success,
)
from suctionbench.learning.models import (
    POSE_DIM,
    activation_bytes,
    build_model,
    count_macs,
    count_parameters,
    image_channels_of,
    pose_dim_of,
)
from suctionbench.learning.train_config import RESUME_IGNORES, TrainConfig, decision_threshold
from suctionbench.sensing.object_context import OBJECT_CONTEXT_COLUMNS
from suctionbench.sensing.thumbnails import ThumbnailConfig

PR_CURVE_NAME = "precision_recall.png"

TRAIN_BYTES_PER_ACTIVATION = 2.0
"""Peak memory of a training step per byte of one image's layer outputs (`activation_bytes`): the
outputs kept for the backward pass, their gradients and temporaries; measured 1.2-1.6 for dn3 and
compact at batches of 1,024 and more (2.5 at 256, where the fixed costs weigh more)."""

CHECKPOINT_BYTES_PER_PARAMETER = 20
"""Disk per network parameter while training: the weights (4 bytes) and the resume state (model and
momentum, 8 bytes), and temporary copies of both while each checkpoint replaces the last."""

EVAL_BATCH = 1024
"""Datapoints per forward pass in validation (no gradients, so larger than the training batch)."""

PROGRESS_EVERY = 10
"""Training steps between progress reports (each report synchronises with the GPU once)."""


@dataclass(frozen=True)
class TrainProgress:
    """What a progress callback receives, every `PROGRESS_EVERY` steps and at the end of each epoch."""

    epoch: int
    """Current epoch, 1-based."""

    epochs: int
    """Last epoch of the run."""

    images_done: int
    """Training images processed in this call of `train` so far."""

    images_total: int
    """Training images this call of `train` will process (epochs left x training datapoints)."""

    loss: float
    """Mean training loss of the current epoch so far."""

    accuracy: float
    """Training accuracy of the current epoch so far (on augmented inputs)."""


class _StaircaseDecay:
    """Learning-rate factor decay_rate ** floor(examples seen / examples per decay), as gqcnn's staircase.

    A class rather than a lambda so the scheduler's state (this object's fields) can be checkpointed.
    """

    def __init__(self, batch_size: int, examples_per_decay: float, decay_rate: float):
        self.batch_size = batch_size
        self.examples_per_decay = examples_per_decay
        self.decay_rate = decay_rate

    def __call__(self, step: int) -> float:
        return self.decay_rate ** math.floor(step * self.batch_size / self.examples_per_decay)


@dataclass
class _Session:
    """Everything that changes during training and is checkpointed."""

    network: torch.nn.Module
    optimizer: torch.optim.Optimizer
    scheduler: torch.optim.lr_scheduler.LambdaLR
    shuffle_rng: np.random.Generator
    augment_gen: torch.Generator
    stats: NormStats
    averaged: torch.optim.swa_utils.AveragedModel | None = None
    epoch: int = 0
    history: list[dict[str, Any]] = field(default_factory=list)
    train_seconds: float = 0.0
    images_trained: int = 0

    def state(self, config: TrainConfig, resume_key: dict[str, Any]) -> dict[str, Any]:
        return {
            "config": to_dict(config), "resume_key": resume_key, "epoch": self.epoch,
            "model": self.network.state_dict(), "optimizer": self.optimizer.state_dict(),
            "scheduler": self.scheduler.state_dict(), "shuffle_rng": self.shuffle_rng.bit_generator.state,
            "augment_rng": self.augment_gen.get_state(), "stats": self.stats.to_dict(), "history": self.history,
            "train_seconds": self.train_seconds, "images_trained": self.images_trained,
            "averaged": None if self.averaged is None else self.averaged.state_dict(),
        }

    @property
    def scored(self) -> torch.nn.Module:
        """The network that is evaluated and saved: the weights' average when there is one."""
        return self.network if self.averaged is None else self.averaged.module

    def restore(self, state: dict[str, Any]) -> None:
        self.network.load_state_dict(state["model"])
        if self.averaged is not None:
            self.averaged.load_state_dict(state["averaged"])
        self.optimizer.load_state_dict(state["optimizer"])
        self.scheduler.load_state_dict(state["scheduler"])
        self.shuffle_rng.bit_generator.state = state["shuffle_rng"]
        self.augment_gen.set_state(state["augment_rng"])
        self.epoch = int(state["epoch"])
        self.history = list(state["history"])
        self.train_seconds = float(state["train_seconds"])
        self.images_trained = int(state["images_trained"])


def _torch_seed(seq: np.random.SeedSequence) -> int:
    return int(seq.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1))


def _device(name: str) -> torch.device:
    """The torch device `name` names: cpu, cuda or cuda:N; InputError for anything else, or for
    cuda where torch sees no GPU."""
    unknown = InputError(f"device '{name}': expected cpu, cuda or cuda:N")
    if not (name == "cpu" or name.startswith("cuda")):
        raise unknown
    try:
        device = torch.device(name)
    except RuntimeError:
        raise unknown from None
    if device.type == "cuda" and not torch.cuda.is_available():
        raise InputError(f"device '{name}': CUDA is not available on this machine (use cpu)")
    return device


def _initial_model(config: TrainConfig, network: Any) -> Any:
    """The model `config.init` names (None without one); InputError if its arch is not `config.arch`
    and cannot grow into `network` (`config.arch`, built; `suctionbench.learning.grow`)."""
    if config.init is None:
        return None
    from suctionbench.learning.checkpoint import load_model

    base = load_model(config.init)
    if base.arch != config.arch:
        from suctionbench.learning.grow import growth_problem

        problem = growth_problem(base.network, network)
        if problem is not None:
            raise InputError(f"--init '{config.init}': a {base.arch} model, which cannot grow into --arch "
                             f"{config.arch} ({problem})")
    return base


def _resume_key(config: TrainConfig, card: dict[str, Any], reader: DatasetReader, train_data: SplitData,
                val_data: SplitData) -> dict[str, Any]:
    """What must match for a checkpoint to be resumed: the config (bar `RESUME_IGNORES`) and the data."""
    settings = {k: v for k, v in to_dict(config).items() if k not in RESUME_IGNORES}
    for key in ("average", "max_train_objects", "train_objects"):  # runs from before these existed resume as they were
        if settings[key] is None:
            del settings[key]
    data = {"fingerprint": card.get("fingerprint"), "datapoints": reader.num_datapoints,
            "num_train": train_data.num_datapoints, "num_val": val_data.num_datapoints}
    return json_safe({"config": settings, "dataset": data})


def _differences(old: dict[str, Any], new: dict[str, Any], prefix: str = "") -> list[str]:
    keys = sorted(set(old) | set(new))
    out: list[str] = []
    for key in keys:
        a, b = old.get(key), new.get(key)
        if isinstance(a, dict) and isinstance(b, dict):
            out += _differences(a, b, f"{prefix}{key}.")
        elif a != b:
            out.append(f"{prefix}{key}")
    return out


def _dataset_summary(directory: Path, card: dict[str, Any], split: str, train_data: SplitData,
                     val_data: SplitData) -> dict[str, Any]:
    """The dataset facts a model card carries: where it came from and what camera and cup it assumes."""
    config = dataset_settings(card)
    label = config.get("label") if isinstance(config.get("label"), dict) else {}
    return {
        "path": str(directory.resolve()), "fingerprint": card.get("fingerprint"), "datapoints": card.get("datapoints"),
        "positive_rate": card.get("positive_rate"), "camera": card.get("camera"),
        "cup": card.get("cup", label.get("cup")), "noise_model": dataset_noise_model(card),
        "noise": config.get("noise"), "thumbnail": to_dict(dataset_thumbnail(card, f"dataset '{directory}'")),
        "seed": config.get("seed"),
        "objects": len(card.get("objects", [])) if isinstance(card.get("objects"), list) else None,
        "split": split, "num_train": train_data.num_datapoints, "num_val": val_data.num_datapoints,
        "suctionbench_version": card.get("suctionbench_version"),
        # the objects it never trained on, by key: `generate --holdout-like MODEL` holds out the same
        # ones in new data without the (GB-sized) dataset the model came from
        "held_out_objects": _held_out_objects(directory, card, split),
        "holdout_like": card.get("holdout_like"),  # the dataset (fingerprint) whose held-out objects it kept
    }


def _held_out_objects(directory: Path, card: dict[str, Any], split: str) -> list[str] | None:
    """The keys of the objects an object-wise split holds out, for the model card; None for an
    image-wise split or a dataset whose card names no objects (a synthetic or imported one)."""
    if split != "object_wise" or not isinstance(card.get("objects"), list) or not card["objects"]:
        return None
    return held_out_keys(directory, f"--dataset '{directory}'")


def _autocast(device: torch.device):
    """bfloat16 autocast on CUDA (no loss scaling needed, unlike float16); a no-op context on the CPU."""
    return torch.autocast(device.type, dtype=torch.bfloat16, enabled=device.type == "cuda")


def _loss(logits: torch.Tensor, metric: np.ndarray, labels: torch.Tensor, target: str,
          reduction: str = "mean") -> torch.Tensor:
    """Cross-entropy of two-class `logits` against the binary `labels` or, for the soft target,
    against class probabilities (1 - metric, metric) (`train_config.TARGETS`)."""
    if target == "binary":
        return F.cross_entropy(logits, labels, reduction=reduction)
    p = torch.from_numpy(np.clip(np.asarray(metric, dtype=np.float32), 0.0, 1.0)).to(logits.device)
    return F.cross_entropy(logits, torch.stack([1.0 - p, p], dim=1), reduction=reduction)


def evaluate(network: torch.nn.Module, data: SplitData, stats: NormStats, threshold: float,
             device: torch.device, target: str = "binary") -> dict[str, Any]:
    """Loss (of `target`), accuracy (q above `decision_threshold` against the binary label; and
    `accuracy_at_half`, q > 0.5, as scored before 2026-11-27), AP and the scores / labels of a split,
    in index order, no augmentation."""
    network.eval()
    scores, labels, loss_sum = [], [], 0.0
    with torch.no_grad():
        for batch in data.batches(EVAL_BATCH):
            images, poses = stats.normalise(*to_tensors(batch, device))
            target_labels = torch.from_numpy(labels_of(batch.metric, threshold)).to(device)
            with _autocast(device):
                logits = network(images, poses)
            logits = logits.float()
            loss_sum += float(_loss(logits, batch.metric, target_labels, target, reduction="sum"))
            scores.append(torch.softmax(logits, dim=1)[:, 1].cpu().numpy())
            labels.append(target_labels.cpu().numpy())
    q = np.concatenate(scores) if scores else np.zeros(0)
    y = np.concatenate(labels) if labels else np.zeros(0, dtype=np.int64)
    n = max(len(y), 1)
    cut = decision_threshold(target, threshold)
    return {"loss": loss_sum / n, "accuracy": float(np.mean((q > cut) == (y == 1))) if len(y) else math.nan,
            "accuracy_at_half": float(np.mean((q > 0.5) == (y == 1))) if len(y) else math.nan,
            "decision_threshold": cut,
            "ap": average_precision(y, q), "positive_rate": float(np.mean(y)) if len(y) else math.nan,
            "scores": q, "labels": y}


def score_model(model: Any, data: SplitData, threshold: float) -> dict[str, Any]:
    """`evaluate` of a trained model (`learning.checkpoint.GQCNNModel`) on `data` (best read with
    `model.split_data`), at the decision threshold of the target it was trained on."""
    return evaluate(model.network, data, model.stats, threshold, model.device, model.target)


def _train_epoch(session: _Session, data: SplitData, config: TrainConfig, threshold: float, device: torch.device,
                 report: Callable[[int, float, float], None]) -> dict[str, float]:
    """One pass over the training split; returns mean loss, accuracy, images and seconds."""
    network = session.network
    network.train()
    loss_sum = torch.zeros((), device=device)
    correct = torch.zeros((), device=device, dtype=torch.int64)
    seen = 0
    cut = decision_threshold(config.target, threshold)
    margin = math.log(cut / (1.0 - cut))  # q > cut, as logits: softmax's q = sigmoid(logit_1 - logit_0)
    start = time.perf_counter()
    batches = data.batches(config.batch_size, session.shuffle_rng, config.shuffle_shards)
    for step, batch in enumerate(batches, start=1):
        images, poses = to_tensors(batch, device)
        labels = torch.from_numpy(labels_of(batch.metric, threshold)).to(device)
        if config.augment.enabled:
            images, poses = augment(images, poses, session.augment_gen, config.augment)
        images, poses = session.stats.normalise(images, poses)
        with _autocast(device):
            logits = network(images, poses)
        loss = _loss(logits.float(), batch.metric, labels, config.target)
        session.optimizer.zero_grad(set_to_none=True)
        loss.backward()
        session.optimizer.step()
        session.scheduler.step()
        if session.averaged is not None:
            session.averaged.update_parameters(network)
        loss_sum += loss.detach() * len(batch)
        scored = logits.detach().float()
        correct += ((scored[:, 1] - scored[:, 0] > margin) == labels.bool()).sum()
        seen += len(batch)
        if step % PROGRESS_EVERY == 0:
            report(seen, float(loss_sum) / seen, int(correct) / seen)
    seconds = time.perf_counter() - start
    loss_mean, accuracy = float(loss_sum) / max(seen, 1), int(correct) / max(seen, 1)
    report(seen, loss_mean, accuracy)
    return {"loss": loss_mean, "accuracy": accuracy, "images": seen, "seconds": seconds}


def _foreign_output(out_dir: Path) -> str | None:
    """The first of the trainer's file names in `out_dir` held by a file suctionbench did not write,
    else None. Proof of ownership: model.json is a card of the model format, model.safetensors
    carries that format in its header, train_state.pt loads as a resume state; the PR curve is ours
    beside any of those."""
    from safetensors import SafetensorError, safe_open

    from suctionbench.learning.checkpoint import CARD_FORMAT, read_model_card

    if not out_dir.is_dir():
        return None
    present = {name for name in (CARD_NAME, WEIGHTS_NAME, STATE_NAME, PR_CURVE_NAME) if (out_dir / name).exists()}
    ours = set()
    if CARD_NAME in present:
        try:
            read_model_card(out_dir)
            ours.add(CARD_NAME)
        except InputError:
            return CARD_NAME
    if WEIGHTS_NAME in present:
        try:
            with safe_open(str(out_dir / WEIGHTS_NAME), framework="pt") as fh:
                if (fh.metadata() or {}).get("format") != CARD_FORMAT:
                    return WEIGHTS_NAME
            ours.add(WEIGHTS_NAME)
        except (SafetensorError, OSError, ValueError):
            return WEIGHTS_NAME
    if STATE_NAME in present:
        try:
            load_train_state(out_dir)
            ours.add(STATE_NAME)
        except InputError:
            if not ours:  # a damaged resume state beside a model of ours is ours
                return STATE_NAME
    if PR_CURVE_NAME in present and not ours:
        return PR_CURVE_NAME
    return None


def _check_sizes(config: TrainConfig, out_dir: Path, network: torch.nn.Module, num_train: int,
                 device: torch.device) -> None:
    """InputError before any training if the checkpoints of `network` do not fit on the disk under
    `out_dir`, or (on the CPU) a training batch does not fit in memory."""
    from suctionbench.validate import require_disk, require_memory

    existing = sum((out_dir / n).stat().st_size for n in (WEIGHTS_NAME, STATE_NAME) if (out_dir / n).is_file())
    need = CHECKPOINT_BYTES_PER_PARAMETER * count_parameters(network) + 2**20 - existing
    require_disk(out_dir, need, f"--arch {config.arch} checkpoints")
    if device.type == "cpu":
        batch = min(config.batch_size, num_train)
        require_memory(batch * TRAIN_BYTES_PER_ACTIVATION * activation_bytes(network),
                       f"--batch-size {batch} (--arch {config.arch})")


def _remove_outputs(out_dir: Path) -> None:
    for name in (STATE_NAME, WEIGHTS_NAME, CARD_NAME, PR_CURVE_NAME):
        (out_dir / name).unlink(missing_ok=True)


def train(dataset_dir: str | Path, out_dir: str | Path, config: TrainConfig | None = None,
          progress: Callable[[TrainProgress], None] | None = None, *, command: str | None = None,
          overwrite: bool = False) -> dict[str, Any]:
    """Train a GQ-CNN on a dataset directory, writing the model and checkpoints to `out_dir`; returns metrics.

    Resumes from ``out_dir/train_state.pt`` when its configuration matches (module docstring);
    `overwrite` discards an existing run instead. `command` is recorded in the model card (default:
    this process's command line). Bad inputs (missing dataset, missing split, unknown arch,
    unavailable device, conflicting checkpoint) raise InputError before any training.
    """
    config = config or TrainConfig()
    dataset_dir, out_dir = Path(dataset_dir), Path(out_dir)
    device = _device(config.device)
    reader = DatasetReader(dataset_dir)
    card = read_card(dataset_dir)
    threshold = config.label_threshold if config.label_threshold is not None else label_threshold(card)
    seq_subset, seq_shuffle, seq_init, seq_augment, seq_fit, seq_val = np.random.SeedSequence(config.seed).spawn(6)
    channels = image_channels_of(config.arch)  # which image fields the network reads
    reads = {"image_channels": channels, "object_context": pose_dim_of(config.arch) > POSE_DIM,
             "load_threads": config.load_threads}
    train_data = SplitData(dataset_dir, config.split, "train", max_datapoints=config.max_train_datapoints,
                           max_objects=config.max_train_objects, objects_matching=config.train_objects,
                           subset_rng=np.random.default_rng(seq_subset), reader=reader, **reads)
    val_data = SplitData(dataset_dir, config.split, "val", max_datapoints=config.max_val_datapoints,
                         subset_rng=np.random.default_rng(seq_val), reader=reader, **reads)
    if train_data.num_datapoints == 0:
        raise InputError(f"dataset '{dataset_dir}': split {config.split} has no training datapoints")
    fit_data = train_data.subset(config.fit_datapoints, np.random.default_rng(seq_fit))
    resume_key = _resume_key(config, card, reader, train_data, val_data)

    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(f"output '{out_dir}': exists and is not a directory")
    foreign = _foreign_output(out_dir)
    if foreign is not None:  # never replace (nor, with overwrite, delete) a file suctionbench did not write
        raise InputError(f"output '{out_dir}': holds '{foreign}', which suctionbench did not write; nothing "
                         "replaced (move it away or choose another --out)")
    network = build_model(config.arch, torch.Generator().manual_seed(_torch_seed(seq_init))).to(device)
    _check_sizes(config, out_dir, network, train_data.num_datapoints, device)
    if overwrite:
        _remove_outputs(out_dir)
    saved = load_train_state(out_dir)
    if saved is not None and saved.get("resume_key") != resume_key:
        changed = ", ".join(_differences(saved.get("resume_key") or {}, resume_key)) or "format"
        raise InputError(f"output '{out_dir}': holds a training run with a different configuration or dataset "
                         f"(differs in: {changed}); use another output directory or overwrite it (--overwrite)")

    base = _initial_model(config, network) if saved is None else None
    if base is not None and base.arch == config.arch:
        network.load_state_dict(base.network.state_dict())
    elif base is not None:  # a wider arch: the same function, more units (suctionbench.learning.grow)
        from suctionbench.learning.grow import grow

        grow(base.network, network, np.random.default_rng(seq_init))
    if saved is not None:
        stats = NormStats.from_dict(saved["stats"])
    else:
        stats = base.stats if base is not None else train_data.compute_stats()
    if stats.image_channels != channels:  # a resume key of the same arch makes this a corrupt state
        raise InputError(f"training checkpoint '{out_dir / STATE_NAME}': normalisation statistics for "
                         f"{stats.image_channels} image channel(s), --arch {config.arch} reads {channels}")
    optimizer = torch.optim.SGD(network.parameters(), lr=config.learning_rate, momentum=config.momentum,
                                weight_decay=config.weight_decay)
    decay = _StaircaseDecay(config.batch_size, config.decay_epochs * train_data.num_datapoints, config.decay_rate)
    averaged = None
    if config.average is not None:
        averaged = torch.optim.swa_utils.AveragedModel(
            network, multi_avg_fn=torch.optim.swa_utils.get_ema_multi_avg_fn(config.average))
    session = _Session(network, optimizer, torch.optim.lr_scheduler.LambdaLR(optimizer, decay),
                       np.random.default_rng(seq_shuffle), torch.Generator().manual_seed(_torch_seed(seq_augment)),
                       stats, averaged)
    resumed_from = 0
    if saved is not None:
        session.restore(saved)
        resumed_from = session.epoch

    summary = _dataset_summary(dataset_dir, card, config.split, train_data, val_data)
    thumbnail = ThumbnailConfig.from_dict(summary["thumbnail"], f"dataset '{dataset_dir}'")
    grasp = f"{thumbnail.crop_size} px crop" + (f", {thumbnail.block} x {thumbnail.block} block means"
                                                  if thumbnail.sampling == "mean" else "")
    images_input = (f"(N, 32, 32) float32 depth thumbnails in metres ({grasp}), grasp at the centre, approach's "
                    "image pointing down the middle column")
    if channels == 2:
        images_input = (f"(N, 2, 32, 32) float32 depth thumbnails in metres: channel 0 the grasp thumbnail ({grasp}), "
                        "channel 1 the context thumbnail (288 px crop, 9 x 9 block means), both with the "
                        "grasp at the centre and the approach's image pointing down the middle column")
    base_card = {
        "arch": config.arch, "parameters": count_parameters(network),
        "macs_per_grasp": count_macs(network),
        "inputs": {"images": images_input,
                   "poses": "(N, 2) [gripper depth (m), approach angle to the table normal (rad, >= 0)]"
                            if not reads["object_context"] else
                            "(N, 8) [gripper depth (m), approach angle to the table normal (rad, >= 0), then the "
                            "object context in metres: " + ", ".join(OBJECT_CONTEXT_COLUMNS) + "]"},
        "output": "probability that the grasp succeeds: softmax of the logits, column 1",
        "label": {"metric": METRIC_FIELD, "threshold": threshold, "positive": "metric > threshold",
                  "target": config.target, "decision": f"q > {decision_threshold(config.target, threshold):g}"},
        "dataset": summary,
        "command": command if command is not None else shlex.join(sys.argv),
        "versions": versions(),
    }
    epochs_left = max(config.epochs - session.epoch, 0)
    images_total = epochs_left * train_data.num_datapoints
    run_images, run_seconds = 0, 0.0
    evaluation: dict[str, Any] | None = None
    val_views = val_data.values("image_labels") if session.epoch < config.epochs else None  # read once
    while session.epoch < config.epochs:
        epoch = session.epoch + 1

        def report(done: int, loss: float, acc: float, epoch: int = epoch, before: int = run_images) -> None:
            if progress is not None:
                progress(TrainProgress(epoch, config.epochs, before + done, images_total, loss, acc))

        lr = optimizer.param_groups[0]["lr"]
        result = _train_epoch(session, train_data, config, threshold, device, report)
        run_images += result["images"]
        run_seconds += result["seconds"]
        session.train_seconds += result["seconds"]
        session.images_trained += result["images"]
        evaluation = evaluate(session.scored, val_data, stats, threshold, device, config.target)
        fit = evaluate(session.scored, fit_data, stats, threshold, device, config.target)
        session.epoch = epoch
        session.history.append(json_safe({
            "epoch": epoch, "lr": lr, "train_loss": result["loss"], "train_accuracy": result["accuracy"],
            "fit_accuracy": fit["accuracy"], "fit_ap": fit["ap"],
            "val_loss": evaluation["loss"], "val_accuracy": evaluation["accuracy"], "val_ap": evaluation["ap"],
            "val_accuracy_at_half": evaluation["accuracy_at_half"],
            # what the policies act on, each view's top-scored grasp: the figure that ranked models as
            # the simulation did where accuracy and AP did not (eval/gqcnn/README.md, "Now")
            "val_top_grasp_success": top_grasp_success(evaluation["labels"], evaluation["scores"],
                                                       val_views)["top_grasp_success"],
            "train_seconds": result["seconds"], "train_images_per_s": result["images"] / max(result["seconds"], 1e-9),
        }))
        _checkpoint(out_dir, session, config, resume_key, base_card, evaluation, device)

    if evaluation is None and not (out_dir / CARD_NAME).is_file():  # resumed a finished run whose files are gone
        evaluation = evaluate(session.scored, val_data, stats, threshold, device, config.target)
        _checkpoint(out_dir, session, config, resume_key, base_card, evaluation, device)
    if evaluation is not None:
        _plot_pr_curve(out_dir / PR_CURVE_NAME, evaluation, f"{config.arch}, {config.split} validation, "
                                                            f"epoch {session.epoch}")
    last = session.history[-1]
    return json_safe({
        "out": str(out_dir), "arch": config.arch, "split": config.split, "epochs": session.epoch,
        "resumed_from_epoch": resumed_from, "epochs_trained_now": session.epoch - resumed_from,
        "num_train": train_data.num_datapoints, "num_val": val_data.num_datapoints, "label_threshold": threshold,
        "train_loss": last["train_loss"], "train_accuracy": last["train_accuracy"],
        "fit_accuracy": last.get("fit_accuracy"), "fit_ap": last.get("fit_ap"),
        "val_loss": last["val_loss"], "val_accuracy": last["val_accuracy"], "val_ap": last["val_ap"],
        "train_seconds": round(session.train_seconds, 3),
        "train_images_per_s": round(run_images / run_seconds, 1) if run_seconds > 0 else
        round(session.images_trained / max(session.train_seconds, 1e-9), 1),
        "parameters": base_card["parameters"], "macs_per_grasp": base_card["macs_per_grasp"],
        "model": str(out_dir / CARD_NAME), "pr_curve": str(out_dir / PR_CURVE_NAME), "device": str(device),
    })


def _checkpoint(out_dir: Path, session: _Session, config: TrainConfig, resume_key: dict[str, Any],
                base_card: dict[str, Any], evaluation: dict[str, Any], device: torch.device) -> None:
    """Write the model (weights, then card) and then the resume state."""
    last = session.history[-1]
    card = dict(base_card)
    card["training"] = {
        "config": to_dict(config), "epochs_completed": session.epoch,
        "status": "complete" if session.epoch >= config.epochs else "in progress",
        "device": str(device), "mixed_precision": "bfloat16" if device.type == "cuda" else None,
        "train_seconds": round(session.train_seconds, 3), "images_trained": session.images_trained,
        "train_images_per_s": round(session.images_trained / max(session.train_seconds, 1e-9), 1),
    }
    card["metrics"] = {key: last[key] for key in ("train_loss", "train_accuracy", "val_loss", "val_accuracy", "val_ap")}
    card["metrics"]["val_positive_rate"] = evaluation["positive_rate"]
    card["history"] = session.history
    save_model(out_dir, GQCNNModel(session.scored, session.stats, card, device=str(device)))
    save_train_state(out_dir, session.state(config, resume_key))


def _plot_pr_curve(path: Path, evaluation: dict[str, Any], title: str) -> None:
    """The validation PR curve as a PNG; skipped when the split has no positives (no curve exists).

    Drawn once per `train` call, after the last epoch: matplotlib takes ~0.4 s a figure, more than
    an epoch of a small dataset.
    """
    precision, recall, _ = precision_recall_curve(evaluation["labels"], evaluation["scores"])
    if len(recall) and np.isfinite(recall[-1]):
        plot_precision_recall(path, precision, recall, ap=evaluation["ap"], positive_rate=evaluation["positive_rate"],
                              title=title)
