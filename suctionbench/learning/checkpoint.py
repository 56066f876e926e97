"""Trained GQ-CNNs on disk: ``model.safetensors`` + ``model.json``, and the trainer's resume state.

A model directory holds

- ``model.safetensors``: the network's tensors under gqcnn's layer names (``image_stream.conv1_1.0.weight``,
  ``merge.fc4.bias``, ...). safetensors rather than a pickle, so loading a downloaded model cannot
  run code, and any framework can read the weights.
- ``model.json``: the model card -- architecture, input normalisation, label definition, a summary
  of the dataset (camera, cup, split, counts), metrics, training time, the command that made it,
  software versions -- and the sha256 of ``model.safetensors``, so a weights file that does not
  belong to its card (a partial copy, a mix of two runs) is refused instead of silently used.
- ``train_state.pt`` (while training; see `suctionbench.learning.train`): model, optimiser,
  scheduler and RNG states for resuming. Not needed for inference.

Every file is written atomically (temporary file + rename); the weights go first and the card
second, so a card never names weights that are not there yet.
"""

from __future__ import annotations

import json
import platform
from pathlib import Path
from typing import Any

import numpy as np
import torch

from suctionbench.errors import InputError
from suctionbench.io import atomic_path, file_digest, json_safe, read_json  # noqa: F401  (json_safe: used by train.py)
from suctionbench.learning.data import NormStats, SplitData, dataset_thumbnail
from suctionbench.learning.models import IMAGE_SIZE, build_model
from suctionbench.sensing.thumbnails import ThumbnailConfig, describe_thumbnail

WEIGHTS_NAME = "model.safetensors"
CARD_NAME = "model.json"
CARD_FORMAT = "suctionbench-gqcnn-1"

PREDICT_BATCH = 1024
"""Grasps per forward pass in `GQCNNModel.predict`: bounds memory (dn3: ~0.3 GB of activations)."""


def versions() -> dict[str, str]:
    """Software versions worth recording next to a trained model."""
    import safetensors

    from suctionbench import __version__

    return {"suctionbench": __version__, "torch": torch.__version__, "numpy": np.__version__,
            "safetensors": safetensors.__version__, "python": platform.python_version()}


