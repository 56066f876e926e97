"""How much of the held-out accuracy target the labels' own Monte-Carlo noise allows.

Usage: python eval/gqcnn/label_noise.py DATASET_DIR [SPLIT]
The robust label is an estimate k / J of the probability p that a perturbed grasp resists (J
samples, the dataset card's `label.perturbation.num_samples`); the held-out accuracy scores a
prediction against k / J > t (t = the card's `label_threshold`). Even a predictor that knew p
exactly (and said p > t) agrees with such a label only with probability P(k > tJ | p) or its
complement: the ceiling of any network's held-out accuracy. Printed for the split's validation
datapoints (default object_wise) with p taken as the label itself (plug-in) and drawn from its
posterior Beta(k + 1, J - k + 1) (seeded), at the card's threshold and at 0.5.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.stats import binom

from suctionbench.dataset.storage import read_card
from suctionbench.learning.data import METRIC_FIELD, SplitData, label_threshold


def main(dataset: Path, split: str) -> None:
    card = read_card(dataset)
    samples = int(card["config"]["label"]["perturbation"]["num_samples"])
    threshold = label_threshold(card)
    val = SplitData(dataset, split, "val")
    rwr = np.concatenate([val.reader.shard(shard, fields=[METRIC_FIELD])[METRIC_FIELD][val.rows(shard)]
                          for shard in val.shards])
    k = np.round(rwr * samples).astype(int)
    rng = np.random.default_rng(0)
    print(f"{dataset.name} {split}: {len(rwr)} validation datapoints, J = {samples}, "
          f"positive share {np.mean(rwr > threshold):.3f} at t = {threshold}")
    for t in (threshold, 0.5):
        above = int(np.floor(t * samples))  # label = k > above
        for name, p in (("plug-in", rwr), ("posterior", rng.beta(k + 1, samples - k + 1))):
            agree = binom.sf(above, samples, p)
            print(f"  t = {t}: ceiling {np.mean(np.where(p > t, agree, 1.0 - agree)):.4f} ({name}); "
                  f"labels within 0.1 of t: {np.mean(np.abs(rwr - t) <= 0.1):.3f}")


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    main(Path(sys.argv[1]), sys.argv[2] if len(sys.argv) == 3 else "object_wise")
