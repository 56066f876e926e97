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
kernel with taps 2 apart, at the window's position). The fully connected layer becomes an s x s
convolution with that dilation (its weights reshaped: torch flattens (C, H, W) row-major), and the
pose stream and the merge layers become 1 x 1 convolutions over a pose map (one pose per
position). Output (B, 2, H - 31, W - 31) logits for an input (B, 1, H, W): position (i, j) is the
32 x 32 window whose top-left pixel is (i, j), i.e. the thumbnail centred on (i + 15.5, j + 15.5).

Cost. No pooling shrinks the maps, so every layer runs at the input's resolution: for compact,
400 + 2 x 2,304 + 25,600 + merge ~ 31 k multiply-accumulates per position, where a thumbnail
costs 0.91 M: ~30x less per grasp, when all positions are wanted. Most positions of a scene are
not wanted (off the object, or scored at another rotation of the image), so the pass splits in
two: `trunk` (the convolutions, 5 k per position, over the whole image) and `head` (the fully
connected layer, 26 k, gathered at the positions asked for, and the merge).

Not converted: SAME padding (`dn3`: its padded zeros inside a thumbnail are neighbouring pixels
in the whole image, so the values would differ near every thumbnail's border) and the context
stream (its thumbnail samples a 3x coarser, box-filtered image: a second dense stream on that
image, resampled onto the first's grid).
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import nn

from suctionbench.errors import InputError
from suctionbench.learning.models import GQCNN, IMAGE_SIZE


class DenseGQCNN(nn.Module):
    """The fully convolutional form of a VALID-padded, one-image-stream `GQCNN` (module doc)."""

    def __init__(self, net: GQCNN):
        super().__init__()
        if net.context_stream is not None:
            raise InputError("dense GQ-CNN: a context network (two image streams) cannot be converted yet")
        self.layers: list[tuple[str, nn.Module, int]] = []
        """(kind, module, dilation) of the image stream, in order: conv, relu, lrn, pool, fc."""
        dilation = 1
        for block in net.image_stream:
            if isinstance(block, nn.Sequential):  # a conv block: conv -> ReLU [-> LRN] [-> pool]
                for module in block:
                    if isinstance(module, nn.Conv2d):
                        if module.padding not in ((0, 0), "valid"):
                            raise InputError("dense GQ-CNN: only VALID-padded networks convert exactly (not dn3)")
                        self.layers.append(("conv", module, dilation))
                    elif isinstance(module, nn.MaxPool2d):
                        self.layers.append(("pool", module, dilation))
                        dilation *= 2
                    else:
                        self.layers.append(("pointwise", module, dilation))
            elif isinstance(block, nn.Linear):  # fc3 over the last C x s x s map
                channels = self.layers_channels()
                side = round((block.in_features / channels) ** 0.5)
                fc = nn.Conv2d(channels, block.out_features, side, dilation=dilation)
                fc.weight.data = block.weight.data.reshape(block.out_features, channels, side, side).clone()
                fc.bias.data = block.bias.data.clone()
                self.layers.append(("fc", fc, dilation))
            elif isinstance(block, nn.ReLU):
                self.layers.append(("pointwise", block, dilation))
        self.stream = nn.ModuleList([module for _, module, _ in self.layers])
        self.fc, self.fc_dilation = next((m, d) for kind, m, d in self.layers if kind == "fc")
        self.fc_matrix = self.fc.weight.detach().reshape(self.fc.out_channels, -1)
        self.pose = _pointwise(net.pose_stream.pc1)
        self.merge_hidden = _pointwise(net.merge.fc4)
        self.merge_out = _pointwise(net.merge.fc5)

    def layers_channels(self) -> int:
        """Output channels of the last convolution so far."""
        convs = [module for kind, module, _ in self.layers if kind == "conv"]
        return convs[-1].out_channels

    def trunk(self, image: torch.Tensor) -> torch.Tensor:
        """The image stream's maps before its fully connected layer, (B, C, h, w), for a normalised
        image (B, 1, H, W): the cheap part, shared by every position."""
        x = image
        for kind, module, dilation in self.layers:
            if kind == "fc":
                break
            if kind == "conv":
                x = F.conv2d(x, module.weight, module.bias, dilation=dilation)
            elif kind == "pool":
                x = F.max_pool2d(x, 2, stride=1, dilation=dilation)
            else:
                x = module(x)
        return x

    def head(self, maps: torch.Tensor, batch: torch.Tensor, rows: torch.Tensor, cols: torch.Tensor,
             poses: torch.Tensor) -> torch.Tensor:
        """Logits (P, 2) at P output positions (image `batch`, `rows`, `cols`; (P,) long) of the
        trunk's `maps`, with normalised poses (P, 2): the fully connected layer's taps gathered
        where the dense form would read them (s x s, the final dilation apart), so only the
        positions asked for pay for it."""
        fc, dilation = self.fc, self.fc_dilation
        side = fc.kernel_size[0]
        taps = dilation * torch.arange(side, device=maps.device)
        r = rows[:, None, None] + taps[None, :, None]
        c = cols[:, None, None] + taps[None, None, :]
        windows = maps[batch[:, None, None], :, r, c]  # (P, s, s, C)
        features = torch.relu(windows.permute(0, 3, 1, 2).reshape(len(rows), -1) @ self.fc_matrix.T + fc.bias)
        hidden = torch.cat([features, torch.relu(poses @ self.pose.weight[:, :, 0, 0].T + self.pose.bias)], dim=1)
        hidden = torch.relu(hidden @ self.merge_hidden.weight[:, :, 0, 0].T + self.merge_hidden.bias)
        return hidden @ self.merge_out.weight[:, :, 0, 0].T + self.merge_out.bias

    def forward(self, image: torch.Tensor, poses: torch.Tensor) -> torch.Tensor:
        """Logits (B, 2, H - 31, W - 31) for a normalised image (B, 1, H, W) and normalised poses
        (B, 2, H - 31, W - 31), one per output position (the thumbnail centred there)."""
        x = F.conv2d(self.trunk(image), self.fc.weight, self.fc.bias, dilation=self.fc_dilation)
        merged = torch.relu(self.merge_hidden(torch.cat([torch.relu(x), torch.relu(self.pose(poses))], dim=1)))
        return self.merge_out(merged)


def _pointwise(linear: nn.Linear) -> nn.Conv2d:
    """A fully connected layer as the 1 x 1 convolution that applies it at every position."""
    conv = nn.Conv2d(linear.in_features, linear.out_features, 1)
    conv.weight.data = linear.weight.data[:, :, None, None].clone()
    conv.bias.data = linear.bias.data.clone()
    return conv


def output_size(height: int, width: int) -> tuple[int, int]:
    """Positions (rows, columns) a dense pass over an image of height x width scores."""
    return height - IMAGE_SIZE + 1, width - IMAGE_SIZE + 1
