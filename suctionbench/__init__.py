"""suctionbench: robust vacuum-suction grasp labels, datasets, GQ-CNN policies and a MuJoCo benchmark.

The analytic model follows Mahler et al., "Dex-Net 3.0" (ICRA 2018); see README.md.
"""

__version__ = "0.1.0"
