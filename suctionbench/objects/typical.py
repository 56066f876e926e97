"""The 25 objects of the "typical" set (household goods built by the `objects.household` generators)
and what each household kind is made of when the training corpus draws it (`HOUSEHOLD_MASS`).

Each spec's mass model says what the real item is made of and holds: walls and contents for
containers, a named material otherwise; items heavier than the cup's mass cap (0.411 kg) are their
lighter real variants, named in the description.
"""

from __future__ import annotations

from suctionbench.objects.mass import MassModel, material, printed, shell_of, solid
from suctionbench.objects.sets import CAN_330_ML
from suctionbench.objects.spec import ObjectSpec


def _typical(name: str, gen: str, description: str, mass: MassModel, **params) -> ObjectSpec:
    """A spec of the typical set."""
    return ObjectSpec(name=name, set="typical", generator=gen, params=params, mass=mass, description=description)


def _container(what: str, wall_material: str, wall: float, contents: str | None = None, litres: float = 0.0):
    """A bottle, jar or jug: a `wall`-thick shell of `wall_material`, holding `litres` of `contents`
    filled from the bottom (upright; the level follows from the shape). A liquid levels again in the
    pose the object rests in (`objects.liquid`); a paste stays where it was filled."""
    text = f"{what}: {wall * 1000:g} mm walls of {material(wall_material).source}"
    if contents is None:
        return MassModel(text, shell=shell_of(wall_material, wall))
    liquid = material(contents)
    levels = " (a liquid: level in any pose it rests in)" if liquid.flows else " (frozen as filled)"
    return MassModel(
        f"{text}; {litres * 1000:g} ml of {liquid.source} filled from the bottom{levels}",
        shell=shell_of(wall_material, wall), contents=litres * 1e-3 * liquid.density, contents_volume=litres * 1e-3,
        liquid=liquid.flows,
    )


PORCELAIN = solid("porcelain", "glazed tableware")

