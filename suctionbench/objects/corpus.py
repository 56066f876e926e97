"""The training corpus: object specs drawn at random from a documented mix of shape families.

A policy trained on suction labels should see what the evaluation sets hold (prismatic primitives,
household goods, adversarial parts) and, beyond them, generic variety so it learns local surface
geometry rather than memorising a few shapes: superquadrics (flat to round), CSG composites (edges,
bosses, pockets, holes, brackets) and smooth blobs (free-form curvature). See CORPUS_CATEGORIES.

Spec i of a corpus depends only on (seed, i): its random stream is np.random.default_rng((seed, i)),
so any slice can be regenerated alone. Every draw is built and checked (watertight, one body,
2-25 cm, at most MAX_FACES faces); a draw that fails is redrawn from the same stream. What each
shape weighs and its scale come from `objects.corpus_priors` (named materials under the evaluation
sets' mass cap by default; `--masses prior` or `filled`, `--sizes items`).
"""

from __future__ import annotations

import functools
import inspect
import math
from collections.abc import Callable
from typing import Any, NamedTuple

import manifold3d as m3d
import numpy as np
import trimesh
from scipy.special import sph_harm_y

from suctionbench.errors import InputError
from suctionbench.geometry.mesh import validate_mesh
from suctionbench.objects.adversarial import radial_sphere, to_trimesh
from suctionbench.objects.build import MAX_FACES
from suctionbench.objects.corpus_priors import (
    CONTAINER_KINDS,
    ITEM_SIZES,
    check_mass_mode,
    check_size_mode,
    corpus_mass,
    filled_mass,
    prior_mass,
)
from suctionbench.objects.shapes import GENERATORS, generator, make_shape
from suctionbench.objects.spec import ObjectSpec

CORPUS_CATEGORIES: dict[str, float] = {
    "primitive": 0.20,
    "superquadric": 0.15,
    "composite": 0.25,
    "blob": 0.15,
    "adversarial": 0.10,
    "household": 0.15,
}
"""Share of each shape family in the corpus (sums to 1); the category ends each object's name.

- primitive (20 %): boxes, cylinders, prisms, tubes - the Basic set's families, at random sizes.
- superquadric (15 %): superellipsoids from sharp boxes through ellipsoids to octahedron-like shapes.
- composite (25 %, the largest: most real parts are made of several features): CSG of 2-4
  primitives that stays one body - bosses, pockets, through-holes, L/T brackets, capsules.
- blob (15 %): ellipsoids with smooth low-frequency random radial displacement (free-form).
- adversarial (10 %): random parameters of the adversarial generators (few sealable spots).
- household (15 %): random parameters of the household_* generators (the Typical set's kinds);
  where none is registered this share goes to composite.
"""

SIZE_RANGE = (0.02, 0.25)
"""Allowed largest extent (m) of a corpus object, small parts to large household goods."""

MAX_TRIES = 10
"""Draws per spec before falling back to a primitive (which always passes)."""

HOUSEHOLD_PREFIX = "household_"
"""Generators with this name prefix are sampled for the household category."""

Params = dict[str, Any]


# -- extra generators --------------------------------------------------------------------------


@generator("csg")
def csg(
    shapes: list[str],
    sizes: list[list[float]],
    positions: list[list[float]],
    rotations: list[list[float]],
    cut: list[bool],
) -> trimesh.Trimesh:
    """Union of the parts with cut = false minus the union of the parts with cut = true.

    Part k is shapes[k] ("box", "cylinder" along z, or "sphere") with bounding extents sizes[k],
    rotated by the rotation vector rotations[k] (rad) about its centre, then moved to positions[k].
    Parallel lists of plain values keep the parameters readable in object.toml.
    """
    parts = [_csg_part(*part) for part in zip(shapes, sizes, positions, rotations, strict=True)]
    added = [p for p, c in zip(parts, cut, strict=True) if not c]
    removed = [p for p, c in zip(parts, cut, strict=True) if c]
    solid = m3d.Manifold.batch_boolean(added, m3d.OpType.Add)
    if removed:
        solid = solid - m3d.Manifold.batch_boolean(removed, m3d.OpType.Add)
    return to_trimesh(solid)


