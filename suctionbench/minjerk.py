"""Minimum-jerk time scaling: the profile of every move the pick episode makes and the labeller
assumes (Flash & Hogan 1985). A move of length L over time T covers L s(t / T).

    s(u) = 10 u^3 - 15 u^4 + 6 u^5,  s'(u) = 30 u^2 (1 - u)^2,  s''(u) = 60 u - 180 u^2 + 120 u^3
"""

from __future__ import annotations

import math

import numpy as np

PEAK_ACCELERATION = 10.0 / math.sqrt(3.0)
"""Peak of s''(u): at u = (3 - sqrt 3) / 6, s'' = 10 / sqrt 3 = 5.774 (a move of L in T peaks at
5.774 L / T^2)."""


def position(u: np.ndarray | float) -> np.ndarray | float:
    """s(u): the share of the move covered at the time fraction u in [0, 1]."""
    return 10 * u**3 - 15 * u**4 + 6 * u**5


def speed(u: np.ndarray | float) -> np.ndarray | float:
    """s'(u): the speed in units of L / T (0 at both ends, 1.875 at u = 1/2)."""
    return 30.0 * u * u * (1.0 - u) ** 2


def acceleration(u: np.ndarray | float) -> np.ndarray | float:
    """s''(u): the acceleration in units of L / T^2 (0 at both ends)."""
    return u * (60.0 - 180.0 * u + 120.0 * u * u)


def progress(share: np.ndarray) -> np.ndarray:
    """The time fraction u at which s(u) = `share` (clipped to [0, 1]), by bisection: s is monotone."""
    target = np.clip(np.asarray(share, dtype=float), 0.0, 1.0)
    low, high = np.zeros_like(target), np.ones_like(target)
    for _ in range(40):
        mid = 0.5 * (low + high)
        below = position(mid) < target
        low, high = np.where(below, mid, low), np.where(below, high, mid)
    return 0.5 * (low + high)
