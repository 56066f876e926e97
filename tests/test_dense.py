"""The dense GQ-CNN (learning/dense.py) is the thumbnail network, evaluated at every position."""

import pytest
import torch

from suctionbench.errors import InputError
from suctionbench.learning.dense import DenseGQCNN, output_size
from suctionbench.learning.models import IMAGE_SIZE, build_model


def _windows(image: torch.Tensor, poses: torch.Tensor):
    """Every 32 x 32 window of image (1, 1, H, W) and its pose, as the thumbnail network's batch."""
    rows, cols = poses.shape[-2:]
    windows = torch.stack([image[0, :, i:i + IMAGE_SIZE, j:j + IMAGE_SIZE] for i in range(rows) for j in range(cols)])
    return windows, poses[0].permute(1, 2, 0).reshape(-1, 2)


def test_dense_equals_thumbnail_network_at_every_position():
    # The "a trous" identity (module doc): stride-1 pools and dilated later layers compute, for the
    # window at each position, exactly what the stride-2 network computes on that window alone.
    gen = torch.Generator().manual_seed(3)
    net = build_model("compact", gen).eval()
    dense = DenseGQCNN(net).eval()
    image = torch.randn(1, 1, 41, 47, generator=gen)
    rows, cols = output_size(41, 47)
    poses = torch.randn(1, 2, rows, cols, generator=gen)
    with torch.no_grad():
        got = dense(image, poses)[0].permute(1, 2, 0).reshape(-1, 2)
        want = net(*_windows(image, poses))
    assert got.shape == want.shape == (rows * cols, 2)
    torch.testing.assert_close(got, want, rtol=1e-5, atol=1e-5)


def test_head_at_chosen_positions_equals_the_dense_map():
    gen = torch.Generator().manual_seed(4)
    dense = DenseGQCNN(build_model("compact", gen)).eval()
    image = torch.randn(3, 1, 40, 36, generator=gen)
    rows, cols = output_size(40, 36)
    poses = torch.randn(3, 2, rows, cols, generator=gen)
    batch, r, c = torch.tensor([0, 2, 1, 2]), torch.tensor([0, rows - 1, 4, 3]), torch.tensor([cols - 1, 0, 2, 3])
    with torch.no_grad():
        full = dense(image, poses)
        picked = dense.head(dense.trunk(image), batch, r, c, poses[batch, :, r, c])
    torch.testing.assert_close(picked, full[batch, :, r, c], rtol=1e-5, atol=1e-5)


@pytest.mark.parametrize("arch", ["dn3", "context"])
def test_networks_that_do_not_convert_exactly_are_refused(arch):
    with pytest.raises(InputError, match="dense GQ-CNN"):
        DenseGQCNN(build_model(arch, torch.Generator().manual_seed(0)))