def _csg_part(shape: str, size: list[float], position: list[float], rotation: list[float]) -> m3d.Manifold:
    """One CSG primitive, as a manifold3d solid."""
    half = np.asarray(size, dtype=float) / 2.0
    if shape == "box":
        solid = m3d.Manifold.cube(tuple(2.0 * half), center=True)
    elif shape == "cylinder":
        solid = m3d.Manifold.cylinder(2.0 * half[2], 1.0, circular_segments=48, center=True)
        solid = solid.scale((half[0], half[1], 1.0))
    elif shape == "sphere":
        solid = m3d.Manifold.sphere(1.0, 32).scale(tuple(half))
    else:
        raise ValueError(f"csg shape '{shape}' is unknown (known: box, cylinder, sphere)")
    transform = np.eye(4)
    angle = float(np.linalg.norm(rotation))
    if angle > 0.0:
        transform = trimesh.transformations.rotation_matrix(angle, np.asarray(rotation) / angle)
    transform[:3, 3] = position
    return solid.transform(transform[:3, :4])


@generator("blob")
def blob(radii: list[float], coefficients: list[float], subdivisions: int = 4) -> trimesh.Trimesh:
    """Ellipsoid with semi-axes `radii` whose radius is scaled by exp(sum_lm c_lm Y_lm).

    Y_lm are real orthonormal spherical harmonics of degree l = 1..L, order m = -l..l, in that
    order: `coefficients` has (L + 1)^2 - 1 entries. Degree 0 is left out (it only rescales).
    The exponential keeps every radius positive, so the surface stays star-shaped and watertight;
    a low L keeps the displacement smooth at the scale of the cup.
    """
    degree = math.isqrt(len(coefficients) + 1) - 1
    if (degree + 1) ** 2 - 1 != len(coefficients) or degree < 1:
        raise ValueError(f"blob: {len(coefficients)} coefficients; expected (L + 1)^2 - 1 for some L >= 1")
    radii = np.asarray(radii, dtype=float)

    def radius_of(d: np.ndarray) -> np.ndarray:
        ellipsoid = 1.0 / np.sqrt(((d / radii) ** 2).sum(axis=1))
        return ellipsoid * np.exp(real_harmonics(d, degree) @ np.asarray(coefficients, dtype=float))

    return radial_sphere(radius_of, subdivisions)


def real_harmonics(directions: np.ndarray, degree: int) -> np.ndarray:
    """(N, (degree + 1)^2 - 1) real orthonormal spherical harmonics, l = 1..degree, m = -l..l."""
    theta = np.arccos(np.clip(directions[:, 2], -1.0, 1.0))
    phi = np.mod(np.arctan2(directions[:, 1], directions[:, 0]), 2.0 * math.pi)
    columns = []
    for n in range(1, degree + 1):
        for m in range(-n, n + 1):
            y = sph_harm_y(n, abs(m), theta, phi)
            columns.append(y.real if m == 0 else math.sqrt(2.0) * (y.imag if m < 0 else y.real))
    return np.stack(columns, axis=1)


# -- samplers: rng -> (generator, params) ------------------------------------------------------


def _log_uniform(rng: np.random.Generator, low: float, high: float) -> float:
    """Scale parameters are drawn log-uniformly so small and large objects are equally common."""
    return float(math.exp(rng.uniform(math.log(low), math.log(high))))


def _dims(rng: np.random.Generator, count: int, largest: tuple[float, float] = (0.03, 0.22)) -> list[float]:
    """`count` dimensions: one log-uniform largest, the others a random fraction (>= 15 %) of it."""
    size = _log_uniform(rng, *largest)
    dims = [size, *(size * rng.uniform(0.15, 1.0, count - 1))]
    return [float(d) for d in rng.permutation(dims)]


def sample_primitive(rng: np.random.Generator) -> tuple[str, Params]:
    """Box, cylinder, regular prism or tube (the Basic set's families)."""
    kind = rng.choice(["box", "cylinder", "prism", "tube"])
    if kind == "box":
        return "box", {"extents": _dims(rng, 3)}
    diameter, height = _dims(rng, 2)
    radius = max(diameter / 2.0, 0.006)
    if kind == "cylinder":
        return "cylinder", {"radius": radius, "height": height}
    if kind == "prism":
        return "prism", {"sides": int(rng.integers(3, 9)), "radius": radius, "height": height}
    wall = max(radius * rng.uniform(0.08, 0.6), 0.0015)
    return "tube", {"outer_radius": radius, "inner_radius": radius - wall, "height": height}


