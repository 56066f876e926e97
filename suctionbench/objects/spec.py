"""What defines an object: its generator and parameters, plus the material it is made of."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from suctionbench.objects.mass import MassModel, printed

SETS = ("basic", "typical", "adversarial")
"""The evaluation sets, as in the paper (25 + 25 + 5 objects)."""

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

    density: float | None = None
    """Uniform density (kg/m^3) giving the mass from the mesh volume, where no `mass` model is given."""

    mass: MassModel | None = None
    """What the object weighs and why (objects.mass): a real item's contents and packaging, a named
    material, a print. Without it (and without `density`) an object is taken as a PLA print."""

    friction: float = 0.5
    """Coulomb friction coefficient of the object's surface against silicone."""

    description: str = ""
    """One line saying what the object is meant to resemble or test."""

    def mass_model(self) -> MassModel:
        """The object's mass model: `mass`, else a uniform solid of `density`, else a PLA print."""
        if self.mass is not None:
            return self.mass
        if self.density is not None:
            return MassModel(f"uniform density {self.density:g} kg/m^3 (given)", density=self.density)
        return printed()
