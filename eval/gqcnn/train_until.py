"""Train a GQ-CNN one epoch at a time until a deadline: as many epochs as a lent GPU's time allows.

    python eval/gqcnn/train_until.py DATASET OUT --arch context-pose --deadline UNIX_SECONDS
        [--device cuda] [--target soft] [--average 0.9995] [--max-val-datapoints 50000]
        [--load-threads 4] [--max-epochs 100] [--seed 0]

Each round calls `suctionbench.learning.train.train` with one epoch more; the trainer resumes from
the checkpoint it wrote after the last epoch, and a resumed run ends with the weights an
uninterrupted run of that many epochs would have (the learning-rate schedule does not depend on
the epoch count), so the model card's command, `suctionbench train ... --epochs K`, reproduces it.
A round starts only if the last one's duration, with 10 % to spare, fits before the deadline. One
JSON line per epoch on stdout. Used by eval/gqcnn/gpu.sh.
"""

import argparse
import json
import time

from suctionbench.cli.train import train_command
from suctionbench.learning.train import train
from suctionbench.learning.train_config import TrainConfig


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset")
    parser.add_argument("out")
    parser.add_argument("--arch", default="context-pose")
    parser.add_argument("--deadline", type=float, required=True, help="unix time by which the last epoch must end")
    parser.add_argument("--device", default="cuda")
    parser.add_argument("--target", default="soft")
    parser.add_argument("--average", type=float, default=0.9995)
    parser.add_argument("--max-val-datapoints", type=int, default=50_000)
    parser.add_argument("--load-threads", type=int, default=4)
    parser.add_argument("--max-epochs", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    epochs, last = 0, 0.0
    while epochs < args.max_epochs and (epochs == 0 or time.time() + 1.1 * last < args.deadline):
        start, epochs = time.time(), epochs + 1
        config = TrainConfig(arch=args.arch, epochs=epochs, device=args.device, split="object_wise",
                             max_val_datapoints=args.max_val_datapoints, target=args.target,
                             average=args.average, load_threads=args.load_threads, seed=args.seed)
        metrics = train(args.dataset, args.out, config, command=train_command(args.dataset, args.out, config))
        last = time.time() - start
        keys = ("val_accuracy", "val_ap", "fit_accuracy", "fit_ap", "train_accuracy", "train_images_per_s")
        print(json.dumps({"arch": args.arch, "epoch": epochs, "seconds": round(last, 1),
                          **{k: metrics.get(k) for k in keys}}), flush=True)


if __name__ == "__main__":
    main()