def sample_superquadric(rng: np.random.Generator) -> tuple[str, Params]:
    """Superellipsoid: exponent 0.1 (near box) to 1 (ellipsoid) to 1.6 (towards an octahedron)."""
    return "superellipsoid", {"extents": _dims(rng, 3), "exponent": float(rng.uniform(0.1, 1.6)), "count": 38}


def sample_blob(rng: np.random.Generator) -> tuple[str, Params]:
    """Ellipsoid with random harmonic displacement; higher degrees get smaller coefficients."""
    radii = [d / 2.0 for d in _dims(rng, 3, largest=(0.025, 0.14))]
    degree = int(rng.integers(2, 5))
    strength = rng.uniform(0.1, 0.45)
    coefficients = [
        float(rng.normal(0.0, strength / l))
        for l in range(1, degree + 1)  # noqa: E741 (l is the harmonic degree)
        for _ in range(2 * l + 1)
    ]
    return "blob", {"radii": radii, "coefficients": coefficients}


def sample_composite(rng: np.random.Generator) -> tuple[str, Params]:
    """One of the CSG templates, each built so its parts overlap (one body) and cuts keep walls."""
    template = COMPOSITE_TEMPLATES[rng.choice(sorted(COMPOSITE_TEMPLATES))]
    parts = template(rng)
    return "csg", {
        "shapes": [p.shape for p in parts],
        "sizes": [p.size for p in parts],
        "positions": [p.position for p in parts],
        "rotations": [p.rotation for p in parts],
        "cut": [p.cut for p in parts],
    }


class Part(NamedTuple):
    """One part of a `csg` shape (see there)."""

    shape: str
    size: Any
    position: Any
    rotation: Any = (0.0, 0.0, 0.0)
    cut: bool = False


def _base(rng: np.random.Generator) -> tuple[Part, np.ndarray]:
    """A box or upright cylinder base centred at the origin, and its extents."""
    shape = rng.choice(["box", "cylinder"])
    size = np.asarray(_dims(rng, 3, largest=(0.04, 0.18)))
    size[2] = max(size[2], 0.012)
    if shape == "cylinder":
        size[:2] = size[:2].max()
    return Part(str(shape), size, (0.0, 0.0, 0.0)), size


def _inside(rng: np.random.Generator, base: np.ndarray, feature: np.ndarray, wall: float = 0.0) -> np.ndarray:
    """A random xy centre for a feature of xy size `feature` that keeps it, with `wall` to spare,
    inside the square inscribed in the base's footprint (0.7 of its extents), so it lies inside
    round bases as well as boxes."""
    room = np.maximum(0.7 * base[:2] / 2.0 - wall - feature[:2] / 2.0, 0.0)
    return rng.uniform(-room, room)


def _bossed(rng: np.random.Generator) -> list[Part]:
    """Base with one or two cylindrical or box bosses on top, sunk 1 mm into it."""
    base, size = _base(rng)
    parts = [base]
    for _ in range(int(rng.integers(1, 3))):
        boss = np.array([size[:2].min() * rng.uniform(0.2, 0.6)] * 2 + [_log_uniform(rng, 0.005, 0.06)])
        xy = _inside(rng, size, boss)
        top = size[2] / 2.0 + boss[2] / 2.0 - 0.001
        parts.append(Part(str(rng.choice(["cylinder", "box"])), boss, (xy[0], xy[1], top)))
    return parts


def _pocketed(rng: np.random.Generator) -> list[Part]:
    """Base with one or two blind pockets (box or cylinder) cut from the top, 2+ mm walls."""
    base, size = _base(rng)
    parts = [base]
    for _ in range(int(rng.integers(1, 3))):
        mouth = np.minimum(size[:2] * 0.7 - 0.004, size[:2] * rng.uniform(0.2, 0.6, 2))
        depth = size[2] * rng.uniform(0.3, 0.7)
        pocket = np.array([*np.maximum(mouth, 0.003), depth + 0.001])
        xy = _inside(rng, size, pocket, wall=0.002)
        centre = (xy[0], xy[1], size[2] / 2.0 - depth / 2.0 + 0.0005)
        parts.append(Part(str(rng.choice(["box", "cylinder"])), pocket, centre, cut=True))
    return parts


