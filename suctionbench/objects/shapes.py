"""Procedural shape generators: every committed or generated object is one of these, called with
plain keyword parameters (metres), so an object is fully described by (generator, params).

Generators return watertight, consistently oriented meshes. Composites are built by constructive
solid geometry through manifold3d (`union`, `difference`), and by smooth deformations.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import trimesh

from suctionbench.geometry.shapes import superellipsoid as _superellipsoid

Generator = Callable[..., trimesh.Trimesh]

GENERATORS: dict[str, Generator] = {}
"""All generators by name (filled by the @generator decorator in this and sibling modules)."""


def generator(name: str) -> Callable[[Generator], Generator]:
    """Register a shape generator under `name` (names are stable: they are stored in object.toml)."""

    def register(fn: Generator) -> Generator:
        if name in GENERATORS:
            raise ValueError(f"generator '{name}' registered twice")
        GENERATORS[name] = fn
        return fn

    return register


def register_all() -> None:
    """Import every module that registers generators, so the registry is complete wherever it
    is used (worker processes, the corpus sampler) whatever was imported before."""
    from suctionbench.objects import adversarial, corpus, household  # noqa: F401


def make_shape(generator_name: str, params: dict[str, Any]) -> trimesh.Trimesh:
    """Build a shape from its generator name and parameters."""
    if generator_name not in GENERATORS:
        register_all()
    return GENERATORS[generator_name](**params)


# -- CSG helpers ---------------------------------------------------------------------------------


def union(*meshes: trimesh.Trimesh) -> trimesh.Trimesh:
    """Boolean union (manifold3d)."""
    return trimesh.boolean.union(list(meshes), engine="manifold")


def difference(a: trimesh.Trimesh, *cutters: trimesh.Trimesh) -> trimesh.Trimesh:
    """Boolean difference a - cutters (manifold3d)."""
    return trimesh.boolean.difference([a, *cutters], engine="manifold")


def placed(mesh: trimesh.Trimesh, translation=(0.0, 0.0, 0.0), rotation=None) -> trimesh.Trimesh:
    """A copy of `mesh`, rotated by the rotation vector `rotation` (rad) then translated."""
    out = mesh.copy()
    if rotation is not None and np.linalg.norm(rotation) > 0:
        angle = float(np.linalg.norm(rotation))
        out.apply_transform(trimesh.transformations.rotation_matrix(angle, np.asarray(rotation) / angle))
    out.apply_translation(translation)
    return out


# -- primitives ----------------------------------------------------------------------------------


@generator("box")
def box(extents: list[float]) -> trimesh.Trimesh:
    """Rectangular box with the given (x, y, z) extents, centred at the origin."""
    return trimesh.creation.box(extents=extents)


@generator("cylinder")
def cylinder(radius: float, height: float, sections: int = 64) -> trimesh.Trimesh:
    """Solid circular cylinder along z."""
    return trimesh.creation.cylinder(radius=radius, height=height, sections=sections)


@generator("prism")
def prism(sides: int, radius: float, height: float) -> trimesh.Trimesh:
    """Right prism along z over a regular polygon with `sides` sides and circumradius `radius`."""
    return trimesh.creation.cylinder(radius=radius, height=height, sections=sides)


@generator("tube")
def tube(outer_radius: float, inner_radius: float, height: float, sections: int = 64) -> trimesh.Trimesh:
    """Open-ended circular tube (annulus extruded along z)."""
    return trimesh.creation.annulus(r_min=inner_radius, r_max=outer_radius, height=height, sections=sections)


@generator("superellipsoid")
def superellipsoid(extents: list[float], exponent: float = 0.3, count: int = 48) -> trimesh.Trimesh:
    """Rounded box / ellipsoid family (see suctionbench.geometry.shapes.superellipsoid)."""
    return _superellipsoid(tuple(extents), exponent=exponent, count=count)
