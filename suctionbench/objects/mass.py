"""What an object weighs and where its mass sits: named materials (densities with their sources),
real items' contents, thin walls, liquids filled to a level and denser parts, combined into one
mass, centre of mass and inertia; and the mass cap the cup sets.

A `MassModel` describes the object as the sum of components, each over the object's own mesh (in
its object frame, +z up for containers):

- a solid of uniform `density` (kg/m^3) filling the mesh (wood, steel, a print's infill);
- a thin `shell` (kg/m^2 = wall density x thickness) over the whole surface (cartons, cans,
  bottles, a print's perimeters), integrated exactly over the surface triangles;
- `contents` (kg) filling the mesh from its bottom up to the level that holds `contents_volume`
  (m^3; None fills it all): liquid in a can sits below its headspace, so the centre of mass is
  below the geometric centroid. Contents that are a `liquid` level again in whatever pose the
  object comes to rest (`objects.liquid`); others (a paste, cereal) stay as filled upright;
- a `part` of the shape (named in PARTS: the steel head of a hammer) whose density replaces the
  solid's inside it.

Where a model weighs more than the cap, its `lighter` variants are tried in turn (a 3D print at
lower infill, a corpus shape printed instead of made of its real material); an object whose
every variant is above the cap is an InputError.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import trimesh

from suctionbench.config import CUP_DEFAULT, STANDARD_GRAVITY, CupConfig
from suctionbench.errors import InputError

# -- materials -------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Material:
    """A named material: density (kg/m^3), where the figure comes from, and whether it flows (a
    liquid, which levels in a container whatever its pose)."""

    density: float
    source: str
    flows: bool = False


def _wood(specific_gravity: float, species: str) -> Material:
    """Wood at 12 % moisture content: the Wood Handbook's specific gravity (oven-dry mass over volume
    at 12 % moisture) times water's density times 1.12 (the water it holds)."""
    density = round(specific_gravity * 1000.0 * 1.12)
    return Material(density, f"{species}, specific gravity {specific_gravity} at 12 % moisture (Wood Handbook, "
                             f"USDA Forest Products Laboratory FPL-GTR-190, 2010, Table 5-3a) x 1.12")


MATERIALS: dict[str, Material] = {
    "beech": _wood(0.64, "American beech"),
    "pine": _wood(0.40, "ponderosa pine"),
    "hickory": _wood(0.72, "shagbark hickory"),
    "incense_cedar": _wood(0.37, "incense-cedar (pencil slats)"),
    "steel": Material(7850.0, "carbon and tool steel, 77.0-78.5 kN/m^3 (EN 1991-1-1, Annex A, Table A.4)"),
    "aluminium": Material(2700.0, "aluminium alloys, 27 kN/m^3 (EN 1991-1-1, Annex A, Table A.4)"),
    "glass": Material(2500.0, "soda-lime silicate glass, 2500 kg/m^3 (EN 572-1)"),
    "porcelain": Material(2400.0, "vitrified porcelain and stoneware tableware, 2.3-2.5 g/cm^3"),
    "pvc": Material(1400.0, "unplasticised PVC pipe compound, 1350-1460 kg/m^3 (EN ISO 1452-2)"),
    "pet": Material(1380.0, "PET bottle resin, semi-crystalline, 1.38-1.40 g/cm^3"),
    "hdpe": Material(955.0, "HDPE blow-moulding grade, 0.94-0.97 g/cm^3"),
    "pp": Material(905.0, "polypropylene, 0.90-0.91 g/cm^3"),
    "abs": Material(1050.0, "ABS, 1.04-1.06 g/cm^3"),
    "pla": Material(1240.0, "PLA filament, 1.24 g/cm^3 (NatureWorks Ingeo 4043D technical data sheet)"),
    "paperboard": Material(750.0, "folding boxboard and greyboard, 0.6-0.9 g/cm^3 (grammage over caliper)"),
    "book_paper": Material(650.0, "uncoated book paper, bulk ~1.55 cm^3/g (book papers: 1.3-2.0 cm^3/g)"),
    "packing_tape": Material(950.0, "wound BOPP packing tape: 0.905 g/cm^3 film with ~1.05 g/cm^3 acrylic adhesive"),
    "water": Material(998.0, "water at 20 degC", flows=True),
    "soft_drink": Material(1040.0, "sugared soft drink, ~10.6 % sugar by mass, 1.04 g/ml", flows=True),
    "milk": Material(1030.0, "whole cow's milk, 1.028-1.035 g/ml", flows=True),
    "shampoo": Material(1020.0, "shampoo (aqueous surfactant solution), ~1.02 g/ml", flows=True),
    "peanut_butter": Material(1080.0, "peanut butter, ~1.08 g/ml (a label's 32 g serving is ~30 ml)"),
}
"""Named materials by key. Wood densities follow the Wood Handbook's table, metals and glass the
European standards' unit weights; plastics and papers the ranges their grades span."""


