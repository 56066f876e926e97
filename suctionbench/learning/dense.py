"""A GQ-CNN evaluated densely: every thumbnail of a resampled depth image in one pass (FC-GQ-CNN).

Dex-Net 4.0 (Mahler et al., Science Robotics 2019; Satish et al., RA-L 2019) turns a trained
GQ-CNN into a fully convolutional one, so one forward pass scores the grasps at every image
position instead of one thumbnail at a time. `DenseGQCNN` does that for a trained `GQCNN` of
VALID padding (`compact`): the same weights, rearranged, give exactly the thumbnail network's
output at every position of a grid.

Why exact. Along the image stream a thumbnail network is a chain of VALID convolutions, ReLUs and
2 x 2 max-pools of stride 2, then a fully connected layer over the last s x s x C map. Slid over a
larger image, the convolutions already compute every window's features; only the pools' stride
would skip windows. So each pool runs with stride 1 instead, and every later layer reads its
input with a dilation of 2 per pool passed (the "a trous" identity: what a stride-2 pool followed
by a kernel of taps 1 apart computes for one window equals a stride-1 pool followed by the same
kernel with taps 2 apart, at the window's position). The fully connected layer over the last
s x s x C map then reads, for a window, its s x s taps that dilation apart (gathered in torch's
(C, H, W) flatten order, so the layer's own weights apply), and the pose stream and the merge run
as they are, one pose per position. Position (i, j) is the 32 x 32 window whose top-left pixel is
(i, j), i.e. the thumbnail centred on (i + 15.5, j + 15.5).

Cost. No pooling shrinks the maps, so every layer runs at the input's resolution: for compact,
400 + 2 x 2,304 + 25,600 + merge ~ 31 k multiply-accumulates per position, where a thumbnail
costs 0.91 M: ~30x less per grasp, when all positions are wanted. Most positions of a scene are
not wanted (off the object, or scored at another rotation of the image), so the pass splits in
two: `trunk` (the convolutions, 5 k per position, over the whole image) and `head` (the fully
connected layer, 26 k, gathered at the positions asked for, and the merge). Where windows every
other position are enough (a fine thumbnail pitch), `trunk(stride=2)` keeps the first pool's stride
and runs the layers after it on a quarter of the positions: for compact 400 + 4,608 / 4 ~ 1.6 k
per input position.

Context nets (two image streams). The context stream reads a thumbnail of the same layout cut
from a 3x coarser, box-filtered image, so it gets its own dense trunk on its own lattice (the
caller resamples that image) and its own window per position; the head concatenates both streams'
features with the pose stream's, in the network's order, and runs the network's merge.

Not converted: SAME padding (`dn3`: its padded zeros inside a thumbnail are neighbouring pixels
in the whole image, so the values would differ near every thumbnail's border).
"""

from __future__ import annotations

from collections.abc import Sequence

import torch
import torch.nn.functional as F
from torch import nn

from suctionbench.errors import InputError
from suctionbench.learning.models import GQCNN, max_pool_2x2


