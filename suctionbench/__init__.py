"""suctionbench: robust vacuum-suction grasp labels, datasets, GQ-CNN policies and a MuJoCo benchmark.

The analytic model follows Mahler et al., "Dex-Net 3.0" (ICRA 2018); see README.md.
"""

import os

# Headless rendering by default (servers, CI); must be set before mujoco is first imported.
# An explicit MUJOCO_GL (e.g. glfw on a desktop) is respected.
os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"
from suctionbench import envs as _envs  # noqa: E402, F401  (registers the gymnasium environments; imports only gymnasium)