def material(name: str) -> Material:
    """The named material, or InputError naming the known ones."""
    if name not in MATERIALS:
        raise InputError(f"material '{name}' is unknown (known: {', '.join(sorted(MATERIALS))})")
    return MATERIALS[name]


# -- the model -------------------------------------------------------------------------------------


@dataclass(frozen=True)
class MassModel:
    """How an object's mass is made up (see the module docstring); numbers in SI units."""

    source: str
    """What the mass is and where its numbers come from (object.toml's mass_source)."""

    density: float = 0.0
    """Density (kg/m^3) of a uniform solid filling the mesh; 0 for none."""

    shell: float = 0.0
    """Areal density (kg/m^2) of a thin wall over the whole surface; 0 for none."""

    contents: float = 0.0
    """Mass (kg) of contents inside the mesh; 0 for none."""

    contents_volume: float | None = None
    """Volume (m^3) the contents fill from the bottom of the mesh (its lowest z) up; None: all of it."""

    liquid: bool = False
    """Whether the contents are a liquid: at rest their surface is level whatever the object's pose
    (`objects.liquid`), where other contents stay as filled upright."""

    part: str | None = None
    """Name of a part of the shape (PARTS key) whose density is `part_density` instead of `density`."""

    part_density: float = 0.0
    """Density (kg/m^3) inside `part`."""

    lighter: tuple[MassModel, ...] = ()
    """Variants tried in turn when this one weighs more than the mass cap."""

    def __post_init__(self) -> None:
        values = {"density": self.density, "shell": self.shell, "contents": self.contents,
                  "part_density": self.part_density}
        for key, value in values.items():
            if not (math.isfinite(value) and value >= 0.0):
                raise InputError(f"mass model: {key} = {value!r} must be a finite number >= 0")
        if self.contents_volume is not None and not (math.isfinite(self.contents_volume) and self.contents_volume > 0):
            raise InputError(f"mass model: contents_volume = {self.contents_volume!r} must be > 0 m^3")
        if self.part is not None and self.part_density <= 0.0:
            raise InputError("mass model: a part needs its density (part_density > 0)")
        if not (self.density or self.shell or self.contents):
            raise InputError("mass model: give a density, a shell or contents")
        if not self.source:
            raise InputError("mass model: say where the mass comes from (source)")

    def to_dict(self) -> dict[str, Any]:
        """The components (without source and variants) as plain TOML-ready values."""
        data: dict[str, Any] = {"density": self.density, "shell": self.shell, "contents": self.contents}
        if self.contents_volume is not None:
            data["contents_volume"] = self.contents_volume
        if self.liquid:
            data["liquid"] = True
        if self.part is not None:
            data["part"], data["part_density"] = self.part, self.part_density
        return {k: round(v, 12) + 0.0 if isinstance(v, float) else v for k, v in data.items()}


def solid(material_name: str, what: str = "") -> MassModel:
    """A uniform solid of a named material; `what` says what the object is made as."""
    mat = material(material_name)
    return MassModel(f"{what + ': ' if what else ''}{mat.source}", density=mat.density)


