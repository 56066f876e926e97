"""Training run settings (`TrainConfig`) and the training targets, apart from the loop that uses them
(`suctionbench.learning.train`), so a caller can build, validate and compare configurations (resume
keys, model cards) without loading the trainer."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from suctionbench.dataset.storage import SPLIT_KINDS
from suctionbench.errors import InputError
from suctionbench.learning.data import AUGMENT_GQCNN, SHUFFLE_SHARDS, AugmentConfig
from suctionbench.learning.models import ARCHITECTURES

TARGETS = ("binary", "soft")
"""Training targets (`TrainConfig.target`). The robust wrench resistance is the share of perturbed
samples a grasp resists, an estimate of its chance of success. The binary label (metric > 0.2, the
paper's) calls a grasp that resists 25 % of the perturbations as good as one that resists them all:
a third of the positives of a dataset labelled with the pick's loads lie in (0.2, 0.5]. A policy
takes the network's maximum over thousands of candidates, so what it needs is the order among
good grasps; the soft target (cross-entropy against the metric, whose minimum over q is q =
metric) makes the network's q the expected resistance and keeps that order."""


def decision_threshold(target: str, threshold: float) -> float:
    """The q above which a network trained on `target` calls a grasp positive (label: metric >
    `threshold`), for its accuracy. Binary: q estimates P(metric > threshold), so 0.5 (the Bayes
    decision). Soft: q estimates the metric itself (the soft cross-entropy is least at q = E[metric
    | input], `TARGETS`), so the label's own test applies to it: q > threshold. (Scored at 0.5, a
    soft network's q = 0.3 for a grasp that resists 30 % of the perturbations, a positive, would
    count as a miss.)"""
    return float(threshold) if target == "soft" else 0.5


@dataclass(frozen=True)
class TrainConfig:
    """Training run settings (defaults: gqcnn's Dex-Net 3.0 recipe on the dn3 network)."""

    arch: str = "dn3"
    """Network: dn3 (Dex-Net 3.0 GQ-CNN, 5.6 M parameters), compact (36 k, CPU friendly), the
    two-channel context (71 k) and context-wide (281 k), which also read the context thumbnail, or
    context-pose (context with the object context in metres in its pose stream) and its twice as wide
    context-pose-wide."""

    epochs: int = 25
    """Passes over the training split. gqcnn: 25."""

    batch_size: int = 64
    """Training datapoints per SGD step. gqcnn: 64."""

    learning_rate: float = 0.01
    """Base learning rate. gqcnn: 0.01."""

    momentum: float = 0.9
    """SGD momentum. gqcnn: 0.9."""

    decay_rate: float = 0.95
    """Factor applied to the learning rate at every decay step (staircase). gqcnn: 0.95."""

    decay_epochs: float = 0.66
    """Epochs between learning-rate decays (gqcnn ``decay_step_multiplier``): 0.66."""

    weight_decay: float = 5e-4
    """L2 coefficient on all weights and biases (gqcnn ``train_l2_regularizer``): 5e-4."""

    split: str = "image_wise"
    """Dataset split: image_wise (unseen images of known objects, gqcnn's) or object_wise (unseen objects)."""

    device: str = "cpu"
    """cpu, or cuda (bfloat16 mixed precision)."""

    seed: int = 0
    """Seed of every random draw: subset, data order, initialisation, augmentation."""

    augment: AugmentConfig = field(default_factory=lambda: AUGMENT_GQCNN)
    """Training augmentation (`AUGMENT_OFF` disables it)."""

    max_train_datapoints: int | None = None
    """Train on a random subset of at most this many training datapoints (None: all)."""

    max_train_objects: int | None = None
    """Train only on the datapoints of a seeded random subset of this many training objects (None:
    all), drawn before `max_train_datapoints`: with both, a learning curve over object diversity at
    a fixed datapoint count."""

    train_objects: str | None = None
    """Train only on the datapoints of the training objects whose key matches this shell pattern
    (e.g. '*household*' for a corpus's household kinds; None: all), chosen before
    `max_train_objects` and `max_train_datapoints`. The held-out side is not filtered."""

    max_val_datapoints: int | None = None
    """Validate on a seeded random subset of at most this many validation datapoints (None: all;
    a 2.8 M-datapoint dataset's 20 % split takes minutes to score after every epoch on a CPU)."""

    shuffle_shards: int = SHUFFLE_SHARDS
    """Shards pooled and shuffled together (`learning.data.SHUFFLE_SHARDS`: why 64; memory ~ twice
    this x one shard: 4 MB per 1000 grasp thumbnails, 8 MB with context)."""

    fit_datapoints: int = 20_000
    """Training datapoints (a fixed random subset of the training split, in whole shards) scored without
    augmentation after every epoch: the fit accuracy and AP, comparable with the validation
    figures (the running train_accuracy is over augmented images while the weights move); a fit
    accuracy clearly above the validation accuracy says the network is not capacity-limited."""

    label_threshold: float | None = None
    """Label = metric > this; None: the dataset card's ``config.label_threshold`` (else 0.2)."""

    target: str = "binary"
    """What the loss fits (`TARGETS`): binary (gqcnn's: cross-entropy against label = metric >
    threshold) or soft (cross-entropy against the metric itself as the probability of the positive
    class). Accuracy and AP are scored against the binary label either way."""

    average: float | None = None
    """Decay of an exponential moving average of the weights (Polyak averaging), updated after
    every step; the averaged network is the one scored and saved (the raw one keeps training).
    None: the last iterate, gqcnn's. Why: gqcnn's schedule is made for 25 epochs, and after 3 the
    learning rate is still 0.0086 of 0.01, so the last iterate wanders: a 1.2 M-datapoint run's
    held-out accuracy fell from 0.877 after its second epoch to 0.821 after its third while its
    running training accuracy rose. 0.9995 averages over ~2,000 steps (128 k datapoints)."""

    load_threads: int = 1
    """Threads reading shards (`SplitData`'s `load_threads`): one keeps up with 2 CPU cores' training
    (~8,000 thumbnail pairs/s read against ~2,600 trained); a GPU trains faster than one thread
    reads. Does not change the data order or the weights."""

    init: str | None = None
    """A trained model directory to start from (fine-tuning: its weights and its input
    normalisation, so the network sees inputs scaled as it learnt them); its arch must be `arch`,
    or one `arch` can grow from (`suctionbench.learning.grow`: a wider net computing the same).
    None: random initial weights and statistics of this dataset."""

    def __post_init__(self) -> None:
        def integer(value: Any, low: int) -> bool:
            return isinstance(value, int | np.integer) and not isinstance(value, bool) and value >= low

        def number(value: Any) -> bool:
            return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)

        checks = {
            "arch": (self.arch in ARCHITECTURES, f"one of {', '.join(ARCHITECTURES)}"),
            "epochs": (integer(self.epochs, 1), "an integer >= 1"),
            "batch_size": (integer(self.batch_size, 1), "an integer >= 1"),
            "learning_rate": (number(self.learning_rate) and self.learning_rate > 0, "a number > 0"),
            "momentum": (number(self.momentum) and 0 <= self.momentum < 1, "a number in [0, 1)"),
            "decay_rate": (number(self.decay_rate) and 0 < self.decay_rate <= 1, "a number in (0, 1]"),
            "decay_epochs": (number(self.decay_epochs) and self.decay_epochs > 0, "a number > 0"),
            "weight_decay": (number(self.weight_decay) and self.weight_decay >= 0, "a number >= 0"),
            "split": (self.split in SPLIT_KINDS, f"one of {', '.join(SPLIT_KINDS)}"),
            "device": (self.device == "cpu" or str(self.device).startswith("cuda"), "cpu or cuda"),
            "seed": (integer(self.seed, 0), "an integer >= 0"),
            "augment": (isinstance(self.augment, AugmentConfig), "an AugmentConfig"),
            "max_train_datapoints": (self.max_train_datapoints is None or integer(self.max_train_datapoints, 1),
                                     "None or an integer >= 1"),
            "max_train_objects": (self.max_train_objects is None or integer(self.max_train_objects, 1),
                                  "None or an integer >= 1"),
            "train_objects": (self.train_objects is None or (isinstance(self.train_objects, str)
                                                             and self.train_objects.strip() != ""),
                              "None or a non-empty pattern"),
            "max_val_datapoints": (self.max_val_datapoints is None or integer(self.max_val_datapoints, 1),
                                   "None or an integer >= 1"),
            "shuffle_shards": (integer(self.shuffle_shards, 1), "an integer >= 1"),
            "load_threads": (integer(self.load_threads, 1), "an integer >= 1"),
            "fit_datapoints": (integer(self.fit_datapoints, 1), "an integer >= 1"),
            "label_threshold": (self.label_threshold is None or number(self.label_threshold), "None or a number"),
            "target": (self.target in TARGETS, f"one of {', '.join(TARGETS)}"),
            "average": (self.average is None or (number(self.average) and 0 < self.average < 1),
                        "None or a number in (0, 1)"),
        }
        for key, (ok, need) in checks.items():
            if not ok:
                raise InputError(f"training config: {key} = {getattr(self, key)!r} must be {need}")


RESUME_IGNORES = ("epochs", "device", "load_threads")
"""Config fields that may differ between a checkpoint and the run resuming it."""