class DenseStream(nn.Module):
    """One image stream of a VALID-padded `GQCNN` in dense form: its convolutions and pools run over
    a whole image (`trunk`), its fully connected layer at the windows asked for (`features`)."""

    def __init__(self, stream: nn.Sequential):
        super().__init__()
        self.stream = stream
        self.layers: list[tuple[nn.Module, int]] = []
        """(module, dilation) of the stream's conv blocks, in order (conv, ReLU, LRN, pool; a pool
        right after a ReLU runs before it)."""
        dilation = 1
        for block in stream:
            if isinstance(block, nn.Sequential):  # a conv block: conv -> ReLU [-> LRN] [-> pool]
                for module in block:
                    if isinstance(module, nn.Conv2d) and module.padding not in ((0, 0), "valid"):
                        raise InputError("dense GQ-CNN: only VALID-padded networks convert exactly (not dn3)")
                    self.layers.append((module, dilation))
                    dilation *= 2 if isinstance(module, nn.MaxPool2d) else 1
            elif isinstance(block, nn.Linear):  # fc3: read densely as s x s taps, `dilation` apart
                self.fc3, self.fc_dilation = block, dilation
            elif not isinstance(block, nn.Flatten | nn.ReLU):
                raise InputError(f"dense GQ-CNN: image stream layer {block!r} has no dense form")
        for i in range(len(self.layers) - 1):  # ReLU then pool -> pool then ReLU: max commutes with
            # the monotone ReLU, so the values are the same and the ReLU runs on the pooled map
            if isinstance(self.layers[i][0], nn.ReLU) and isinstance(self.layers[i + 1][0], nn.MaxPool2d):
                self.layers[i], self.layers[i + 1] = self.layers[i + 1], self.layers[i]
        self.pooled_convs = frozenset(i for i in range(len(self.layers) - 1) if isinstance(self.layers[i][0], nn.Conv2d)
                                      and isinstance(self.layers[i + 1][0], nn.MaxPool2d))
        """Indices in `layers` of the convolutions a max-pool follows directly (`_conv_pooled`)."""
        channels = next(m for m, _ in reversed(self.layers) if isinstance(m, nn.Conv2d)).out_channels
        self.fc_side = round((self.fc3.in_features / channels) ** 0.5)

    @property
    def max_stride(self) -> int:
        """The coarsest window stride `trunk` can give: 2 to the number of the stream's pools."""
        return self.fc_dilation

    def trunk(self, image: torch.Tensor, stride: int = 1) -> torch.Tensor:
        """The stream's maps before its fully connected layer, (B, C, h, w), for a normalised image
        (B, 1, H, W): the cheap part, shared by every position.

        `stride` (a power of 2, at most `max_stride`): only the windows whose top-left pixel is a
        multiple of it, the first log2(stride) pools keeping their stride 2 (a window at an even
        position pools the same 2 x 2 blocks as the whole image's stride-2 pool), so every later
        layer runs on stride^2 times fewer positions. Window (i, j) is then map position
        (i / stride, j / stride)."""
        if stride not in {2**k for k in range(self.max_stride.bit_length())}:
            raise ValueError(f"dense GQ-CNN: stride {stride} is not a power of 2 up to {self.max_stride}")
        x, done = image, 1  # done: the subsampling the strided pools have applied so far
        layers = enumerate(self.layers)
        for at, (module, dilation) in layers:
            step = dilation // done  # the layer's taps apart, in the subsampled maps
            if at in self.pooled_convs and done < stride:
                next(layers)  # conv, then the pool at stride 2: as four stride-2 convolutions
                x = _conv_pooled(x, module, step)
                done *= 2
            elif isinstance(module, nn.Conv2d):
                x = F.conv2d(x, module.weight, module.bias, dilation=step)
            elif isinstance(module, nn.MaxPool2d) and done < stride:  # the pool as it is, stride 2
                x = max_pool_2x2(x)
                done *= 2
            elif isinstance(module, nn.MaxPool2d):  # 2 x 2, stride 1, taps `step` apart
                # as two elementwise maxima of shifted views: several times faster on CPU than
                # max_pool2d's dilated path, and the same values
                x = torch.maximum(x[..., :, :-step], x[..., :, step:])
                x = torch.maximum(x[..., :-step, :], x[..., step:, :])
            elif isinstance(module, nn.ReLU):
                x = torch.relu_(x)  # in place: x is this pass's own fresh map
            else:
                x = module(x)
        return x

    def features(self, maps: torch.Tensor, batch: torch.Tensor, rows: torch.Tensor, cols: torch.Tensor,
                 stride: int = 1) -> torch.Tensor:
        """The fully connected layer's output (P, F) at P windows (image `batch`, `rows`, `cols`;
        (P,) long) of the trunk's `maps` (computed with `stride`): its s x s taps gathered where the
        dense form would read them (the final dilation apart), in (row, column, channel) order,
        with the layer's own weights read in that order. Window (i, j) is the
        32 x 32 window whose top-left pixel is (stride i, stride j)."""
        _, channels, height, width = maps.shape
        taps = self.fc_dilation // stride * torch.arange(self.fc_side, device=maps.device)
        r = rows[:, None, None] + taps[None, :, None]
        c = cols[:, None, None] + taps[None, None, :]
        # Gathered as rows of C from channels-last maps, (P, s, s, C) contiguous: one transposed
        # copy of the maps instead of a permuted copy of every window's s x s x C taps
        pixels = maps.permute(0, 2, 3, 1).reshape(-1, channels)  # (B h w, C)
        windows = pixels[((batch[:, None, None] * height + r) * width + c).reshape(-1)]
        weight = self.fc3.weight  # (F, C s s) in torch's flatten order, read as (F, s s C)
        tapwise = weight.reshape(len(weight), channels, self.fc_side, self.fc_side).permute(0, 2, 3, 1)
        return torch.relu(F.linear(windows.reshape(len(rows), -1), tapwise.reshape(len(weight), -1), self.fc3.bias))