def _holed(rng: np.random.Generator) -> list[Part]:
    """Base with one to three through-holes, vertical or (through the side) horizontal."""
    base, size = _base(rng)
    parts = [base]
    for _ in range(int(rng.integers(1, 4))):
        if rng.random() < 0.6:  # vertical hole
            d = min(size[:2].min() * rng.uniform(0.1, 0.4), size[:2].min() * 0.7 - 0.004)
            xy = _inside(rng, size, np.array([d, d]), wall=0.002)
            parts.append(Part("cylinder", (d, d, size[2] + 0.01), (xy[0], xy[1], 0.0), cut=True))
        else:  # horizontal hole along x through the side, centred in height, 2+ mm walls in y
            d = min(size[2] * rng.uniform(0.2, 0.5), size[1] * 0.7 - 0.004)
            if d < 0.002:
                continue
            y = rng.uniform(-1.0, 1.0) * max(size[1] * 0.35 - d / 2.0 - 0.002, 0.0)
            parts.append(Part("cylinder", (d, d, size[0] * 1.5), (0.0, y, 0.0), (0.0, math.pi / 2.0, 0.0), True))
    return parts


def _bracket(rng: np.random.Generator) -> list[Part]:
    """L or T bracket: a base plate and an upright plate on its edge or middle, maybe a hole."""
    length, width = _dims(rng, 2, largest=(0.04, 0.16))
    thick = min(width, length) * rng.uniform(0.1, 0.35)
    height = _log_uniform(rng, 0.02, 0.12)
    x = -length / 2.0 + thick / 2.0 if rng.random() < 0.5 else 0.0  # L on the edge, T in the middle
    parts = [
        Part("box", (length, width, thick), (0.0, 0.0, 0.0)),
        Part("box", (thick, width, height), (x, 0.0, height / 2.0 - thick / 2.0)),
    ]
    if rng.random() < 0.5:  # a hole through the base plate, clear of the upright
        d = min(width * 0.5, (length / 2.0 - thick) * 0.6)
        if d > 0.003:
            hx = x + thick / 2.0 + 0.001 + d / 2.0 + rng.uniform(0.0, max(length / 2.0 - x - thick - d - 0.003, 0.0))
            hx = min(hx, length / 2.0 - d / 2.0 - 0.0015)
            parts.append(Part("cylinder", (d, d, thick * 3.0), (hx, 0.0, 0.0), cut=True))
    return parts


def _capsule(rng: np.random.Generator) -> list[Part]:
    """Cylinder with sphere or box ends: capsules, dumbbells, pills, spools."""
    diameter = _log_uniform(rng, 0.01, 0.06)
    length = _log_uniform(rng, 0.02, 0.15)
    end = diameter * rng.uniform(0.8, 1.8)
    shape = str(rng.choice(["sphere", "box"]))
    return [
        Part("cylinder", (diameter, diameter, length), (0.0, 0.0, 0.0)),
        Part(shape, (end, end, end), (0.0, 0.0, length / 2.0)),
        Part(shape, (end, end, end), (0.0, 0.0, -length / 2.0)),
    ]


COMPOSITE_TEMPLATES: dict[str, Callable[[np.random.Generator], list[Part]]] = {
    "bossed": _bossed,
    "pocketed": _pocketed,
    "holed": _holed,
    "bracket": _bracket,
    "capsule": _capsule,
}
"""CSG templates for the composite category, drawn with equal probability."""


