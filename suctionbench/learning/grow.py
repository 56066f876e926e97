"""Grow a trained GQ-CNN into a wider one that computes the same function (Net2WiderNet).

Why: the held-out accuracy of the context nets rises with their size (eval/gqcnn/README.md,
"capacity"), but a wider net trained from scratch repeats the hours its narrower parent already
spent. Chen, Goodfellow and Shlens, "Net2Net: Accelerating Learning via Knowledge Transfer"
(ICLR 2016), widen a trained ReLU net without changing its output: each new unit copies an
existing unit's incoming weights and bias, and the layer that reads both shares the original's
outgoing weight between them, so ``sum of the copies' contributions = the original's``.

Net2Net divides the outgoing weight equally and adds noise to break the copies' symmetry (equal
copies receive equal gradients forever). Here each outgoing weight is split between the copies
in random positive shares that sum to one, element by element: the output stays exact (up to
float rounding) and the copies, weighted differently, receive different gradients from the
first step on.

Only nets without local response normalisation grow (LRN mixes neighbouring channels, so a
copied channel changes its neighbours' outputs); the compact family (`compact`, `context*`) has
none. Growing needs the same layout: the same layers, kernels, padding and inputs, every width
at least its parent's.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn

from suctionbench.learning.models import GQCNN

SHARE_RANGE = (0.5, 1.5)
"""Outgoing weights are split between copies in proportion to draws from this range: unequal
enough to break the copies' symmetry, no copy's share near zero."""


def _layers(model: nn.Module) -> list[tuple[str, nn.Module]]:
    """(name, layer) of every Conv2d / Linear / LocalResponseNorm, in the order of `named_modules`:
    the layers growth copies units of, and the one kind it refuses."""
    kinds = nn.Conv2d | nn.Linear | nn.LocalResponseNorm
    return [(name, module) for name, module in model.named_modules() if isinstance(module, kinds)]


def growth_problem(base: GQCNN, target: GQCNN) -> str | None:
    """Why `target` cannot be grown from `base` (see the module doc), or None when it can: `target`
    must be `base` with every width the same or larger."""
    base_layers, target_layers = _layers(base), _layers(target)
    if any(isinstance(layer, nn.LocalResponseNorm) for _, layer in base_layers + target_layers):
        return "local response normalisation, which a copied channel would change"
    if [name for name, _ in base_layers] != [name for name, _ in target_layers]:
        return "the layers differ"
    if base.pose_dim != target.pose_dim or base.image_channels != target.image_channels:
        return "the inputs differ"
    for (name, old), (_, new) in zip(base_layers, target_layers, strict=True):
        if isinstance(old, nn.Conv2d) and (old.kernel_size != new.kernel_size or old.padding != new.padding):
            return f"layer {name}'s kernel or padding differ"
        if old.weight.shape[0] > new.weight.shape[0]:
            return f"layer {name} is narrower ({new.weight.shape[0]} < {old.weight.shape[0]})"
    return None


def _mapping(old: int, new: int, rng: np.random.Generator) -> np.ndarray:
    """Which original unit each of `new` units copies: the originals first, then the extra units
    drawn without repeats until every original has been copied once more (Net2Net draws with
    replacement; without, doubling gives every unit exactly one copy)."""
    extra = new - old
    draws = [rng.permutation(old) for _ in range(-(-extra // old))] if extra > 0 else []
    return np.concatenate([np.arange(old), *draws])[:new].astype(np.int64)


def _shared_inputs(weight: torch.Tensor, mapping: np.ndarray, old_inputs: int,
                   rng: np.random.Generator) -> torch.Tensor:
    """`weight` (out, in, ...) with its input dimension grown by `mapping`: each copy of input i gets
    a random share of the original weight on i, the shares of i's copies summing to one."""
    index = torch.from_numpy(mapping)
    gathered = weight.index_select(1, index)
    draws = torch.from_numpy(rng.uniform(*SHARE_RANGE, size=tuple(gathered.shape))).to(weight.dtype)
    totals = torch.zeros((gathered.shape[0], old_inputs, *gathered.shape[2:]), dtype=weight.dtype)
    totals.index_add_(1, index, draws)
    return gathered * draws / totals.index_select(1, index)


def _concat_mapping(parts: list[tuple[np.ndarray, int]]) -> tuple[np.ndarray, int]:
    """One input mapping for a layer that reads several layers' outputs side by side:
    `parts` = (mapping, old width) per input block in order; returns (mapping, old total width)."""
    pieces, offset = [], 0
    for mapping, old in parts:
        pieces.append(mapping + offset)
        offset += old
    return np.concatenate(pieces), offset


def grow(base: GQCNN, target: GQCNN, rng: np.random.Generator) -> None:
    """Set `target`'s weights so that it computes what `base` computes (see the module doc).

    `target` must be growable from `base` (`growth_problem` is None). Image stream, context stream
    and pose stream are widened layer by layer; the merge's first layer reads all three.
    """
    with torch.no_grad():
        state = {}
        ends: list[tuple[np.ndarray, int]] = []  # (mapping, old width) of each block the merge reads
        context = ["context_stream"] if base.context_stream is not None else []
        for prefix in ["image_stream", *context, "pose_stream"]:
            ends.append(_grow_chain(state, prefix, _paired(base, target, prefix), rng))
        _grow_chain(state, "merge", _paired(base, target, "merge"), rng, first_inputs=_concat_mapping(ends))
        target.load_state_dict(state)


def _paired(base: GQCNN, target: GQCNN, prefix: str) -> list[tuple[str, nn.Module, nn.Module]]:
    """(name, base layer, target layer) of the part `prefix` of both nets, in order."""
    return [(name, old, new) for (name, old), (_, new) in zip(
        _layers(getattr(base, prefix)), _layers(getattr(target, prefix)), strict=True)]


def _grow_chain(state: dict, prefix: str, chain: list[tuple[str, nn.Module, nn.Module]], rng: np.random.Generator,
                first_inputs: tuple[np.ndarray, int] | None = None) -> tuple[np.ndarray, int]:
    """Widen a chain of layers, each reading the previous one's output, into `state` (tensors under
    the target's names); `first_inputs` maps the first layer's inputs when an earlier block grew
    them. Returns (mapping, old width) of the chain's output. A Linear after a Conv2d reads the
    flattened (channels, height, width) map, so its inputs grow channel by channel."""
    inputs = first_inputs
    previous_conv = False
    for name, old, new in chain:
        weight, bias = old.weight, old.bias
        if inputs is not None:
            mapping, old_inputs = inputs
            if isinstance(old, nn.Linear) and previous_conv:  # (out, C * H * W) read as (out, C, H * W)
                spatial = weight.shape[1] // old_inputs
                weight = _shared_inputs(weight.reshape(weight.shape[0], old_inputs, spatial), mapping,
                                        old_inputs, rng).reshape(weight.shape[0], -1)
            else:
                weight = _shared_inputs(weight, mapping, old_inputs, rng)
        outputs = _mapping(old.weight.shape[0], new.weight.shape[0], rng)
        index = torch.from_numpy(outputs)
        key = f"{prefix}.{name}"
        state[f"{key}.weight"] = weight.index_select(0, index).clone()
        state[f"{key}.bias"] = bias.index_select(0, index).clone()
        inputs = (outputs, old.weight.shape[0])
        previous_conv = isinstance(old, nn.Conv2d)
    return inputs

