"""GQ-CNN learning: the Dex-Net 3.0 and compact networks, streaming data with augmentation, training, checkpoints.

Entry points: `suctionbench.learning.train.train` (with `suctionbench.learning.train_config.TrainConfig`),
`suctionbench.learning.checkpoint.load_model` (a trained model's ``predict``),
`suctionbench.learning.models.build_model`. The modules import torch, so import them where needed rather
than from here.
"""
