"""The evaluation sets: Basic (here), Typical (typical.py), Adversarial (adversarial.py).

Basic follows the paper: prismatic solids - boxes of many aspect ratios, cylinders, prisms and
tubes - at household sizes (2-25 cm). Specs are explicit, so names and shapes never drift. Each
object's mass model (objects.mass) says what it is made of: the real item's contents and packaging
where it depicts one, else a named material. Real items heavier than the cup's mass cap (0.411 kg)
are their lighter real variants, named in the description.
"""

from __future__ import annotations

from suctionbench.objects.mass import MassModel, material, shell_of, solid
from suctionbench.objects.spec import ObjectSpec


def _basic(name: str, generator: str, description: str, mass: MassModel, **params) -> ObjectSpec:
    return ObjectSpec(name=name, set="basic", generator=generator, params=params, description=description, mass=mass)


def _carton(contents_kg: float, what: str, thickness: float = 0.0005) -> MassModel:
    """A carton of folding boxboard (`thickness` m) holding `contents_kg` spread through it."""
    return MassModel(
        f"{what} + carton: {thickness * 1000:g} mm paperboard ({material('paperboard').source}) over the surface",
        shell=shell_of("paperboard", thickness), contents=contents_kg,
    )


CAN_330_ML = MassModel(
    "full 330 ml drink can: 330 ml of soft drink (" + material("soft_drink").source + ") filling the can from "
    "the bottom (headspace above; a liquid, level in any pose the can rests in) "
    "+ aluminium can, 0.15 mm average wall (0.1 mm body, thicker base and lid; "
    + material("aluminium").source + "); about 0.35 kg, as a full 330 ml can weighs",
    shell=shell_of("aluminium", 0.00015), contents=0.330e-3 * material("soft_drink").density,
    contents_volume=0.330e-3, liquid=True,
)
"""A full 330 ml drink can (basic/cylinder_can, typical/can_soda)."""

BASIC_SPECS: list[ObjectSpec] = [
    _basic("box_cereal", "box",
           "cereal box, tall and thin, holding 250 g of corn flakes (the small retail size: a 375-500 g box "
           "weighs 0.45-0.65 kg with its packaging, above the cup's mass cap)",
           _carton(0.25, "250 g of cereal (the pack's net weight) spread through the box"), extents=[0.19, 0.06, 0.25]),
    _basic("box_shoe", "box", "shoe box, empty (its lid on)",
           MassModel("empty shoe box: 1.5 mm greyboard walls (" + material("paperboard").source + ")",
                     shell=shell_of("paperboard", 0.0015)), extents=[0.22, 0.14, 0.10]),
    _basic("box_tea", "box", "tea box of 50 tea bags",
           _carton(0.1, "50 tea bags of 2 g (100 g net weight)"), extents=[0.14, 0.07, 0.07]),
    _basic("box_matchbox", "box", "matchbox, small, with 45 safety matches",
           _carton(0.0045, "45 matches of ~0.1 g (aspen splints 2 x 2 x 47 mm, ~420 kg/m^3, with heads)",
                   thickness=0.0008), extents=[0.05, 0.035, 0.015]),
    _basic("box_book", "box", "paperback book, flat", solid("book_paper", "paperback"), extents=[0.18, 0.11, 0.025]),
    _basic("box_cube_small", "box", "small wooden toy cube", solid("beech", "toy block"), extents=[0.04, 0.04, 0.04]),
    _basic("box_cube", "box", "wooden toy cube", solid("beech", "toy block"), extents=[0.08, 0.08, 0.08]),
    _basic("box_stick", "box", "long square wooden stick", solid("pine", "sawn timber"), extents=[0.20, 0.025, 0.025]),
    _basic("box_plank", "box", "wide flat wooden plank", solid("pine", "sawn timber"), extents=[0.24, 0.08, 0.015]),
    _basic("box_brick", "box", "wooden toy brick (a full-size clay brick, ~2.5 kg, is far above the cup's mass cap)",
           solid("beech", "toy block"), extents=[0.10, 0.05, 0.03]),
    _basic("cylinder_can", "cylinder", "soda can, full (330 ml)", CAN_330_ML, radius=0.033, height=0.12),
    _basic("cylinder_tuna", "cylinder", "tuna can, squat, full (185 g net)",
           MassModel("full tuna can: 185 g net weight (the common 85 mm can) filling it + tinplate can, 0.2 mm "
                     "steel (" + material("steel").source + ")", shell=shell_of("steel", 0.0002), contents=0.185),
           radius=0.043, height=0.04),
    _basic("cylinder_jar", "cylinder", "glass jar, empty (lid ignored)",
           MassModel("empty glass jar: 2.5 mm walls (container glass: 2-4 mm) of " + material("glass").source,
                     shell=shell_of("glass", 0.0025)), radius=0.045, height=0.10),
    _basic("cylinder_dowel", "cylinder", "thick hardwood dowel", solid("beech", "dowel"), radius=0.015, height=0.20),
    _basic("cylinder_puck", "cylinder", "ice-hockey puck",
           MassModel("regulation ice-hockey puck, 156-170 g (IIHF Official Rule Book, rule 26; NHL rule 25): "
                     "163 g of vulcanised rubber", contents=0.163),
           radius=0.038, height=0.025),
    _basic("cylinder_battery", "cylinder", "D-cell battery (alkaline)",
           MassModel("alkaline D cell (IEC LR20), ~140 g (manufacturers' data sheets, e.g. Duracell MN1300 "
                     "and Energizer E95: 135-150 g)", contents=0.140),
           radius=0.017, height=0.06),
    _basic("prism_tri_toblerone", "prism", "triangular prism, chocolate-bar style (a 100 g bar in its carton)",
           _carton(0.1, "a 100 g chocolate bar (net weight) spread through the carton"),
           sides=3, radius=0.025, height=0.20),
    _basic("prism_tri_wedge", "prism", "short triangular prism, a wooden wedge", solid("pine", "sawn timber"),
           sides=3, radius=0.045, height=0.05),
    _basic("prism_hex_nut", "prism", "hexagonal prism, large nut blank in aluminium (a steel one, 0.46 kg, "
           "exceeds the cup's mass cap)", solid("aluminium", "bar stock"), sides=6, radius=0.03, height=0.025),
    _basic("prism_hex_pencil", "prism", "hexagonal prism, jumbo pencil", solid("incense_cedar", "pencil"),
           sides=6, radius=0.012, height=0.18),
    _basic("prism_pent", "prism", "pentagonal wooden prism", solid("pine", "sawn timber"),
           sides=5, radius=0.04, height=0.08),
    _basic("prism_oct", "prism", "octagonal wooden prism", solid("pine", "sawn timber"),
           sides=8, radius=0.035, height=0.12),
    _basic("tube_pipe", "tube", "pipe section, PVC", solid("pvc", "pipe"),
           outer_radius=0.025, inner_radius=0.02, height=0.15),
    _basic("tube_roll", "tube", "paper towel core (a sturdy 3 mm spiral-wound board)",
           solid("paperboard", "wound core"), outer_radius=0.022, inner_radius=0.019, height=0.22),
    _basic("tube_ring", "tube", "wide short ring, a PVC pipe off-cut", solid("pvc", "pipe"),
           outer_radius=0.045, inner_radius=0.035, height=0.03),
]
"""The 25 Basic objects."""