class GQCNNModel:
    """A trained GQ-CNN ready for inference: network + input normalisation + model card.

    `predict` takes thumbnails and pose vectors exactly as a dataset stores them (metres, unsigned
    approach angle) and returns the probability that each grasp succeeds. `image_channels` is what
    the network reads: 1 (grasp thumbnail) or 2 (grasp and context thumbnail, the context nets).
    """

    def __init__(self, network: torch.nn.Module, stats: NormStats, card: dict[str, Any], device: str = "cpu"):
        self.network = network.to(device).eval()
        if stats.image_channels != self.image_channels:
            raise InputError(f"GQ-CNN model '{card.get('arch')}': the network reads {self.image_channels} image "
                             f"channel(s), the normalisation statistics are for {stats.image_channels}")
        if len(stats.pose_mean) != self.pose_dim:
            raise InputError(f"GQ-CNN model '{card.get('arch')}': the network reads poses of {self.pose_dim} "
                             f"values, the normalisation statistics are for {len(stats.pose_mean)}")
        self.stats = stats
        self.card = card
        self.device = torch.device(device)

    @property
    def arch(self) -> str:
        return self.card["arch"]

    @property
    def image_channels(self) -> int:
        """Image channels the network reads (1: grasp thumbnail; 2: grasp and context thumbnail)."""
        return int(getattr(self.network, "image_channels", 1))

    @property
    def pose_dim(self) -> int:
        """Length of the pose vector the network reads: 2, or 8 with the object context."""
        return int(getattr(self.network, "pose_dim", 2))

    @property
    def thumbnail(self) -> ThumbnailConfig:
        """The grasp thumbnail's geometry and sampling the network was trained on, as its dataset
        recorded it (cards from before the choice existed: gqcnn's point samples)."""
        return ThumbnailConfig.recorded(self.card.get("dataset", {}).get("thumbnail"), f"model card of '{self.arch}'")

    @property
    def target(self) -> str:
        """What the network was trained to fit (`learning.train_config.TARGETS`); models from before the
        choice existed were trained on the binary label."""
        return self.card.get("label", {}).get("target", "binary")

    def split_data(self, dataset: str | Path, kind: str, part: str, **options: Any) -> SplitData:
        """One side of a dataset's split, read as this network reads it (its image channels, the
        object context if its poses carry it); `options` as `SplitData`'s (e.g. `max_datapoints`).
        InputError if the dataset cut its grasp thumbnails otherwise than the network's were cut
        (`thumbnail`): a 96 px model shown 48 px crops scores images it never saw the like of."""
        from suctionbench.dataset.storage import read_card

        cut = dataset_thumbnail(read_card(dataset), f"dataset '{dataset}'")
        if cut != self.thumbnail:
            raise InputError(f"dataset '{dataset}': its grasp thumbnails are {describe_thumbnail(cut)}, the "
                             f"model's were {describe_thumbnail(self.thumbnail)}; its scores there would mean "
                             "nothing (score it on a dataset cut as it was trained on)")
        return SplitData(dataset, kind, part, image_channels=self.image_channels, object_context=self.pose_dim > 2,
                         **options)

    def predict(self, images: np.ndarray, poses: np.ndarray, batch_size: int = PREDICT_BATCH) -> np.ndarray:
        """Success probability q (N,) float64 for thumbnails float32 metres and poses (N, 2) =
        [gripper depth (m), approach angle (rad)] (N, 8 with the object context: `pose_dim`);
        batched, without gradients.

        Thumbnails: (N, C, 32, 32) with C = `image_channels` (channel 0 the grasp thumbnail, 1 the
        context thumbnail); a one-channel model also takes (N, 32, 32) and (N, 32, 32, 1).
        """
        images = given = np.asarray(images)
        poses = np.asarray(poses)
        channels, size = self.image_channels, IMAGE_SIZE
        if channels == 1 and images.ndim == 4 and images.shape[-1] == 1:
            images = images[..., 0]
        if channels == 1 and images.ndim == 3:
            images = images[:, None]
        if images.ndim != 4 or images.shape[1:] != (channels, size, size):
            want = f"(N, {size}, {size})" if channels == 1 else f"(N, {channels}, {size}, {size})"
            raise InputError(f"images: shape {given.shape}, expected {want} for architecture "
                             f"'{self.card.get('arch')}'")
        if poses.shape != (len(images), self.pose_dim):
            raise InputError(f"poses: shape {poses.shape}, expected ({len(images)}, {self.pose_dim}) to match the "
                             "images")
        for name, arr in (("images", images), ("poses", poses)):
            if arr.dtype.kind not in "fiu" or not np.isfinite(arr).all():
                raise InputError(f"{name}: must be finite numbers (dtype {arr.dtype})")
        out = np.empty(len(images), dtype=np.float64)
        with torch.no_grad():
            for start in range(0, len(images), batch_size):
                im = torch.from_numpy(np.ascontiguousarray(images[start:start + batch_size], dtype=np.float32))
                po = torch.from_numpy(np.ascontiguousarray(poses[start:start + batch_size], dtype=np.float32))
                im, po = self.stats.normalise(im.to(self.device), po.to(self.device))
                logits = self.network(im, po).float()
                out[start:start + len(im)] = torch.softmax(logits, dim=1)[:, 1].cpu().numpy()
        return out


def save_model(directory: str | Path, model: GQCNNModel) -> Path:
    """Write ``model.safetensors`` then ``model.json`` into `directory`; returns the card path.

    The card is `model.card` plus the arch, image channels, normalisation statistics, format tag and
    weights hash.
    """
    from safetensors.torch import save

    directory = Path(directory)
    weights = directory / WEIGHTS_NAME
    tensors = {k: v.detach().to("cpu").contiguous().clone() for k, v in model.network.state_dict().items()}
    check_finite_weights(tensors, f"model to save in '{directory}'")  # a diverged network is not a model
    # Serialised in memory (at most tens of MB), written by Python: a full disk is an OSError that
    # atomic_path reports with the path (safetensors' own file writer raises an error without one).
    data = save(tensors, metadata={"format": CARD_FORMAT, "arch": model.arch})
    with atomic_path(weights) as tmp:
        tmp.write_bytes(data)
    card = dict(model.card)
    card.update(format=CARD_FORMAT, normalisation=model.stats.to_dict(), weights=WEIGHTS_NAME,
                weights_sha256=file_digest(weights)[0])
    card["image_channels"] = model.image_channels  # cards without it (made before the context nets): 1
    path = write_model_card(directory, card)
    model.card = card
    return path


