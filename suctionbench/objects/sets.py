"""The evaluation sets: Basic (here), Typical (household.py), Adversarial (adversarial.py).

Basic follows the paper: prismatic solids - boxes of many aspect ratios, cylinders, prisms and
tubes - at household sizes (2-25 cm). Specs are explicit, so names and shapes never drift.
"""

from __future__ import annotations

from suctionbench.objects.spec import ObjectSpec


def _basic(name: str, generator: str, description: str, **params) -> ObjectSpec:
    return ObjectSpec(name=name, set="basic", generator=generator, params=params, description=description)


BASIC_SPECS: list[ObjectSpec] = [
    _basic("box_cereal", "box", "cereal box, tall and thin", extents=[0.19, 0.06, 0.25]),
    _basic("box_shoe", "box", "shoe box", extents=[0.22, 0.14, 0.10]),
    _basic("box_tea", "box", "tea box", extents=[0.14, 0.07, 0.07]),
    _basic("box_matchbox", "box", "matchbox, small", extents=[0.05, 0.035, 0.015]),
    _basic("box_book", "box", "paperback book, flat", extents=[0.18, 0.11, 0.025]),
    _basic("box_cube_small", "box", "small cube", extents=[0.04, 0.04, 0.04]),
    _basic("box_cube", "box", "cube", extents=[0.08, 0.08, 0.08]),
    _basic("box_stick", "box", "long square stick", extents=[0.20, 0.025, 0.025]),
    _basic("box_plank", "box", "wide flat plank", extents=[0.24, 0.08, 0.015]),
    _basic("box_brick", "box", "toy brick", extents=[0.10, 0.05, 0.03]),
    _basic("cylinder_can", "cylinder", "soda can", radius=0.033, height=0.12),
    _basic("cylinder_tuna", "cylinder", "tuna can, squat", radius=0.043, height=0.04),
    _basic("cylinder_jar", "cylinder", "jar", radius=0.045, height=0.10),
    _basic("cylinder_dowel", "cylinder", "thick dowel", radius=0.015, height=0.20),
    _basic("cylinder_puck", "cylinder", "hockey puck", radius=0.038, height=0.025),
    _basic("cylinder_battery", "cylinder", "D-cell battery", radius=0.017, height=0.06),
    _basic("prism_tri_toblerone", "prism", "triangular prism, chocolate-bar style", sides=3, radius=0.025, height=0.20),
    _basic("prism_tri_wedge", "prism", "short triangular prism", sides=3, radius=0.045, height=0.05),
    _basic("prism_hex_nut", "prism", "hexagonal prism, large nut blank", sides=6, radius=0.03, height=0.025),
    _basic("prism_hex_pencil", "prism", "hexagonal prism, jumbo pencil", sides=6, radius=0.012, height=0.18),
    _basic("prism_pent", "prism", "pentagonal prism", sides=5, radius=0.04, height=0.08),
    _basic("prism_oct", "prism", "octagonal prism", sides=8, radius=0.035, height=0.12),
    _basic("tube_pipe", "tube", "pipe section", outer_radius=0.025, inner_radius=0.02, height=0.15),
    _basic("tube_roll", "tube", "paper towel core", outer_radius=0.022, inner_radius=0.019, height=0.22),
    _basic("tube_ring", "tube", "wide short ring", outer_radius=0.045, inner_radius=0.035, height=0.03),
]
"""The 25 Basic objects."""
