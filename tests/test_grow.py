"""Growing a trained GQ-CNN into a wider one (Net2WiderNet): the function is kept, the copies differ."""

from __future__ import annotations

import numpy as np
import torch

from suctionbench.learning.grow import grow, growth_problem
from suctionbench.learning.models import build_model, count_macs, count_parameters


def _inputs(arch_pose_dim: int, n: int = 64) -> tuple[torch.Tensor, torch.Tensor]:
    generator = torch.Generator().manual_seed(5)
    return torch.randn(n, 2, 32, 32, generator=generator), torch.randn(n, arch_pose_dim, generator=generator)


def test_the_larger_layouts_have_the_sizes_derived_in_the_module_doc():
    # context-pose-wide-fc, per image stream: conv1 5*5*1*32 + 32 = 832, conv2 and conv3
    # 3*3*32*32 + 32 = 9,248 each, fc3 (5*5*32) * 512 + 512 = 410,112 -> 429,440, two streams
    # 858,880; pose 8*128 + 128 = 1,152; fc4 (512 + 512 + 128) * 512 + 512 = 590,336; fc5 512*2 + 2
    # = 1,026. Total 1,451,394.
    assert count_parameters(build_model("context-pose-wide-fc")) == 858_880 + 1_152 + 590_336 + 1_026 == 1_451_394
    # context-pose-wider: conv1 25*64 + 64 = 1,664, conv2/3 9*64*64 + 64 = 36,928, fc3 (5*5*64) * 256
    # + 256 = 409,856 -> 485,376 a stream, 970,752 both; pose 8*64 + 64 = 576; fc4 (256 + 256 + 64)
    # * 256 + 256 = 147,712; fc5 514. Total 1,119,554.
    assert count_parameters(build_model("context-pose-wider")) == 970_752 + 576 + 147_712 + 514 == 1_119_554
    # Multiply-adds: the convolutions dominate and scale with filters squared (conv2/3), so the fc
    # widening adds little (fc3 800 x 128 -> 800 x 512: +0.3 M a stream; the merge 288 x 128 ->
    # 1,152 x 512: +0.55 M) while doubling the filters takes the convolutions' 5.75 M to 20.5 M
    # (conv2 and conv3 4x, conv1 2x): 3.6x in all.
    wide = count_macs(build_model("context-pose-wide"))
    assert count_macs(build_model("context-pose-wide-fc")) < 1.25 * wide
    assert 3 * wide < count_macs(build_model("context-pose-wider")) < 4 * wide


def test_a_grown_net_computes_what_its_parent_computes():
    # Each new unit copies a unit's incoming weights and bias, so it outputs the same activation;
    # the next layer's weights on the copies are shares summing to the original's weight, so the
    # next layer's pre-activation is unchanged; by induction the logits are. Exact up to float32
    # rounding of the re-associated sums (~1e-6 of logits of size ~10).
    for parent, child in (("context-pose", "context-pose-wide"), ("context-pose-wide", "context-pose-wide-fc"),
                          ("context-pose-wide", "context-pose-wider"), ("compact", "compact")):
        base = build_model(parent, torch.Generator().manual_seed(1)).eval()
        target = build_model(child, torch.Generator().manual_seed(2)).eval()
        assert growth_problem(base, target) is None
        grow(base, target, np.random.default_rng(0))
        images, poses = _inputs(base.pose_dim)
        images = images[:, :base.image_channels]
        with torch.no_grad():
            expected, got = base(images, poses), target(images, poses)
        assert torch.allclose(got, expected, atol=1e-4, rtol=1e-4), (parent, child)


def test_the_copies_share_their_outgoing_weight_unequally():
    # Equal shares would give the two copies equal gradients forever (the same activation times
    # the same outgoing weight); unequal positive shares keep the sum and break the symmetry.
    base = build_model("context-pose", torch.Generator().manual_seed(1))
    target = build_model("context-pose-wide")
    grow(base, target, np.random.default_rng(0))
    fc5_old, fc5_new = base.merge.fc5.weight, target.merge.fc5.weight  # reads fc4's 64 -> 128 units
    # fc4's first 64 units are the originals; each of the other 64 copies one of them exactly once
    copies = [int(np.flatnonzero((target.merge.fc4.weight[64:] == target.merge.fc4.weight[j]).all(dim=1))[0])
              for j in range(64)]
    assert sorted(copies) == list(range(64))
    for original, copy in enumerate(copies):
        shares = torch.stack([fc5_new[:, original], fc5_new[:, 64 + copy]])
        assert torch.allclose(shares.sum(0), fc5_old[:, original], atol=1e-6)
        assert not torch.allclose(shares[0], shares[1])
        assert (shares[0] * fc5_old[:, original] > 0).all()  # positive shares keep the sign


def test_what_cannot_grow_is_named():
    wide, wider = build_model("context-pose-wide"), build_model("context-pose-wider")
    assert growth_problem(wider, wide) == "layer image_stream.conv1.0 is narrower (32 < 64)"
    assert growth_problem(build_model("context-wide"), wide) == "the inputs differ"  # 2 vs 8 pose inputs
    assert growth_problem(build_model("compact"), wide) == "the layers differ"  # no context stream
    assert "local response normalisation" in growth_problem(build_model("dn3"), build_model("dn3"))