def write_model_card(directory: str | Path, card: dict[str, Any]) -> Path:
    """Write `card` as `directory`'s ``model.json`` (atomically: a reader never sees half a card);
    returns its path. `save_model` writes the whole model; this alone amends a card's facts."""
    text = json.dumps(json_safe(card), indent=2, allow_nan=False) + "\n"
    path = Path(directory) / CARD_NAME
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return path


def read_model_card(directory: str | Path) -> dict[str, Any]:
    """The card of a model directory; InputError if it is missing or malformed."""
    path = Path(directory) / CARD_NAME
    if not Path(directory).is_dir():
        raise InputError(f"model '{directory}': not a directory")
    card = read_json(path, "model card", "not a trained model directory?")
    if not isinstance(card, dict) or card.get("format") != CARD_FORMAT or not isinstance(card.get("arch"), str):
        raise InputError(f"model card '{path}': not a {CARD_FORMAT} card (format or arch missing)")
    return card


def check_finite_weights(tensors: dict[str, torch.Tensor], what: str) -> None:
    """InputError naming `what` and the first bad tensor if any floating-point tensor holds NaN or
    infinities: such a network predicts NaN (or nothing sensible) for every grasp."""
    bad = [name for name, tensor in tensors.items()
           if tensor.is_floating_point() and not bool(torch.isfinite(tensor).all())]
    if bad:
        raise InputError(f"{what}: {len(bad)} tensor(s) hold NaN or infinite values (first: {bad[0]})")


def load_model(directory: str | Path, device: str = "cpu") -> GQCNNModel:
    """A trained model from `directory`, on `device` (CPU by default); InputError if it is missing or corrupt."""
    from safetensors import SafetensorError
    from safetensors.torch import load_file

    card = read_model_card(directory)
    weights = Path(directory) / WEIGHTS_NAME
    if not weights.is_file():
        raise InputError(f"model weights '{weights}': missing")
    if file_digest(weights)[0] != card.get("weights_sha256"):
        raise InputError(f"model weights '{weights}': sha256 does not match the card (corrupt or from another run)")
    stats = NormStats.from_dict(card.get("normalisation"), source=f"model card '{Path(directory) / CARD_NAME}'")
    try:
        tensors = load_file(str(weights))
    except (SafetensorError, OSError, ValueError) as exc:
        raise InputError(f"model weights '{weights}': unreadable ({exc})") from None
    check_finite_weights(tensors, f"model weights '{weights}'")
    network = build_model(card["arch"])
    channels = network.image_channels  # the statistics' channels: GQCNNModel checks them
    if card.get("image_channels", 1) != channels:
        raise InputError(f"model card '{Path(directory) / CARD_NAME}': architecture '{card['arch']}' reads "
                         f"{channels} image channel(s), but the card records {card.get('image_channels', 1)}")
    try:
        network.load_state_dict(tensors, strict=True)
    except RuntimeError as exc:
        first = str(exc).strip().splitlines()[0]
        raise InputError(f"model weights '{weights}': do not fit architecture '{card['arch']}' ({first})") from None
    return GQCNNModel(network, stats, card, device=device)


# -- trainer state ---------------------------------------------------------------------------------

STATE_NAME = "train_state.pt"
STATE_FORMAT = "suctionbench-train-state-1"


def save_train_state(directory: str | Path, state: dict[str, Any]) -> Path:
    """Write the trainer's resume state (``train_state.pt``) atomically."""
    path = Path(directory) / STATE_NAME
    with atomic_path(path) as tmp:
        torch.save({"format": STATE_FORMAT, **state}, tmp)
    return path


def load_train_state(directory: str | Path) -> dict[str, Any] | None:
    """The trainer's resume state in `directory`, None if there is none; InputError if it is corrupt.

    Loaded with ``weights_only=True``: tensors and plain Python values only, no code.
    """
    path = Path(directory) / STATE_NAME
    if not path.is_file():
        return None
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # torch raises several types for a truncated or foreign file
        raise InputError(f"training checkpoint '{path}': unreadable ({type(exc).__name__}); delete it to "
                         "start over") from None
    if not isinstance(state, dict) or state.get("format") != STATE_FORMAT:
        raise InputError(f"training checkpoint '{path}': not a {STATE_FORMAT} file")
    model = state.get("model")
    if isinstance(model, dict):  # resuming from NaN weights would train on NaN
        check_finite_weights({k: v for k, v in model.items() if isinstance(v, torch.Tensor)},
                             f"training checkpoint '{path}'")
    return state