TYPICAL_SPECS: list[ObjectSpec] = [
    _typical("mug_classic", "household_mug", "Straight 8 cm porcelain coffee mug with a round C handle.", PORCELAIN),
    _typical(
        "mug_tall", "household_mug", "Tall porcelain latte mug flaring towards the rim, with a long flat handle.",
        PORCELAIN,
        radius=0.042, bottom_radius=0.034, height=0.12, handle_radius=0.034, handle_width=0.016, handle_offset=0.012,
    ),
    _typical(
        "mug_espresso", "household_mug", "Small thick-walled porcelain espresso cup with a small handle.", PORCELAIN,
        radius=0.03, bottom_radius=0.025, height=0.06, wall=0.005, floor=0.008,
        handle_radius=0.016, handle_thickness=0.007, handle_width=0.01, handle_offset=0.006,
    ),
    _typical(
        "bottle_water", "household_bottle",
        "Half-litre PET water bottle, pinched waist, small cap, empty (full it weighs ~0.52 kg, above the cap).",
        _container("empty 0.5 l water bottle", "pet", 0.00025),
        radius=0.032, body_height=0.15, shoulder_height=0.04, waist=0.08,
    ),
    _typical(
        "bottle_wine", "household_bottle",
        "Slim 375 ml half-bottle of glass with a long neck and a screw cap, empty (a full 0.75 l wine bottle, "
        "~1.2 kg, is far above the cup's mass cap).",
        _container("empty glass half-bottle", "glass", 0.0025),
        radius=0.036, body_height=0.14, shoulder_height=0.035, neck_radius=0.014, neck_height=0.05,
        cap_radius=0.016, cap_height=0.03,
    ),
    _typical(
        "bottle_shampoo", "household_bottle",
        "Flat squared HDPE shampoo bottle with a wide flip cap, part used: 250 ml left (full, ~0.45 kg, it is "
        "above the cap).",
        _container("shampoo bottle", "hdpe", 0.0008, "shampoo", 0.25),
        radius=0.04, body_height=0.13, shoulder_height=0.025, neck_radius=0.014, neck_height=0.012,
        cap_radius=0.02, cap_height=0.025, squareness=5.0, depth_ratio=0.55,
    ),
    _typical(
        "jar_wide", "household_bottle",
        "Squat PET peanut-butter jar: wide body, short neck, large lid; 250 g left (full, ~0.8 kg, it is above "
        "the cap).",
        _container("peanut-butter jar", "pet", 0.0006, "peanut_butter", 0.25 / 1.08),
        radius=0.045, body_height=0.08, shoulder_height=0.012, neck_radius=0.038, neck_height=0.012,
        cap_radius=0.041, cap_height=0.02, squareness=2.6,
    ),
    _typical(
        "spray_bottle_cleaner", "household_spray_bottle",
        "Trigger spray cleaner with a flat oval HDPE body, half used: 250 ml left (full, ~0.6 kg, it is above the "
        "cap).",
        _container("trigger spray bottle", "hdpe", 0.0008, "water", 0.25),
    ),
    _typical(
        "stapler_desk", "household_stapler",
        "Desk stapler with its arm closed and slightly lifted at the front; pressed-steel shells.",
        MassModel("pressed-steel stapler: 0.8 mm sheet over the surface (" + material("steel").source + ")",
                  shell=shell_of("steel", 0.0008)),
    ),
    _typical(
        "jug_detergent", "household_jug",
        "Laundry-detergent jug with a moulded through-hole handle and a cap, empty (full, ~2 kg, it is far above "
        "the cap).",
        _container("empty detergent jug", "hdpe", 0.001),
    ),
    _typical(
        "jug_milk", "household_jug",
        "Tall narrow HDPE milk jug with a rounder body and a small cap, 250 ml of milk left (full, ~2 kg, it is "
        "far above the cap).",
        _container("milk jug", "hdpe", 0.0005, "milk", 0.25),
        width=0.12, depth=0.11, height=0.21, exponent=0.35, top_depth_scale=0.7, hole=[0.035, 0.075],
        grip=0.022, cap_radius=0.018, cap_height=0.02,
    ),
    _typical(
        "hammer_claw", "household_hammer", "Claw hammer: steel head, hickory handle (head-heavy).",
        MassModel(
            "steel head (" + material("steel").source + ") on a hickory handle (" + material("hickory").source + ")",
            density=material("hickory").density, part="household_hammer.head", part_density=material("steel").density,
        ),
    ),
    _typical(
        "screwdriver_flat", "household_screwdriver",
        "Flat-blade screwdriver with a faceted polypropylene handle and a steel shaft.",
        MassModel(
            "polypropylene handle (" + material("pp").source + ") with a steel shaft and blade ("
            + material("steel").source + ")",
            density=material("pp").density, part="household_screwdriver.shaft", part_density=material("steel").density,
        ),
    ),
    _typical(
        "wrench_combination", "household_wrench", "Combination wrench lying flat; solid steel.",
        solid("steel", "forged wrench"),
    ),
    _typical("toy_car", "household_toy_car", "Wooden toy car: rounded body, sloped cabin, four wheels.",
             solid("beech", "wooden toy")),
    _typical(
        "toy_truck", "household_toy_car", "Wooden toy truck: long low body with a tall cab at the front.",
        solid("beech", "wooden toy"),
        length=0.16, width=0.06, body_height=0.025, cabin_length=0.045, cabin_height=0.035, cabin_offset=0.045,
        windshield_slope=0.85, wheel_radius=0.015, wheel_width=0.012, clearance=0.01,
    ),
    _typical(
        "blocks_tower", "household_block_stack", "Three wooden toy blocks stacked, each turned against the one below.",
        solid("beech", "toy blocks"),
        blocks=[[0.06, 0.06, 0.03], [0.05, 0.04, 0.035], [0.035, 0.035, 0.035]], yaws=[0.0, 0.4, 0.9],
    ),
    _typical(
        "blocks_steps", "household_block_stack", "Rounded wooden toy bricks stacked off-centre like steps.",
        solid("beech", "toy blocks"),
        blocks=[[0.08, 0.04, 0.025], [0.06, 0.04, 0.025], [0.04, 0.04, 0.025]],
        shifts=[[0.0, 0.0], [0.01, 0.0], [0.02, 0.0]], exponent=0.15,
    ),
    _typical("bowl_cereal", "household_bowl", "Porcelain cereal bowl: spherical shell cut at the rim on a foot ring.",
             PORCELAIN),
    _typical(
        "bowl_small", "household_bowl", "Small deep porcelain dessert bowl with a thicker wall.", PORCELAIN,
        radius=0.05, wall=0.005, depth=0.042, foot_radius=0.022, foot_height=0.006,
    ),
    _typical(
        "soap_dish", "household_tray", "Polypropylene soap dish: shallow rounded tray with drainage ribs.",
        solid("pp", "moulded tray"), length=0.12, width=0.085, height=0.025, ribs=5,
    ),
    _typical(
        "pencil_tray", "household_tray", "Long ABS desk-organiser tray with straight walls.",
        solid("abs", "moulded tray"), length=0.22, width=0.07, height=0.03, wall=0.007, floor=0.005, exponent=0.2,
    ),
    _typical(
        "tape_packing", "household_tape_roll", "Roll of 48 mm packing tape lying flat.",
        solid("packing_tape", "tape roll (its 3 mm paperboard core, ~700 kg/m^3, counted at the tape's density)"),
    ),
    _typical("can_soda", "household_can", "Full 330 ml drink can, necked top, domed bottom.", CAN_330_ML),
    _typical(
        "can_soup", "household_can",
        "Full can of condensed soup (305 g net, a 68 x 102 mm can) with side beads and flush rims; the 400 g "
        "size (73 x 110 mm, ~0.46 kg) is above the cup's mass cap.",
        MassModel("full food can: 305 g net weight (the condensed-soup size) filling it + tinplate can, 0.2 mm "
                  "steel (" + material("steel").source + ")", shell=shell_of("steel", 0.0002), contents=0.305),
        radius=0.034, height=0.102, top_radius=0.0345, neck_height=0.006, foot_radius=0.031,
        foot_height=0.004, dome=0.002, lid_depth=0.003, rim_width=0.002, beads=4,
    ),
]
"""The 25 objects of the typical set: household goods with several flat or gently curved patches."""