def sample_adversarial(rng: np.random.Generator) -> tuple[str, Params]:
    """Random parameters of one of the adversarial generators (see adversarial.py)."""
    kind = str(rng.choice(["twisted_star", "ribbed_saddle", "gear", "knobby_blob", "ball_truss", "torus_knot"]))
    if kind == "twisted_star":
        outer = _log_uniform(rng, 0.015, 0.06)
        twist = float(rng.uniform(0.0, math.pi))
        return kind, {
            "points": int(rng.integers(3, 9)), "outer_radius": outer, "inner_radius": outer * rng.uniform(0.25, 0.65),
            "height": _log_uniform(rng, 0.02, 0.15), "twist": twist, "divisions": max(1, math.ceil(twist / 0.1)),
        }
    if kind == "ribbed_saddle":
        size = _log_uniform(rng, 0.05, 0.15)
        return kind, {
            "size": size, "thickness": size * rng.uniform(0.05, 0.12), "curvature": rng.uniform(0.3, 1.5) / size,
            "rib_spacing": size * rng.uniform(0.2, 0.35), "rib_width": size * rng.uniform(0.02, 0.05),
            "rib_height": size * rng.uniform(0.02, 0.06), "edge": size / 9.0,
        }
    if kind == "gear":
        root = _log_uniform(rng, 0.015, 0.06)
        teeth = int(rng.integers(8, 31))
        hub = root * rng.uniform(0.3, 0.7)
        thickness = root * rng.uniform(0.15, 0.5)
        return kind, {
            "teeth": teeth, "root_radius": root, "tip_radius": root * rng.uniform(1.1, 1.4),
            "tooth_width": 2.0 * math.pi * root / teeth * rng.uniform(0.2, 0.6), "thickness": thickness,
            "hub_radius": hub, "hub_height": thickness * rng.uniform(1.2, 3.0),
            "bore_radius": hub * rng.uniform(0.2, 0.7),
        }
    if kind == "knobby_blob":
        radius = _log_uniform(rng, 0.015, 0.05)
        return kind, {
            "radius": radius, "bumps": int(rng.integers(12, 81)), "bump_height": radius * rng.uniform(0.05, 0.2),
            "bump_width": rng.uniform(0.06, 0.2),
        }
    if kind == "ball_truss":
        cell = _log_uniform(rng, 0.025, 0.06)
        bar = cell * rng.uniform(0.04, 0.1)
        cells = rng.integers(1, 3, 3)
        cells[rng.integers(3)] = 1  # at most 2 x 2 x 1 cells keeps the face count within budget
        return kind, {
            "cells": [int(c) for c in cells], "cell_size": cell, "bar_radius": bar,
            "node_radius": min(bar * rng.uniform(1.5, 3.0), cell * 0.4), "diagonals": bool(rng.random() < 0.5),
        }
    p, q = [(2, 3), (3, 2), (2, 5), (3, 4), (3, 5)][int(rng.integers(5))]
    major = _log_uniform(rng, 0.025, 0.06)
    minor = major * rng.uniform(0.3, 0.5)
    tube = minor * rng.uniform(0.2, 0.5)  # <= half the minor radius: strands stay apart (checked too)
    return kind, {"p": p, "q": q, "major_radius": major, "minor_radius": minor, "tube_radius": tube}


def household_generators() -> list[str]:
    """Registered household_* generators whose parameters all have defaults (sampled around them).

    Read at call time from GENERATORS, so the list (and hence the corpus) depends on which
    generator modules have been imported: import them all before drawing a corpus.
    """
    names = []
    for name in sorted(GENERATORS):
        params = inspect.signature(GENERATORS[name]).parameters.values()
        if name.startswith(HOUSEHOLD_PREFIX) and all(p.default is not inspect.Parameter.empty for p in params):
            names.append(name)
    return names


def sample_household(rng: np.random.Generator) -> tuple[str, Params]:
    """A household generator at its default parameters, scaled together and jittered per value.

    The generators' signatures are not known here, so every float (lengths, and angles too) is
    multiplied by one common factor (0.7-1.4: keeps ratios such as inner < outer) and a small
    independent one (0.9-1.1: varies proportions); integers, flags and strings stay at their
    defaults. Draws that break a generator's constraints fail validation and are redrawn.
    """
    names = household_generators()
    name = names[int(rng.integers(len(names)))]
    largest = min(1.4, 0.9 * SIZE_RANGE[1] / _default_extent(name))  # long tools stay below 25 cm
    scale = rng.uniform(min(0.7, largest), largest)

    def jitter(value: Any) -> Any:
        if isinstance(value, float):
            return value * scale * rng.uniform(0.9, 1.1)
        if isinstance(value, (list, tuple)):
            return [jitter(v) for v in value]
        return value

    defaults = inspect.signature(GENERATORS[name]).parameters
    return name, {key: jitter(p.default) for key, p in defaults.items()}


@functools.cache
def _default_extent(name: str) -> float:
    """Largest extent (m) of a generator's shape at its default parameters."""
    return float(make_shape(name, {}).extents.max())


SAMPLERS: dict[str, Callable[[np.random.Generator], tuple[str, Params]]] = {
    "primitive": sample_primitive,
    "superquadric": sample_superquadric,
    "composite": sample_composite,
    "blob": sample_blob,
    "adversarial": sample_adversarial,
    "household": sample_household,
}
"""Parameter sampler of each corpus category."""


# -- the corpus --------------------------------------------------------------------------------


