"""GQ-CNN architectures for suction: the Dex-Net 3.0 network (`dn3`) and a CPU-friendly `compact` net.

Both take normalised inputs -- images (B, 1, 32, 32) and poses (B, 2) = [gripper depth, signed
approach angle], each standardised with the training set's statistics (`suctionbench.learning.data`)
-- and return logits (B, 2); softmax column 1 is the predicted probability that the grasp succeeds.
`build_model(arch)` is the one entry point; `ARCHITECTURES` lists the names.

dn3: gqcnn's GQCNN-3.0 (cfg/train_dex-net_3.0.yaml), layer for layer
---------------------------------------------------------------------
image stream  conv1_1 7x7x64 -> conv1_2 5x5x64, LRN, 2x2 max-pool -> conv2_1 3x3x64 -> conv2_2 3x3x64,
              LRN, 2x2 max-pool -> fc3 1024
pose stream   pc1 2 -> 128
merge         fc4 (1024 + 128) -> 1024 -> fc5 1024 -> 2 (logits; softmax outside the network)

Every convolution is stride 1 with SAME padding and every hidden layer is followed by a ReLU
(gqcnn's leaky ReLU with coefficient 0). Inside a conv block gqcnn applies conv -> ReLU -> LRN ->
max-pool (network_tf.py `_build_conv_layer`), and so does `_ConvBlock`. gqcnn's fc4 keeps separate
weight matrices for its two inputs plus one bias, which is exactly one linear layer on their
concatenation; it is built that way here. gqcnn's pools use TF SAME padding, which on the even
sizes 32 and 16 adds no padding, so ``nn.MaxPool2d(2)`` is the same operation.

Local response normalisation, TF vs torch. TF computes
``x / (bias + alpha * sum_{|j - c| <= r} x_j^2) ** beta`` with ``depth_radius`` r; torch's
``nn.LocalResponseNorm(size, alpha, beta, k)`` computes ``x / (k + alpha / size * sum) ** beta``
over a window of ``size`` channels, i.e. torch divides alpha by the window size. gqcnn's
r = 2, alpha = 2e-5, beta = 0.75, bias = 1 is therefore torch's size = 2 r + 1 = 5,
alpha = 2e-5 * 5 = 1e-4, beta = 0.75, k = 1 (torch centres an odd window like TF: two channels
each side). `tf_lrn_to_torch` does the conversion; a test checks it against the TF formula.

Parameter count of dn3 (weights + biases): conv1_1 7*7*1*64 + 64 = 3,200; conv1_2 5*5*64*64 + 64 =
102,464; conv2_1 and conv2_2 3*3*64*64 + 64 = 36,928 each; fc3 8*8*64*1024 + 1024 = 4,195,328; pc1
2*128 + 128 = 384; fc4 (1024 + 128) * 1024 + 1024 = 1,180,672; fc5 1024*2 + 2 = 2,050; total
5,557,954. Cost: 132.3 M multiply-accumulates per grasp (265 MFLOP), 79 % of it in conv1_2.

Initialisation (gqcnn): every weight and every hidden bias ~ truncated normal with std
sqrt(2 / fan_in) (He), cut at two standard deviations like ``tf.truncated_normal``; the output
layer's bias starts at 0. fan_in of fc4 counts both inputs (1024 + 128).

compact: Dex-Net 4.0's suction net, adapted to 32 x 32
------------------------------------------------------
Dex-Net 4.0 made suction GQ-CNNs small enough for a CPU (96 x 96 input, conv 9x9x8 -> pool ->
conv 3x3x8 -> conv 3x3x8 -> pool, VALID padding, fc 64; pose fc 16; merge fc 64 -> 2). Our
thumbnails are the 96 x 96 crop scaled by 1/3, so 9 image pixels become 3 thumbnail pixels; the
adaptation keeps the layout, VALID padding and the small fully connected layers, uses 5x5 then 3x3
kernels at the coarser scale and 16 filters instead of 8 (the 32 x 32 input carries the same scene
in 9x fewer pixels, so each pixel needs a richer description):

image stream  conv 5x5x16 VALID -> 28, 2x2 max-pool -> 14 -> conv 3x3x16 -> 12 -> conv 3x3x16 -> 10,
              2x2 max-pool -> 5 x 5 x 16 -> fc 64
pose stream   fc 16
merge         fc (64 + 16) -> 64 -> fc 64 -> 2

VALID padding keeps padded zeros (which, normalised, would read as "mean depth") out of the
features, and the sizes are chosen so the grasp point stays on the centre of every feature map
(15.5 -> 13.5 -> 6.5 -> 5.5 -> 4.5 -> 2), which keeps the net's geometry symmetric under the flips
and the rotation of training-time symmetrisation. Parameters: 416 + 2,320 + 2,320 + 25,664 (fc)
+ 48 (pose) + 5,184 (merge) + 130 (out) = 36,082; cost 0.91 M multiply-accumulates (1.8 MFLOP) per
grasp, ~146x less than dn3. Same initialisation as dn3.

context, context-wide: what decides the label, in view
------------------------------------------------------
With a physical cup the robust label depends on the gravity torque, i.e. on where the grasp lies
relative to the object's centre of mass, and the 96-pixel crop (~11 cm at 0.6 m) cannot see the
centre of a long or large object. These nets add a second image stream of compact's layout that
reads the context thumbnail (`suctionbench.sensing.thumbnails.THUMBNAIL_CONTEXT`: 3x the field of
view, 288 pixels, at the same 32 x 32, each pixel a 9 x 9 block mean), rotated like the grasp
thumbnail so training-time flips apply to both channels alike. Inputs: images (B, 2, 32, 32) =
(grasp, context). context: 2 x 30,720 (image streams) + 48 (pose) + 9,280 (merge: (2 x 64 + 16)
x 64 + 64) + 130 = 70,898 parameters, 1.8 M multiply-accumulates per grasp; context-wide, twice
the filters and fc widths: 281,058 parameters, 6.0 M multiply-accumulates.

context-pose: the object context in metres
------------------------------------------
The context net with a pose vector of 2 + 6: gripper depth, approach angle, and the object context
(`suctionbench.sensing.object_context`: the grasp's horizontal offset from the visible object's
centroid, that offset along the approach's lean, the grasp's rise above the centroid, the visible
object's length, width and top), read from the dataset field ``object_context``. Distances the
context thumbnail shows only in pixels of depth-dependent size, and a long object's centre that
it may not show at all. 70,994 parameters (pc1: 8 x 16 + 16).

context-pose-wide-fc, context-pose-wider: larger, grown from a trained net
-------------------------------------------------------------------------
Held-out accuracy rose with size from context-pose to context-pose-wide, and the wide net fits its
own training data barely better than held-out data: it underfits. Two larger layouts, meant to be
grown from a trained context-pose-wide (`suctionbench.learning.grow`, ``train --init``) rather
than trained from scratch: context-pose-wide-fc keeps the 32 filters and makes every fc layer 4x
wider (image fc 512, pose fc 128, merge fc 512: 1,451,394 parameters, 7.2 M multiply-accumulates,
most of the added size where it costs little time); context-pose-wider doubles everything (64
filters, fc 256 / 64 / 256: 1,119,554 parameters, 21.5 M multiply-accumulates, 3.6x the wide net's).
Measured (eval/gqcnn/README.md): the default grown into context-pose-wide-fc was level held out
with the same training at its own size, so the wide net's fc layers are not where it underfits;
grown into context-pose-wider it gained 0.1 point held out and as much on its own training data,
so capacity is not what holds the wide net's accuracy at ~0.92.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Sequence

import torch
from torch import nn

from suctionbench.errors import InputError
from suctionbench.sensing.object_context import OBJECT_CONTEXT_COLUMNS

IMAGE_SIZE = 32
"""Side of the square thumbnail both networks take (pixels)."""

POSE_DIM = 2
"""Length of the pose vector: [gripper depth, approach angle]."""

OBJECT_CONTEXT_DIM = len(OBJECT_CONTEXT_COLUMNS)
"""Length of the object context the `context-pose` net appends to its pose vector
(`suctionbench.sensing.object_context`: where the grasp lies on the visible object, in metres)."""

LRN_RADIUS = 2
"""gqcnn's LRN ``depth_radius`` r (channels each side of the centre channel)."""

