"""Record in model cards the objects the models never trained on, for models trained before `train`
wrote them (`dataset.held_out_objects`): read from the dataset whose object-wise split held them out.

    python eval/gqcnn/record_held_out.py DATASET MODEL [MODEL ...]

DATASET is the one the models' held-out objects came from: their own training dataset (the card's
`dataset.fingerprint`) or the one it held out like (`generate --holdout-like`), regenerated if need
be (generation is deterministic: the fingerprint and the object-wise split come back the same).
With the keys in the card, `generate --holdout-like MODEL` holds out the same objects in new data
without the GB-sized dataset. Only the card's JSON changes (the weights and their hash do not); a
card that already lists other objects is refused.
"""

from __future__ import annotations

import sys
from pathlib import Path

from suctionbench.dataset.storage import held_out_keys, read_card
from suctionbench.learning.checkpoint import read_model_card, write_model_card


def record(dataset: Path, models: list[Path]) -> None:
    keys = held_out_keys(dataset)
    fingerprint = read_card(dataset).get("fingerprint")
    for model in models:
        card = read_model_card(model)
        data = card.get("dataset")
        if not isinstance(data, dict) or data.get("split") != "object_wise":
            sys.exit(f"model '{model}': not trained on an object-wise split; it held out no objects")
        if data.get("held_out_objects") not in (None, keys):
            sys.exit(f"model '{model}': its card already lists other held-out objects")
        data["held_out_objects"] = keys
        data.setdefault("held_out_from", fingerprint)  # the dataset the keys were read from
        write_model_card(model, card)
        print(f"{model}: {len(keys)} held-out objects (dataset {fingerprint}; its own {data.get('fingerprint')})")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    record(Path(sys.argv[1]), [Path(m) for m in sys.argv[2:]])