def _corpus_kind(model: MassModel) -> MassModel:
    """A household kind's material for corpus draws, falling back to a PLA print of the shape (at
    the infill that fits) where the real material would exceed the cup's mass cap."""
    return MassModel(model.source, density=model.density, shell=model.shell, part=model.part,
                     part_density=model.part_density, lighter=(printed(),))


HOUSEHOLD_MASS: dict[str, MassModel] = {
    "household_mug": _corpus_kind(PORCELAIN),
    "household_bottle": _corpus_kind(_container("empty bottle", "pet", 0.00025)),
    "household_spray_bottle": _corpus_kind(_container("empty trigger spray bottle", "hdpe", 0.0008)),
    "household_stapler": _corpus_kind(next(s.mass for s in TYPICAL_SPECS if s.name == "stapler_desk")),
    "household_jug": _corpus_kind(_container("empty jug", "hdpe", 0.001)),
    "household_hammer": _corpus_kind(next(s.mass for s in TYPICAL_SPECS if s.name == "hammer_claw")),
    "household_screwdriver": _corpus_kind(next(s.mass for s in TYPICAL_SPECS if s.name == "screwdriver_flat")),
    "household_wrench": _corpus_kind(solid("steel", "forged wrench")),
    "household_toy_car": _corpus_kind(solid("beech", "wooden toy")),
    "household_block_stack": _corpus_kind(solid("beech", "toy blocks")),
    "household_bowl": _corpus_kind(PORCELAIN),
    "household_tray": _corpus_kind(solid("pp", "moulded tray")),
    "household_tape_roll": _corpus_kind(solid("packing_tape", "tape roll")),
    "household_can": _corpus_kind(_container("empty can", "aluminium", 0.00015)),
}
"""What each household kind is made of when the training corpus draws it at random sizes: the
typical set's materials, containers empty (their contents' level would depend on the draw)."""