LRN_ALPHA_TF = 2e-5
"""gqcnn's LRN alpha in TensorFlow's convention (multiplies the sum of squares itself)."""

LRN_BETA = 0.75
"""gqcnn's LRN exponent beta."""

LRN_BIAS = 1.0
"""gqcnn's LRN bias (torch's k)."""

TRUNCATION = 2.0
"""Truncated-normal initialisation is cut at this many standard deviations (``tf.truncated_normal``)."""


def tf_lrn_to_torch(radius: int, alpha: float, beta: float, bias: float) -> nn.LocalResponseNorm:
    """The torch layer equal to ``tf.nn.local_response_normalization(depth_radius=radius, alpha=...)``.

    torch divides alpha by the window size, TF does not: window 2 r + 1, alpha_torch = alpha_tf (2 r + 1).
    """
    size = 2 * radius + 1
    return nn.LocalResponseNorm(size, alpha=alpha * size, beta=beta, k=bias)


def max_pool_2x2(x: torch.Tensor) -> torch.Tensor:
    """``F.max_pool2d(x, 2)`` (2 x 2, stride 2, an odd last row or column dropped) as the elementwise
    maxima of the four strided views: the same values, ~7x faster on CPU (1.2 against 9.2 ms on
    200 x 16 x 28 x 28, 2 threads)."""
    x = x[..., : x.shape[-2] // 2 * 2, : x.shape[-1] // 2 * 2]
    return torch.maximum(torch.maximum(x[..., 0::2, 0::2], x[..., 0::2, 1::2]),
                         torch.maximum(x[..., 1::2, 0::2], x[..., 1::2, 1::2]))


class MaxPool2x2(nn.MaxPool2d):
    """``nn.MaxPool2d(2)`` whose forward pass without autograd (planning, evaluation) is
    `max_pool_2x2`; with autograd it is max_pool2d itself, whose gradient (all of it to the first
    maximum of a tie) the shipped models were trained with."""

    def __init__(self) -> None:
        super().__init__(2)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if torch.is_grad_enabled() and x.requires_grad:
            return super().forward(x)
        return max_pool_2x2(x)


class _ConvBlock(nn.Sequential):
    """conv -> ReLU [-> LRN] [-> 2x2 max-pool], gqcnn's order within a conv layer."""

    def __init__(self, in_channels: int, out_channels: int, kernel: int, *, padding: str, lrn: bool, pool: bool):
        layers: list[nn.Module] = [nn.Conv2d(in_channels, out_channels, kernel, padding=padding), nn.ReLU()]
        if lrn:
            layers.append(tf_lrn_to_torch(LRN_RADIUS, LRN_ALPHA_TF, LRN_BETA, LRN_BIAS))
        if pool:
            layers.append(MaxPool2x2())
        super().__init__(*layers)


def _image_stream(convs: Sequence[tuple[str, int, int, bool, bool]], padding: str, image_fc: int) -> nn.Sequential:
    """conv blocks on one 32 x 32 channel, flattened into a ReLU fc layer of `image_fc` features."""
    layers: dict[str, nn.Module] = {}
    channels, size = 1, IMAGE_SIZE
    for name, out_channels, kernel, lrn, pool in convs:
        layers[name] = _ConvBlock(channels, out_channels, kernel, padding=padding, lrn=lrn, pool=pool)
        channels = out_channels
        size = size if padding == "same" else size - kernel + 1
        size = size // 2 if pool else size
    layers.update(flatten=nn.Flatten(), fc3=nn.Linear(channels * size * size, image_fc), relu3=nn.ReLU())
    return nn.Sequential(OrderedDict(layers))


class GQCNN(nn.Module):
    """GQ-CNN: conv image stream + fc, fc pose stream, merged by fc layers into 2 logits; with
    `context`, a second image stream of the same layout reads the context thumbnail (channel 1).

    The architectures differ only in their layer sizes and the context stream (`_SPECS`), so one
    class builds them all. `image_channels` is 1 (the grasp thumbnail) or 2 (grasp, context).
    """

    def __init__(self, convs: Sequence[tuple[str, int, int, bool, bool]], padding: str, image_fc: int, pose_fc: int,
                 merge_fc: int, context: bool = False, object_context: bool = False):
        super().__init__()
        # gqcnn's layer names (conv*, fc3, pc1, fc4, fc5) name the tensors of a saved model.
        self.image_stream = _image_stream(convs, padding, image_fc)
        self.context_stream = _image_stream(convs, padding, image_fc) if context else None
        self.image_channels = 2 if context else 1
        self.pose_dim = POSE_DIM + (OBJECT_CONTEXT_DIM if object_context else 0)
        self.pose_stream = nn.Sequential(OrderedDict(pc1=nn.Linear(self.pose_dim, pose_fc), relu=nn.ReLU()))
        self.merge = nn.Sequential(OrderedDict(fc4=nn.Linear(self.image_channels * image_fc + pose_fc, merge_fc),
                                               relu=nn.ReLU(), fc5=nn.Linear(merge_fc, 2)))

    def forward(self, images: torch.Tensor, poses: torch.Tensor) -> torch.Tensor:
        """Logits (B, 2) for normalised images (B, image_channels, 32, 32) and poses (B, pose_dim)."""
        features = [self.image_stream(images[:, :1])]
        if self.context_stream is not None:
            features.append(self.context_stream(images[:, 1:2]))
        return self.merge(torch.cat([*features, self.pose_stream(poses)], dim=1))


def _compact_layout(width: int, fc_scale: int | None = None, **extra) -> dict:
    """compact's layer layout with `width` filters per conv layer and fc widths scaled alike
    (or by `fc_scale` times compact's)."""
    scale = fc_scale or width // 16
    convs = [("conv1", width, 5, False, True), ("conv2", width, 3, False, False), ("conv3", width, 3, False, True)]
    return {"convs": convs,
            "padding": "valid", "image_fc": 64 * scale, "pose_fc": 16 * scale, "merge_fc": 64 * scale, **extra}


_SPECS: dict[str, dict] = {
    # (name, out_channels, kernel, LRN after ReLU, 2x2 max-pool at the end) per conv layer
    "dn3": {"convs": [("conv1_1", 64, 7, False, False), ("conv1_2", 64, 5, True, True),
                      ("conv2_1", 64, 3, False, False), ("conv2_2", 64, 3, True, True)],
            "padding": "same", "image_fc": 1024, "pose_fc": 128, "merge_fc": 1024},
    "compact": _compact_layout(16),
    # compact's layout twice: the grasp thumbnail and the context thumbnail (module doc, "context")
    "context": _compact_layout(16, context=True),
    # the same with twice the filters and fc widths: the capacity step of the size sweep
    "context-wide": _compact_layout(32, context=True),
    # context, and the object context in metres in the pose stream (module doc, "context-pose")
    "context-pose": _compact_layout(16, context=True, object_context=True),
    # context-pose with twice the filters and fc widths: the capacity step with the object context
    "context-pose-wide": _compact_layout(32, context=True, object_context=True),
    # context-pose-wide with 4x its fc widths: capacity where it costs few multiply-adds (module doc)
    "context-pose-wide-fc": _compact_layout(32, fc_scale=8, context=True, object_context=True),
    # context-pose-wide with twice the filters and fc widths (module doc, "larger")
    "context-pose-wider": _compact_layout(64, context=True, object_context=True),
}

ARCHITECTURES = tuple(_SPECS)
"""Names `build_model` accepts, and `train`: the context nets train on datasets that store the
context thumbnail (`context_ims_tf_table`, written by ``suctionbench generate``); `image_channels_of`
tells which."""



def image_channels_of(arch: str) -> int:
    """Image channels network `arch` reads: 1 (grasp thumbnail) or 2 (grasp, context); InputError
    for an unknown name. The same as ``build_model(arch).image_channels``, without building it."""
    if arch not in _SPECS:
        raise InputError(f"architecture '{arch}': unknown (known: {', '.join(ARCHITECTURES)})")
    return 2 if _SPECS[arch].get("context") else 1


def pose_dim_of(arch: str) -> int:
    """Length of the pose vector network `arch` reads: POSE_DIM, plus OBJECT_CONTEXT_DIM for the nets
    with the object context; InputError for an unknown name."""
    if arch not in _SPECS:
        raise InputError(f"architecture '{arch}': unknown (known: {', '.join(ARCHITECTURES)})")
    return POSE_DIM + (OBJECT_CONTEXT_DIM if _SPECS[arch].get("object_context") else 0)


def init_weights(model: nn.Module, generator: torch.Generator | None = None) -> None:
    """gqcnn's initialisation: weights and hidden biases ~ truncated normal, std sqrt(2 / fan_in); output bias 0.

    `generator` makes the draw reproducible without touching torch's global RNG.
    """
    layers = [m for m in model.modules() if isinstance(m, nn.Conv2d | nn.Linear)]
    for index, layer in enumerate(layers):
        fan_in = layer.weight[0].numel()  # in_channels * kh * kw, or in_features
        std = math.sqrt(2.0 / fan_in)
        bound = TRUNCATION * std
        with torch.no_grad():
            nn.init.trunc_normal_(layer.weight, std=std, a=-bound, b=bound, generator=generator)
            if index == len(layers) - 1:
                nn.init.zeros_(layer.bias)
            else:
                nn.init.trunc_normal_(layer.bias, std=std, a=-bound, b=bound, generator=generator)


def build_model(arch: str, generator: torch.Generator | None = None) -> GQCNN:
    """A freshly initialised network `arch` (see `ARCHITECTURES`); InputError for an unknown name."""
    if arch not in _SPECS:
        raise InputError(f"architecture '{arch}': unknown (known: {', '.join(ARCHITECTURES)})")
    model = GQCNN(**_SPECS[arch])
    init_weights(model, generator)
    return model


def count_parameters(model: nn.Module) -> int:
    """Number of trainable scalars."""
    return sum(p.numel() for p in model.parameters() if p.requires_grad)


def count_macs(model: GQCNN) -> int:
    """Multiply-accumulates of one forward pass for one grasp, over conv and linear layers (FLOPs ~ 2x).

    Measured by running one dummy input through the network with hooks, so it follows the real
    feature-map sizes; ReLU, LRN and pooling are not counted (a few % of the total).
    """
    total = 0

    def hook(module: nn.Module, _inputs, output: torch.Tensor) -> None:
        nonlocal total
        total += module.weight[0].numel() * output[0].numel()  # MACs per output value x output values

    _dummy_forward(model, [m for m in model.modules() if isinstance(m, nn.Conv2d | nn.Linear)], hook)
    return total


def activation_bytes(model: GQCNN) -> int:
    """Bytes of the outputs of every layer in one forward pass for one grasp: what a training step
    keeps per image for the backward pass (measured with hooks on a dummy input, like `count_macs`)."""
    total = 0

    def hook(_module: nn.Module, _inputs, output: torch.Tensor) -> None:
        nonlocal total
        if isinstance(output, torch.Tensor):
            total += output.numel() * output.element_size()

    _dummy_forward(model, [m for m in model.modules() if not list(m.children())], hook)
    return total


def _dummy_forward(model: GQCNN, modules: list[nn.Module], hook) -> None:
    """One forward pass of a zero grasp (one image, one pose) with `hook` on `modules`, removed after."""
    handles = [m.register_forward_hook(hook) for m in modules]
    try:
        with torch.no_grad():
            param = next(model.parameters())
            model(torch.zeros(1, model.image_channels, IMAGE_SIZE, IMAGE_SIZE, device=param.device),
                  torch.zeros(1, model.pose_dim, device=param.device))
    finally:
        for handle in handles:
            handle.remove()