def _conv_pooled(x: torch.Tensor, conv: nn.Conv2d, dilation: int) -> torch.Tensor:
    """``max_pool_2x2(F.conv2d(x, ...))`` as the maxima of four convolutions of stride 2, one per
    phase (i, j) of the pool's 2 x 2 blocks: the full convolution at (2p + i, 2q + j) is the
    stride-2 convolution of x shifted by (i, j) at (p, q). The same values (each output is the
    same sum), without writing and re-reading the full-resolution map: 1.3x faster on 2 cores for
    conv1 of 16 lattices of 124 x 122 (4.1 against 5.3 ms). All four read windows of one shape, so
    they share one compiled convolution."""
    height, width = x.shape[-2] - 1, x.shape[-1] - 1
    phases = [F.conv2d(x[..., i:i + height, j:j + width], conv.weight, conv.bias, stride=2, dilation=dilation)
              for i in (0, 1) for j in (0, 1)]
    return torch.maximum(torch.maximum(phases[0], phases[1]), torch.maximum(phases[2], phases[3]))


Window = tuple[torch.Tensor, torch.Tensor, torch.Tensor]
"""(batch, rows, cols), each (P,) long: one window per output position, in one stream's maps."""


class DenseGQCNN(nn.Module):
    """The fully convolutional form of a VALID-padded `GQCNN` (module doc): one `DenseStream` per
    image stream (`streams`: grasp, then context for the context nets), the network's own pose
    stream and merge at the positions asked for (`head`)."""

    def __init__(self, net: GQCNN):
        super().__init__()
        self.net = net
        self.streams = nn.ModuleList([DenseStream(net.image_stream)]
                                     + ([DenseStream(net.context_stream)] if net.context_stream is not None else []))

    def head(self, maps: Sequence[torch.Tensor], windows: Sequence[Window], poses: torch.Tensor) -> torch.Tensor:
        """Logits (P, 2) at P output positions: per image stream its trunk's maps and the positions'
        windows in them (same order as `streams`), and the normalised poses (P, D). Only the
        positions asked for pay for the fully connected layers."""
        if len(maps) != len(self.streams) or len(windows) != len(self.streams):
            raise ValueError(f"dense GQ-CNN: {len(self.streams)} image streams, given {len(maps)} maps and "
                             f"{len(windows)} window sets")
        return self.merge([stream.features(m, *w) for stream, m, w in zip(self.streams, maps, windows, strict=True)],
                          poses)

    def merge(self, features: Sequence[torch.Tensor], poses: torch.Tensor,
              shared: Sequence[torch.Tensor | None] | None = None) -> torch.Tensor:
        """Logits (P, 2) at P positions from each image stream's `DenseStream.features` and their
        normalised poses (P, D): the network's pose stream and merge layers.

        `shared`, per stream, maps positions to rows of its features ((P,) long; None: one row per
        position): positions that share a window share its features, computed once. The merge's
        first layer is linear in the concatenated features, W [f_1; f_2; f_pose] = W_1 f_1 + W_2 f_2
        + W_pose f_pose, so each stream's part is applied to its distinct windows only and gathered
        (a context window serves ~81 pixels): the same logits up to float rounding, for a fraction
        of the per-position cost."""
        shared = list(shared) if shared is not None else [None] * len(features)
        fc4, rest = self.net.merge[0], self.net.merge[1:]
        pose = self.net.pose_stream(poses)
        widths = [f.shape[1] for f in features] + [pose.shape[1]]
        weights = torch.split(fc4.weight, widths, dim=1)
        total = F.linear(pose, weights[-1], fc4.bias)
        for f, w, index in zip(features, weights[:-1], shared, strict=True):
            part = F.linear(f, w)
            total = total + (part if index is None else part[index])
        return rest(total)