def shell_of(material_name: str, thickness: float) -> float:
    """Areal density (kg/m^2) of a wall of a named material and thickness (m)."""
    return material(material_name).density * thickness


PRINT_WALL = 0.0008
"""Perimeter and top/bottom skin thickness (m) of the 3D prints: two 0.4 mm extrusion widths."""

PRINT_INFILL = 0.20
"""Infill fraction of the 3D prints (a common slicer default)."""


def printed(infill: float = PRINT_INFILL, wall: float = PRINT_WALL, lighter: bool = True) -> MassModel:
    """A PLA print: a `wall`-thick skin over the surface and `infill` (fraction of solid) inside.

    Mass = rho (infill V + (1 - infill) A wall): the skin is counted as a shell of areal density
    (1 - infill) rho wall on top of infill everywhere, exact for walls thin against the part (the
    skin's volume A wall is approximated to first order; where the part is thinner than two walls
    it is overcounted). With `lighter`, lower infills (5 % steps down to none) are the variants
    tried when the print would exceed the cap."""
    rho = material("pla").density
    variants = tuple(printed(f / 100.0, wall, lighter=False) for f in range(round(infill * 100) - 5, -1, -5)) \
        if lighter else ()
    return MassModel(
        f"3D print in PLA ({rho:g} kg/m^3, NatureWorks Ingeo 4043D data sheet): {wall * 1000:g} mm skin "
        f"(two 0.4 mm perimeters) and {infill * 100:g} % infill; mass = rho (infill V + (1 - infill) A wall)",
        density=infill * rho, shell=(1.0 - infill) * rho * wall, lighter=variants,
    )


# -- mass properties ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class MassProperties:
    """Mass (kg), centre of mass (3,) and inertia tensor about the centre of mass (3, 3), in the
    object frame."""

    mass: float
    com: np.ndarray
    inertia: np.ndarray

    def __add__(self, other: MassProperties) -> MassProperties:
        mass = self.mass + other.mass
        com = (self.mass * self.com + other.mass * other.com) / mass
        return MassProperties(mass, com, self.inertia_about(com) + other.inertia_about(com))

    def inertia_about(self, point: np.ndarray) -> np.ndarray:
        """Inertia tensor (3, 3) about `point` (parallel-axis theorem)."""
        d = self.com - np.asarray(point, dtype=float)
        return self.inertia + self.mass * (float(d @ d) * np.eye(3) - np.outer(d, d))

    def rotated(self, rotation: np.ndarray) -> MassProperties:
        """The same body expressed in a frame turned by `rotation` (3 x 3, old to new axes)."""
        return MassProperties(self.mass, rotation @ self.com, rotation @ self.inertia @ rotation.T)

    def scaled_to(self, mass: float) -> MassProperties:
        """The same body's distribution of mass, weighing `mass`."""
        return MassProperties(mass, self.com, self.inertia * (mass / self.mass))


def solid_properties(mesh: trimesh.Trimesh, density: float) -> MassProperties:
    """A closed mesh of uniform density."""
    props = mesh.mass_properties
    return MassProperties(density * float(props.volume), np.asarray(props.center_mass, dtype=float),
                          density * np.asarray(props.inertia, dtype=float))


def shell_properties(mesh: trimesh.Trimesh, areal_density: float) -> MassProperties:
    """A thin wall of uniform areal density (kg/m^2) over the mesh's surface. Per triangle
    (vertices a, b, c, area A): integral of x x^T dA = A / 12 (a a^T + b b^T + c c^T + s s^T),
    s = a + b + c."""
    triangles = np.asarray(mesh.triangles, dtype=float)
    area = np.asarray(mesh.area_faces, dtype=float)
    total = float(area.sum())
    com = (area[:, None] * triangles.mean(axis=1)).sum(axis=0) / total
    s = triangles.sum(axis=1)
    second = (np.einsum("f,fvi,fvj->ij", area, triangles, triangles) + np.einsum("f,fi,fj->ij", area, s, s)) / 12.0
    second = areal_density * (second - total * np.outer(com, com))
    return MassProperties(areal_density * total, com, np.trace(second) * np.eye(3) - second)


