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
        got = dense.head([dense.streams[0].trunk(images)], [(batch, r, c)], poses)
        windows = torch.stack([images[b, :, i:i + IMAGE_SIZE, j:j + IMAGE_SIZE]
                               for b, i, j in zip(batch.tolist(), r.tolist(), c.tolist(), strict=True)])
        want = net(windows, poses)
    assert got.shape == want.shape == (2 * rows * cols, 2)
    torch.testing.assert_close(got, want, rtol=1e-5, atol=1e-5)


@pytest.mark.parametrize("stride", [2, 4])
def test_strided_trunk_equals_thumbnail_network_at_its_windows(stride):
    # trunk(stride=s): the first log2(s) pools keep their stride 2, so the maps hold only the windows
    # whose top-left corner is a multiple of s (a window at an even position pools the same 2 x 2
    # blocks as the whole image's stride-2 pool), at map position (i / s, j / s); each must still be
    # the thumbnail network's output on that window alone (compact has two pools: s up to 4).
    gen = torch.Generator().manual_seed(5)
    net = build_model("compact", gen).eval()
    stream = DenseGQCNN(net).streams[0]
    assert stream.max_stride == 4
    images = torch.randn(2, 1, 45, 50, generator=gen)
    rows, cols = range(0, 45 - IMAGE_SIZE + 1, stride), range(0, 50 - IMAGE_SIZE + 1, stride)
    batch, r, c = (t.reshape(-1) for t in torch.meshgrid(torch.arange(2), torch.tensor(rows), torch.tensor(cols),
                                                          indexing="ij"))
    with torch.no_grad():
        got = stream.features(stream.trunk(images, stride), batch, r // stride, c // stride, stride)
        windows = torch.stack([images[b, :, i:i + IMAGE_SIZE, j:j + IMAGE_SIZE]
                               for b, i, j in zip(batch.tolist(), r.tolist(), c.tolist(), strict=True)])
        want = net.image_stream(windows)
    assert got.shape == want.shape == (2 * len(rows) * len(cols), net.image_stream[-2].out_features)
    torch.testing.assert_close(got, want, rtol=1e-5, atol=1e-5)
    with pytest.raises(ValueError, match="stride 8 is not a power of 2 up to 4"):
        stream.trunk(images, 8)


def test_dense_context_net_equals_two_stream_network():
    # A context net's two streams each run densely over their own image (the context lattice is
    # coarser, so its maps have another size) and each position reads its own window in each; the
    # head must give the two-stream network's logits on the (grasp, context) window pair.
    gen = torch.Generator().manual_seed(4)
    net = build_model("context", gen).eval()
    dense = DenseGQCNN(net).eval()
    assert len(dense.streams) == 2
    grasp, context = torch.randn(1, 1, 40, 44, generator=gen), torch.randn(1, 1, 35, 37, generator=gen)
    count = 50
    gr = torch.randint(0, 40 - IMAGE_SIZE + 1, (count,), generator=gen)
    gc = torch.randint(0, 44 - IMAGE_SIZE + 1, (count,), generator=gen)
    cr = torch.randint(0, 35 - IMAGE_SIZE + 1, (count,), generator=gen)
    cc = torch.randint(0, 37 - IMAGE_SIZE + 1, (count,), generator=gen)
    zero = torch.zeros(count, dtype=torch.long)
    poses = torch.randn(count, 2, generator=gen)
    with torch.no_grad():
        got = dense.head([dense.streams[0].trunk(grasp), dense.streams[1].trunk(context)],
                         [(zero, gr, gc), (zero, cr, cc)], poses)
        pairs = torch.stack([torch.cat([grasp[0, :, a:a + IMAGE_SIZE, b:b + IMAGE_SIZE],
                                        context[0, :, c:c + IMAGE_SIZE, d:d + IMAGE_SIZE]])
                             for a, b, c, d in zip(gr.tolist(), gc.tolist(), cr.tolist(), cc.tolist(), strict=True)])
        want = net(pairs, poses)
    torch.testing.assert_close(got, want, rtol=1e-5, atol=1e-5)
    # shared windows: each stream's distinct windows once, positions mapped to them; the merge's
    # first layer split by stream (linear, so W [f1; f2; fp] = W1 f1 + W2 f2 + Wp fp) gives the
    # same logits as the features repeated per position
    with torch.no_grad():
        f1 = dense.streams[0].features(dense.streams[0].trunk(grasp), zero[:5], gr[:5], gc[:5])
        f2 = dense.streams[1].features(dense.streams[1].trunk(context), zero[:2], cr[:2], cc[:2])
        i1, i2 = torch.randint(0, 5, (count,), generator=gen), torch.randint(0, 2, (count,), generator=gen)
        torch.testing.assert_close(dense.merge([f1, f2], poses, [i1, i2]), dense.merge([f1[i1], f2[i2]], poses),
                                   rtol=1e-5, atol=1e-5)
        torch.testing.assert_close(dense.merge([f1[i1], f2[i2]], poses),
                                   net.merge(torch.cat([f1[i1], f2[i2], net.pose_stream(poses)], dim=1)),
                                   rtol=1e-5, atol=1e-5)
    with pytest.raises(ValueError, match="2 image streams"):
        dense.head([dense.streams[0].trunk(grasp)], [(zero, gr, gc)], poses)


def test_same_padded_network_is_refused():
    # dn3's SAME padding reads zeros at a thumbnail's border where the whole image has neighbours.
    with pytest.raises(InputError, match="dense GQ-CNN: only VALID"):
        DenseGQCNN(build_model("dn3", torch.Generator().manual_seed(0)))


@pytest.mark.parametrize("dilation", [1, 2])
@pytest.mark.parametrize("size", [(23, 30), (24, 27)])
def test_conv_then_pool_as_four_strided_convolutions(dilation, size):
    # pool(conv(x)) at (p, q) is the max over the conv at (2p + i, 2q + j), i.e. over the four
    # stride-2 convolutions of x shifted by (i, j): the same sums, so the same values exactly.
    from suctionbench.learning.dense import _conv_pooled
    from suctionbench.learning.models import max_pool_2x2

    generator = torch.Generator().manual_seed(4)
    conv = torch.nn.Conv2d(3, 5, 3)
    x = torch.randn(2, 3, *size, generator=generator)
    with torch.no_grad():
        want = max_pool_2x2(torch.nn.functional.conv2d(x, conv.weight, conv.bias, dilation=dilation))
        got = _conv_pooled(x, conv, dilation)
    assert got.shape == want.shape and torch.equal(got, want)