def plain(value: Any) -> Any:
    """Parameters as plain Python values (JSON/TOML): floats rounded to 6 digits, lists not tuples."""
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [plain(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return round(float(value), 6) + 0.0  # + 0.0 turns -0.0 into 0.0
    if isinstance(value, np.str_):
        return str(value)
    return value


def check_shape(mesh: trimesh.Trimesh) -> str | None:
    """Why `mesh` is not a valid corpus object (None if it is): what build.prepare_mesh needs,
    without decimation (the corpus is generated within the face budget), plus the size range."""
    try:
        info = validate_mesh(mesh)
    except InputError as exc:
        return str(exc)
    if not info.watertight:
        return "not watertight"
    if len(info.mesh.faces) > MAX_FACES:
        return f"{len(info.mesh.faces)} faces (> {MAX_FACES})"
    largest = float(info.mesh.extents.max())
    if not SIZE_RANGE[0] <= largest <= SIZE_RANGE[1]:
        return f"largest extent {largest:.4g} m outside {SIZE_RANGE[0]}-{SIZE_RANGE[1]} m"
    bodies = len(info.mesh.split(only_watertight=False))
    if bodies != 1:
        return f"{bodies} bodies"
    return None


def corpus_spec(seed: int, index: int, masses: str = "material", sizes: str = "family") -> ObjectSpec:
    """Spec `index` of the corpus drawn with `seed`: depends only on (seed, index) (and `masses`,
    MASS_MODES, which sets its mass and nothing else, from its own streams (seed, index, 1 or 3),
    and `sizes`, SIZE_MODES, which sets its scale and, through it, its mass).

    The category is drawn first, always from the full CORPUS_CATEGORIES (a household draw becomes
    composite when no household generator is registered, so other specs do not shift). Then
    parameters are drawn and the shape built and checked, up to MAX_TRIES times from the same
    stream; if every draw fails, a primitive is used (primitives always pass). With `sizes`
    "items" a generic shape is scaled to a largest extent drawn from its own stream
    (seed, index, 2), so the shapes are those of the "family" corpus at other sizes.
    """
    rng = np.random.default_rng((seed, index))
    size_rng = np.random.default_rng((seed, index, 2))
    names = list(CORPUS_CATEGORIES)
    category = names[int(rng.choice(len(names), p=np.asarray([CORPUS_CATEGORIES[n] for n in names])))]
    if category == "household" and not household_generators():
        category = "composite"
    rescale = sizes == "items" and category != "household"
    for _ in range(MAX_TRIES):
        gen, params = SAMPLERS[category](rng)
        params = plain(params)
        largest = _log_uniform(size_rng, *ITEM_SIZES) if rescale else None
        try:
            mesh = make_shape(gen, params)
            if largest is not None:  # what the "scaled" generator builds, from the mesh at hand
                gen, params = "scaled", plain({"generator": gen, "params": params,
                                              "factor": largest / float(mesh.extents.max())})
                mesh.apply_scale(params["factor"])
            problem = check_shape(mesh)
        except Exception as exc:  # any generator error (bad parameter combination) means: redraw
            problem = f"{type(exc).__name__}: {exc}"
        if problem is None:
            break
    else:
        category = "primitive"
        gen, params = sample_primitive(rng)
        params = plain(params)
    kind = params["generator"] if gen == "scaled" else gen
    scaled = f", scaled x{params['factor']:.3g}" if gen == "scaled" else ""
    if masses == "prior":
        mass = prior_mass(kind, np.random.default_rng((seed, index, 1)))
    elif masses == "filled" and kind in CONTAINER_KINDS:  # a container is never the fallback primitive
        mass = filled_mass(kind, float(mesh.volume), np.random.default_rng((seed, index, 3)))
    else:
        mass = corpus_mass(kind)
    return ObjectSpec(
        name=f"train_{index:05d}_{category}",
        set="train",
        generator=gen,
        params=params,
        description=f"training corpus: {category} ({kind}{scaled})",
        mass=mass,
    )


def corpus_specs(count: int, seed: int, masses: str = "material", sizes: str = "family") -> list[ObjectSpec]:
    """The first `count` specs of the corpus drawn with `seed` (set "train"), masses as `masses`
    (MASS_MODES), sizes as `sizes` (SIZE_MODES)."""
    from suctionbench.objects.shapes import register_all

    check_mass_mode(masses)
    check_size_mode(sizes)
    register_all()  # the household share must not depend on what happened to be imported
    return [corpus_spec(seed, i, masses, sizes) for i in range(count)]