def below(mesh: trimesh.Trimesh, level: float) -> trimesh.Trimesh:
    """The part of a closed mesh below the height z = level (closed, via manifold3d)."""
    lo, hi = mesh.bounds
    size = hi - lo + 0.02
    cutter = trimesh.creation.box(extents=[size[0], size[1], level - lo[2] + 0.01])
    cutter.apply_translation([(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, (level + lo[2] - 0.01) / 2.0])
    return trimesh.boolean.intersection([mesh, cutter], engine="manifold")


def fill_level(mesh: trimesh.Trimesh, volume: float, tolerance: float = 1e-9) -> float:
    """Height z below which the closed mesh holds `volume` (m^3), by bisection (to `tolerance` m^3)."""
    if not 0.0 < volume <= float(mesh.volume) * (1.0 + 1e-9):
        raise InputError(f"contents of {volume * 1e6:.4g} ml do not fit the object's {mesh.volume * 1e6:.4g} ml")
    lo, hi = float(mesh.bounds[0, 2]), float(mesh.bounds[1, 2])
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        held = float(below(mesh, mid).volume)
        if abs(held - volume) <= tolerance:
            return mid
        lo, hi = (mid, hi) if held < volume else (lo, mid)
    return 0.5 * (lo + hi)


def contents_properties(mesh: trimesh.Trimesh, mass: float, volume: float | None,
                        down: np.ndarray | None = None) -> MassProperties:
    """Contents of `mass` (kg) filling `volume` (m^3; None: all) of the closed mesh from its
    bottom: the lowest z, or the lowest point along the direction `down` (the object's pose: the
    fill is found with the mesh turned so that `down` is -z, and turned back)."""
    if down is not None and volume is not None:
        turn = trimesh.geometry.align_vectors(np.asarray(down, dtype=float), [0.0, 0.0, -1.0])  # 4 x 4
        turned = mesh.copy().apply_transform(turn)
        return contents_properties(turned, mass, volume).rotated(turn[:3, :3].T)
    held = mesh if volume is None else below(mesh, fill_level(mesh, volume))
    return solid_properties(held, mass / float(held.volume))


PARTS: dict[str, Callable[..., trimesh.Trimesh]] = {}
"""Parts of shapes made of another material, by name: called with the object's generator
parameters, they return a closed mesh inside the object (e.g. a hammer's steel head)."""


def part(name: str) -> Callable[[Callable[..., trimesh.Trimesh]], Callable[..., trimesh.Trimesh]]:
    """Register a part function under `name`."""

    def register(fn: Callable[..., trimesh.Trimesh]) -> Callable[..., trimesh.Trimesh]:
        if name in PARTS:
            raise ValueError(f"part '{name}' registered twice")
        PARTS[name] = fn
        return fn

    return register


def mass_properties(mesh: trimesh.Trimesh, model: MassModel, params: dict[str, Any] | None = None) -> MassProperties:
    """Mass, centre of mass and inertia of `mesh` made up as `model` says (`params`: the
    generator's parameters, for a part)."""
    components = []
    if model.density:
        components.append(solid_properties(mesh, model.density))
    if model.shell:
        components.append(shell_properties(mesh, model.shell))
    if model.contents:
        components.append(contents_properties(mesh, model.contents, model.contents_volume))
    if model.part is not None:
        if model.part not in PARTS:
            from suctionbench.objects.shapes import register_all

            register_all()
        if model.part not in PARTS:
            raise InputError(f"part '{model.part}' is unknown (known: {', '.join(sorted(PARTS))})")
        piece = PARTS[model.part](**(params or {}))
        base = solid_properties(piece, model.density)
        heavy = solid_properties(piece, model.part_density)
        # the part's own density replaces the solid's inside it: add the part, take the solid's share away
        components.append(heavy)
        components.append(MassProperties(-base.mass, base.com, -base.inertia))
    total = components[0]
    for component in components[1:]:
        total = total + component
    return total


# -- the cap ---------------------------------------------------------------------------------------------


def mass_cap(cup: CupConfig = CUP_DEFAULT) -> dict[str, Any]:
    """The heaviest object the cup may carry, and how it follows from the cup's numbers."""
    return {
        "mass_cap_kg": round(cup.mass_cap_kg, 4),
        "formula": "V / (S (g + a_peak))",
        "vacuum_force_N": round(cup.vacuum_force, 4),
        "vacuum_pressure_Pa": cup.vacuum_pressure,
        "effective_radius_m": cup.effective_radius,
        "safety_factor": cup.safety_factor,
        "gravity": STANDARD_GRAVITY,
        "peak_acceleration": cup.peak_acceleration,
        "derivation": (
            f"V = {cup.vacuum_pressure / 1000:g} kPa x pi ({cup.effective_radius * 1000:g} mm)^2 = "
            f"{cup.vacuum_force:.2f} N; cap = V / (S (g + a_peak)) = {cup.vacuum_force:.2f} / "
            f"({cup.safety_factor:g} x ({STANDARD_GRAVITY:.2f} + {cup.peak_acceleration:g})) = {cup.mass_cap_kg:.3f} kg"
        ),
    }


def resolve_mass(
    mesh: trimesh.Trimesh, model: MassModel, name: str, params: dict[str, Any] | None = None,
    cup: CupConfig = CUP_DEFAULT, *, keep_above_cap: bool = False,
) -> tuple[MassModel, MassProperties]:
    """The first of `model` and its lighter variants that weighs no more than the cup's mass cap,
    with its mass properties. If none does: InputError, or with `keep_above_cap` the lightest
    variant (the object is kept, heavier than that cup carries)."""
    tried = []
    for candidate in variants(model):
        props = mass_properties(mesh, candidate, params)
        if props.mass <= cup.mass_cap_kg:
            return candidate, props
        tried.append((props.mass, candidate, props))
    if keep_above_cap:
        _, candidate, props = min(tried, key=lambda t: t[0])
        return candidate, props
    lightest = f" (its lightest variant {min(t[0] for t in tried):.3f} kg)" if len(tried) > 1 else ""
    raise InputError(over_cap_message(name, tried[0][0], cup, lightest))


def above_cap_warning(mass: float) -> str:
    """What an object of `mass` kg, above the default cup's mass cap, is told: which cup presets
    (`config.CUP_PRESETS`) carry it, if any."""
    from suctionbench.config import CUP_PRESETS

    carriers = [f"{k} ({c.mass_cap_kg:.3g} kg)" for k, c in CUP_PRESETS.items() if c.mass_cap_kg >= mass]
    cups = f"the cups that do: {', '.join(carriers)}" if carriers else "no cup preset carries it"
    return (f"{mass:.3f} kg is above the default cup's mass cap of {CUP_DEFAULT.mass_cap_kg:.3f} kg "
            f"({mass_cap(CUP_DEFAULT)['derivation']}): no grasp of that cup holds it ({cups}); give "
            "--mass if the real item is lighter")


def variants(model: MassModel) -> list[MassModel]:
    """`model` and its lighter variants, depth first (each variant's own variants follow it)."""
    return [model, *(v for lighter in model.lighter for v in variants(lighter))]


def over_cap_message(name: str, mass: float, cup: CupConfig = CUP_DEFAULT, note: str = "") -> str:
    """Why an object of `mass` kg is rejected: the cap and its derivation."""
    return (
        f"object '{name}': {mass:.3f} kg{note} is above the mass cap of {cup.mass_cap_kg:.3f} kg, the most the "
        f"cup carries at the episode's peak acceleration with safety factor {cup.safety_factor:g} "
        f"({mass_cap(cup)['derivation']}); choose a lighter variant of the object or give a lower mass"
    )
