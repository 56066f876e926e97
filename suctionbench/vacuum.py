"""Vacuum under a leaking cup: the ejector's flow curve against the leak's orifice flow.

Both the labeller and the simulated cup ask the same physical question - given a leak area A under
the lip, what vacuum p does the ejector hold? - and answer it with this law; each measures its own
leak area. The ejector's curve is linear between its blocked-flow vacuum p_max and its free-air
flow Q_max: Q_e(p) = Q_max (1 - p / p_max). A leak is a sharp-edged orifice, Q_l(p) = C_d A
sqrt(2 p / rho) (incompressible: it overstates the flow by up to ~15 % near 60 kPa, where real
flow starts to choke, so leaks are judged slightly pessimistically). The equilibrium Q_e = Q_l is a
quadratic in s = sqrt(p): (Q_max / p_max) s^2 + beta s - Q_max = 0, beta = C_d A sqrt(2 / rho).

Example (default cup): two 2 x 4 mm channels, A = 16 mm^2, leak ~170 l/min at 50 kPa; the 16 l/min
ejector then holds only ~0.3 kPa, so no seal. 1 mm^2 of leak halves the vacuum.
"""

from __future__ import annotations

import numpy as np

from suctionbench.config import CupConfig

AIR_DENSITY = 1.204
"""Density of air at 20 C and 1 atm (kg/m^3)."""


def equilibrium_vacuum(leak_area: np.ndarray | float, cup: CupConfig) -> np.ndarray:
    """Vacuum (Pa) the ejector holds against a leak of area `leak_area` (m^2); p_max at zero leak."""
    area = np.maximum(np.asarray(leak_area, dtype=float), 0.0)
    q_max, p_max = cup.ejector_flow, cup.vacuum_pressure
    a = q_max / p_max
    beta = cup.discharge_coefficient * area * np.sqrt(2.0 / AIR_DENSITY)
    s = (-beta + np.sqrt(beta * beta + 4.0 * a * q_max)) / (2.0 * a)
    return np.minimum(s * s, p_max)


def leak_area_at_pressure(pressure: np.ndarray | float, cup: CupConfig) -> np.ndarray:
    """Leak area (m^2) at which the equilibrium vacuum is `pressure` (Pa): the inverse of
    `equilibrium_vacuum` on (0, p_max]."""
    p = np.asarray(pressure, dtype=float)
    flow = cup.ejector_flow * (1.0 - p / cup.vacuum_pressure)
    return flow / (cup.discharge_coefficient * np.sqrt(2.0 * p / AIR_DENSITY))


def vacuum_force(leak_area: np.ndarray | float, cup: CupConfig) -> np.ndarray:
    """Suction force (N) on the object: equilibrium vacuum x the cup's effective area (the preset's
    override scaled by the same vacuum fraction)."""
    return equilibrium_vacuum(leak_area, cup) / cup.vacuum_pressure * cup.vacuum_force
