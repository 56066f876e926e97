"""The analytic suction labeller: Dex-Net 3.0's compliant suction contact model.

seal.py (spring seal formation), wrench.py (suction-ring wrench resistance), robust.py
(Monte-Carlo robust wrench resistance), metrics.py (metric registry), labeller.py (entry point).
"""

from suctionbench.contact.labeller import SuctionLabeller
from suctionbench.contact.metrics import METRICS, GraspLabels
from suctionbench.contact.seal import FAILURES, SealResult

__all__ = ["FAILURES", "METRICS", "GraspLabels", "SealResult", "SuctionLabeller"]
