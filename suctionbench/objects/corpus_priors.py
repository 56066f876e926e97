"""What a training-corpus object weighs and how large it is: the corpus' mass and size priors.

The corpus (`objects.corpus`) draws shapes; these choose, per shape, what it is made of
(`--masses`: each shape's own material, or the training mass prior) and its scale (`--sizes`:
each family's own range, or real items' sizes). Both are drawn from their own random streams, so
changing them leaves every shape's parameters as they were.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np
import trimesh

from suctionbench.errors import InputError
from suctionbench.objects.mass import MassModel, material, printed, shell_of, solid
from suctionbench.objects.shapes import generator, make_shape

ITEM_SIZES = (0.04, 0.245)
"""Largest extent (m) of a generic corpus shape under `--sizes items`, drawn log-uniformly: the
span of the household goods a 15 mm cup picks, from a matchbox or a D cell (4-6 cm) to a cereal
box or a shoe box (22-25 cm; the upper end stays inside SIZE_RANGE after rounding). The families'
own ranges ("family") centre on 8-9 cm (blobs 5.6 cm): half the corpus' largest extents lie below
9.0 cm (a tin of tuna's is 8.6 cm), while real items, such as the evaluation sets' (4-25 cm, median
12-13 cm), are larger."""

SIZE_MODES = ("family", "items")
"""`objects generate --sizes`: each family's own size range (the shipped corpus), or the generic
families scaled to ITEM_SIZES (household kinds keep their real sizes either way)."""


def check_size_mode(sizes: str) -> None:
    """InputError naming `--sizes` unless it is one of SIZE_MODES."""
    if sizes not in SIZE_MODES:
        raise InputError(f"--sizes '{sizes}': one of {', '.join(SIZE_MODES)}")


@generator("scaled")
def scaled(generator: str, params: dict[str, Any], factor: float) -> trimesh.Trimesh:
    """Another generator's shape scaled uniformly by `factor` (the corpus' size prior)."""
    mesh = make_shape(generator, params)  # a new mesh every call
    mesh.apply_scale(factor)
    return mesh


def corpus_mass(generator_name: str) -> MassModel:
    """What a corpus object is made of: a household kind its kind's material (objects.typical.
    HOUSEHOLD_MASS: porcelain mugs, steel wrenches, empty plastic bottles ...), every other shape a
    PLA print (objects.mass.printed). Both fall back to lighter prints (lower infill) where they
    would weigh more than the cup's mass cap, so corpus masses obey the evaluation sets' cap."""
    from suctionbench.objects.typical import HOUSEHOLD_MASS

    return HOUSEHOLD_MASS.get(generator_name) or printed()


def prior_mass(generator_name: str, rng: np.random.Generator) -> MassModel:
    """What a corpus object is made of under the training mass prior: a household kind its kind's
    material (as `corpus_mass`), every other shape one of TRAINING_MAKES drawn with equal
    probability (falling back to a lighter print where it would exceed the cap)."""
    from suctionbench.objects.typical import HOUSEHOLD_MASS

    if generator_name in HOUSEHOLD_MASS:
        return HOUSEHOLD_MASS[generator_name]
    return TRAINING_MAKES[int(rng.integers(len(TRAINING_MAKES)))]()


def _make(model: Callable[[], MassModel]) -> Callable[[], MassModel]:
    """A training make with a PLA print (at the infill that fits) as its lighter variant."""
    def build() -> MassModel:
        made = model()
        return dataclasses.replace(made, source=f"training mass prior: {made.source}", lighter=(printed(),))
    return build


TRAINING_MAKES: tuple[Callable[[], MassModel], ...] = (
    _make(printed),
    _make(lambda: solid("pine", "solid wood")),
    _make(lambda: solid("abs", "solid moulded plastic")),
    _make(lambda: solid("aluminium", "solid metal part")),
    _make(lambda: MassModel(f"full container: {material('water').source} filling the shape, 0.3 mm walls of "
                            f"{material('pet').source}", density=material("water").density,
                            shell=shell_of("pet", 0.0003))),
    _make(lambda: MassModel(f"empty carton: 0.5 mm walls of {material('paperboard').source}",
                            shell=shell_of("paperboard", 0.0005))),
)
"""The training mass prior (`objects generate --masses prior`): what a real object of a corpus
shape could be made of, from an empty carton (~0.4 kg/m^2 of wall, nothing inside) through a print,
wood and plastic to a full container (water, ~1000 kg/m^3) and a metal part (2700 kg/m^3). A depth
image shows the shape, not what is inside it, so the network's label should be the robust label
averaged over what the shape could weigh. With each shape's own material (`--masses material`) the
corpus is light (median 38 g against 136 g and 248 g for the basic and typical sets' real items), and
a network trained on it scores small dense objects (a D cell, a full can) as if they were prints."""

CONTAINER_KINDS = ("household_bottle", "household_spray_bottle", "household_jug", "household_can")
"""Household kinds that are closed containers (a bottle's, a jug's or a can's closed outer surface),
which `--masses filled` part-fills."""

CONTAINER_CONTENTS = ("water", "soft_drink", "milk", "shampoo", "peanut_butter")
"""What `--masses filled` fills a container with (objects.mass.MATERIALS): the typical set's
contents, four liquids, which level in whatever pose the container rests in, and a paste, which
stays where it was filled."""

FILL_FRACTION = (0.1, 0.8)
"""Share of a filled container's enclosed volume its contents take, drawn uniformly: from a last
drop to a full bottle's ~90 % below its neck, less the closed mesh's cap and trigger head, which
hold none."""

EMPTY_SHARE = 0.25
"""Share of containers `--masses filled` leaves empty, as the shipped corpus has them all."""


def filled_mass(generator_name: str, volume: float, rng: np.random.Generator) -> MassModel:
    """What a corpus object is made of under `--masses filled`: `corpus_mass`, except that a container
    (CONTAINER_KINDS) of enclosed `volume` (m^3) holds, unless it is drawn empty (EMPTY_SHARE), a
    drawn FILL_FRACTION of one of CONTAINER_CONTENTS, filled from the bottom upright. Where that
    weighs more than the cup's mass cap it holds a half, then a quarter of it, then nothing.

    The evaluation sets' containers are part-filled (a shampoo bottle, a spray cleaner, a milk jug,
    a jar of peanut butter, full cans) while the shipped corpus' are empty, so a network trained on
    it has never seen a bottle whose load is its contents'."""
    base = corpus_mass(generator_name)
    if generator_name not in CONTAINER_KINDS or rng.random() < EMPTY_SHARE:
        return base
    contents = material(CONTAINER_CONTENTS[int(rng.integers(len(CONTAINER_CONTENTS)))])
    fraction = float(rng.uniform(*FILL_FRACTION))
    levels = "a liquid: level in any pose it rests in" if contents.flows else "frozen as filled"
    model = base
    for share in (fraction / 4.0, fraction / 2.0, fraction):  # built lightest first: each falls back to the next
        model = MassModel(f"{base.source}, holding {share * 100:.3g} % of its volume of {contents.source} filled "
                          f"from the bottom ({levels})", shell=base.shell, contents=share * volume * contents.density,
                          contents_volume=share * volume, liquid=contents.flows, lighter=(model,))
    return model


MASS_MODES = ("material", "prior", "filled")
"""`objects generate --masses`: each shape's own material (`corpus_mass`), the training prior
(`prior_mass`), or each shape's own material with containers part-filled (`filled_mass`)."""


def check_mass_mode(masses: str) -> None:
    """InputError naming `--masses` unless it is one of MASS_MODES."""
    if masses not in MASS_MODES:
        raise InputError(f"--masses '{masses}': one of {', '.join(MASS_MODES)}")
