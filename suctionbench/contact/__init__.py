"""The analytic suction labeller: Dex-Net 3.0's compliant suction contact model.

seal.py (spring seal formation), swing.py (the wrench the swinging bellows' lip carries; in time:
swing_path.py, the load's arrival: arrival.py), wrench.py (suction-ring wrench resistance),
press.py (the touch-down's press), robust.py (Monte-Carlo robust wrench resistance), metrics.py
(metric registry), labeller.py (entry point).
"""

from suctionbench.contact.labeller import SuctionLabeller
from suctionbench.contact.metrics import METRICS, GraspLabels
from suctionbench.contact.seal import FAILURES, SealResult

__all__ = ["FAILURES", "METRICS", "GraspLabels", "SealResult", "SuctionLabeller"]
