"""The dense GQ-CNN (learning/dense.py) is the thumbnail network, evaluated at every position."""

import pytest
import torch

from suctionbench.errors import InputError
from suctionbench.learning.dense import DenseGQCNN
from suctionbench.learning.models import IMAGE_SIZE, build_model


def test_dense_equals_thumbnail_network_at_every_position():
    # The "a trous" identity (module doc): stride-1 pools and dilated later layers compute, for the
    # window at each position, exactly what the stride-2 network computes on that window alone;
    # checked at every position of two images of one batch (the head gathers across the batch).
    gen = torch.Generator().manual_seed(3)
    net = build_model("compact", gen).eval()
    dense = DenseGQCNN(net).eval()
    images = torch.randn(2, 1, 41, 47, generator=gen)
    rows, cols = 41 - IMAGE_SIZE + 1, 47 - IMAGE_SIZE + 1
    batch, r, c = (t.reshape(-1) for t in torch.meshgrid(torch.arange(2), torch.arange(rows), torch.arange(cols),
                                                          indexing="ij"))
    poses = torch.randn(len(batch), 2, generator=gen)
    with torch.no_grad():
        got = dense.head(dense.trunk(images), batch, r, c, poses)
        windows = torch.stack([images[b, :, i:i + IMAGE_SIZE, j:j + IMAGE_SIZE]
                               for b, i, j in zip(batch.tolist(), r.tolist(), c.tolist(), strict=True)])
        want = net(windows, poses)
    assert got.shape == want.shape == (2 * rows * cols, 2)
    torch.testing.assert_close(got, want, rtol=1e-5, atol=1e-5)


@pytest.mark.parametrize("arch", ["dn3", "context"])
def test_networks_that_do_not_convert_exactly_are_refused(arch):
    with pytest.raises(InputError, match="dense GQ-CNN"):
        DenseGQCNN(build_model(arch, torch.Generator().manual_seed(0)))
