"""What defines an object: its generator and parameters, plus the material it is made of."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

SETS = ("basic", "typical", "adversarial")
"""The evaluation sets, as in the paper (25 + 25 + 5 objects)."""

DEFAULT_DENSITY = 400.0
"""Effective density (kg/m^3) of household goods and 3D prints: packaged goods and hollow
containers average well below solid plastic (~1000-1200); PLA prints at 20-30 % infill come to
~300-450. Objects heavier than the mass cap are capped (see objects.build)."""


@dataclass(frozen=True)
class ObjectSpec:
    """A reproducible object: a registered generator called with fixed parameters."""

    name: str
    """Unique name within its set (lower case, digits, underscores)."""

    set: str
    """Set the object belongs to: basic, typical, adversarial, train or custom."""

    generator: str
    """Name of the shape generator in suctionbench.objects.shapes.GENERATORS."""

    params: dict[str, Any] = field(default_factory=dict)
    """Keyword parameters of the generator (metres, radians); plain numbers, lists and strings."""

    density: float = DEFAULT_DENSITY
    """Effective density (kg/m^3) giving the mass from the mesh volume."""

    friction: float = 0.5
    """Coulomb friction coefficient of the object's surface against silicone."""

    description: str = ""
    """One line saying what the object is meant to resemble or test."""
