"""Liquids that level in the pose an object rests in.

An object is built with its contents filled upright, from the bottom of its mesh (`objects.mass`).
A liquid does not stay there: a part-filled bottle lying on its side holds its liquid along its
whole length, under a level surface, not in the end that was its bottom. Where the liquid lies
moves the centre of mass by centimetres (the spray cleaner's 250 ml, lying: 45 mm along its axis
and 13 mm across), and the centre of mass decides whether a suction grasp holds against gravity's torque.

The model is quasi-static: whenever the object is at rest, the liquid's surface is the plane
perpendicular to gravity that leaves the liquid's volume below it, inside the object's closed
surface (the wall's thickness is neglected, as when the object was built). While the object
moves - falling, rolling, lifted on the cup - the liquid moves with it as if frozen; sloshing,
and the liquid flowing during a lift that tilts the object, are not modelled.

`Liquid.of(record)` is None for an object without a liquid; otherwise `properties(down)` gives the
object's mass, centre of mass and inertia (object frame) with the liquid levelled for gravity
along `down` (object frame). The simulation applies it each time an object comes to rest
(`sim.episode.PickEpisode.settle`); the labeller takes the centre of mass from the simulation's
body, so both judge the same object.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from suctionbench.objects.build import ObjectRecord
from suctionbench.objects.mass import MassProperties, contents_properties

UPRIGHT = np.array([0.0, 0.0, -1.0])
"""Gravity in the object frame when the object stands as built (+z up)."""


@dataclass(frozen=True)
class Liquid:
    """An object's liquid contents and the rest of the object's mass."""

    mesh: trimesh.Trimesh
    """The closed surface the liquid fills (the object's surface mesh, object frame)."""

    mass: float
    """Mass (kg) of the liquid."""

    volume: float
    """Volume (m^3) of the liquid."""

    dry: MassProperties
    """The object without its liquid (walls, cap, ...), object frame."""

    @classmethod
    def of(cls, record: ObjectRecord, mesh: trimesh.Trimesh | None = None) -> Liquid | None:
        """The liquid of a built object (its mass model's contents, where they are a liquid filling
        part of the object), None where it has none. `mesh`: the record's surface mesh, if loaded."""
        model = record.mass_model or {}
        if not model.get("liquid") or not model.get("contents") or model.get("contents_volume") is None:
            return None
        mesh = record.mesh() if mesh is None else mesh
        mass, volume = float(model["contents"]), float(model["contents_volume"])
        whole = MassProperties(record.mass, np.asarray(record.com, dtype=float),
                               np.asarray(record.inertia, dtype=float))
        upright = contents_properties(mesh, mass, volume)
        dry = whole + MassProperties(-upright.mass, upright.com, -upright.inertia)
        return cls(mesh=mesh, mass=mass, volume=volume, dry=dry)

    def properties(self, down: np.ndarray) -> MassProperties:
        """The whole object's mass properties (object frame) with the liquid level for gravity
        along `down` (object frame; any length)."""
        return self.dry + contents_properties(self.mesh, self.mass, self.volume, down=down)


def com_at_rest(record: ObjectRecord, rotation: np.ndarray, liquid: Liquid | None) -> np.ndarray:
    """The centre of mass (object frame) of `record` at rest with orientation `rotation` (object to
    world, 3 x 3): as built, or with its `liquid` (`Liquid.of(record)`) levelled in that pose."""
    if liquid is None:
        return np.asarray(record.com, dtype=float)
    return liquid.properties(np.asarray(rotation, dtype=float).T @ UPRIGHT).com
