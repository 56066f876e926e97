"""Turn a mesh into an object directory: validated mesh, mass properties, stable poses and a
convex decomposition for simulation, described by object.toml. Written atomically.

Layout of an object directory:
    object.toml         everything below, human readable
    mesh.stl            the (decimated) surface mesh used for labels, rendering and visuals
    parts/part_NNN.stl  convex parts (CoACD): one MuJoCo collision geom each
"""

from __future__ import annotations

import hashlib
import shutil
import tempfile
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w
import trimesh

from suctionbench.config import CUP_DEFAULT
from suctionbench.errors import InputError
from suctionbench.geometry.mesh import mesh_scale, validate_mesh
from suctionbench.objects.decompose import CoacdFailed, run_coacd
from suctionbench.objects.spec import ObjectSpec

MAX_FACES = 6000
"""Surface meshes above this many faces are decimated (quadric decimation) before anything else."""

MASS_CAP = 0.8 * CUP_DEFAULT.payload_kg
"""Masses from density are capped at 80 % of the default cup's payload (0.72 kg): the benchmark
is about where to grasp, and an object no cup position can lift tests nothing."""

MIN_MASS = 0.005
"""Lightest object mass (kg), so that no simulated object is a feather."""

COACD_SCHEDULE = ((0.05, 24), (0.03, 48), (0.02, 64))
"""(concavity threshold, max parts) tried in turn until the parts' union exceeds the object's
volume by at most EXCESS_MAX: hulls that bridge a bowl's or a tray's hollow would put phantom
material exactly where a suction cup may want to grasp."""

MAX_STABLE_POSES = 10
"""Stable poses kept per object (most probable first)."""

MIN_POSE_PROBABILITY = 0.005
"""Stable poses less probable than this are dropped (the most probable one is always kept: a
sphere has a continuum of equally improbable poses)."""

COVERAGE_MIN = 0.95
"""The union of the convex parts must cover at least this fraction of the object's volume."""

EXCESS_MAX = 1.25
"""...and its volume may exceed the object's by at most this factor (hulls bridge concavities)."""


@dataclass
class ObjectRecord:
    """One built object: the contents of object.toml plus where it lives."""

    name: str
    set: str
    generator: str
    params: dict[str, Any]
    description: str
    source: str
    units: str
    scale: float
    density: float
    mass: float
    com: list[float]
    inertia: list[list[float]]
    friction: float
    volume: float
    watertight: bool
    faces: int
    extents: list[float]
    geometry_hash: str
    stable_poses: list[dict[str, Any]]
    parts: list[str]
    decomposition: dict[str, Any] = field(default_factory=dict)
    directory: Path | None = None

    @property
    def key(self) -> str:
        """SET/NAME."""
        return f"{self.set}/{self.name}"

    def mesh(self) -> trimesh.Trimesh:
        """The object's surface mesh (metres, object frame)."""
        return trimesh.load(self.directory / "mesh.stl", force="mesh")

    def part_meshes(self) -> list[trimesh.Trimesh]:
        """The convex collision parts."""
        return [trimesh.load(self.directory / p, force="mesh") for p in self.parts]

    def most_probable_pose(self) -> np.ndarray:
        """4x4 transform placing the object at rest on the plane z = 0."""
        return np.asarray(self.stable_poses[0]["transform"], dtype=float)

    def to_toml(self) -> dict[str, Any]:
        data = {k: v for k, v in self.__dict__.items() if k != "directory"}
        return data

    @classmethod
    def load(cls, directory: Path) -> ObjectRecord:
        path = Path(directory) / "object.toml"
        try:
            data = tomllib.loads(path.read_text())
        except FileNotFoundError:
            raise InputError(f"object '{directory}': no object.toml") from None
        except tomllib.TOMLDecodeError as exc:
            raise InputError(f"object '{path}': malformed TOML ({exc})") from None
        return cls(**data, directory=Path(directory))


def geometry_hash(mesh: trimesh.Trimesh) -> str:
    """Content hash of a mesh's geometry (vertices rounded to 1 micrometre, faces)."""
    digest = hashlib.sha256()
    digest.update(np.round(np.asarray(mesh.vertices), 6).astype(np.float64).tobytes())
    digest.update(np.asarray(mesh.faces, dtype=np.int64).tobytes())
    return digest.hexdigest()[:32]


def prepare_mesh(mesh: trimesh.Trimesh, source: str) -> trimesh.Trimesh:
    """Validate, decimate if large, and insist on one closed body (what simulation needs)."""
    info = validate_mesh(mesh, source=source)
    mesh = info.mesh
    if not info.watertight:
        raise InputError(f"mesh '{source}': not watertight (has holes or inconsistent faces)")
    bodies = mesh.split(only_watertight=False)
    if len(bodies) > 1:
        raise InputError(f"mesh '{source}': {len(bodies)} disconnected bodies, expected one")
    if len(mesh.faces) > MAX_FACES:
        reduced = mesh.simplify_quadric_decimation(face_count=MAX_FACES)
        if reduced.is_watertight and reduced.is_winding_consistent and reduced.volume > 0:
            mesh = reduced
    return mesh


def stable_poses(mesh: trimesh.Trimesh, com: np.ndarray) -> list[dict[str, Any]]:
    """Quasi-static stable resting poses (Goldberg et al.) with probabilities, most probable first."""
    transforms, probs = trimesh.poses.compute_stable_poses(mesh, center_mass=com, sigma=0.0, n_samples=1)
    order = np.argsort(-probs)
    kept = [i for i in order if probs[i] >= MIN_POSE_PROBABILITY][:MAX_STABLE_POSES] or [order[0]]
    return [
        {"probability": round(float(probs[i]), 6), "transform": np.round(transforms[i], 9).tolist()}
        for i in kept
    ]


def convex_parts(
    mesh: trimesh.Trimesh, threshold: float, max_hulls: int, seed: int = 0, options: dict | None = None
) -> list[trimesh.Trimesh]:
    """Convex decomposition with CoACD (MuJoCo collides meshes by their convex hulls), run in a child
    process (suctionbench.objects.decompose) so that a native crash raises CoacdFailed here."""
    raw = run_coacd(np.asarray(mesh.vertices), np.asarray(mesh.faces), threshold, max_hulls, seed, options)
    parts = [trimesh.Trimesh(v, f, process=True).convex_hull for v, f in raw]
    return sorted(parts, key=lambda p: tuple(np.round(p.centroid, 6)))


def decompose_mesh(
    mesh: trimesh.Trimesh, source: str = "mesh", schedule=COACD_SCHEDULE, options: dict | None = None
) -> tuple[list[trimesh.Trimesh], dict[str, Any]]:
    """Convex parts following `schedule`, and how well they fit (the last try if none fits); `options`
    are further CoACD keywords (imports use decompose.IMPORT_SCHEDULE and IMPORT_OPTIONS).

    A CoACD run that crashes moves on to the next threshold; if every run crashes, a convex object
    (hull within EXCESS_MAX of its volume) falls back to its hull, anything else is an InputError."""
    best, failures = None, []
    for threshold, max_hulls in schedule:
        try:
            parts = convex_parts(mesh, threshold, max_hulls, options=options)
        except CoacdFailed as exc:
            failures.append(f"threshold {threshold:g}: {exc}")
            continue
        quality = decomposition_quality(mesh, parts)
        best = parts, {"method": "coacd", "threshold": threshold, "max_convex_hull": max_hulls, **quality}
        if quality["excess"] <= EXCESS_MAX and quality["coverage"] >= COVERAGE_MIN:
            break
    if best is not None:
        return best
    hull = mesh.convex_hull
    if float(hull.volume) <= EXCESS_MAX * float(mesh.volume):
        return [hull], {"method": "hull", "failures": failures, **decomposition_quality(mesh, [hull])}
    raise InputError(f"mesh '{source}': convex decomposition failed ({'; '.join(failures)})")


def decomposition_quality(mesh: trimesh.Trimesh, parts: list[trimesh.Trimesh]) -> dict[str, float]:
    """Coverage (share of the mesh inside the parts' union) and excess (union volume / mesh volume)."""
    hull_union = trimesh.boolean.union(parts, engine="manifold") if len(parts) > 1 else parts[0]
    outside = trimesh.boolean.difference([mesh, hull_union], engine="manifold")
    with np.errstate(invalid="ignore", divide="ignore"):  # an empty difference has zero volume
        outside_volume = float(outside.volume) if len(outside.faces) else 0.0
    return {
        "coverage": round(1.0 - max(outside_volume, 0.0) / float(mesh.volume), 6),
        "excess": round(float(hull_union.volume) / float(mesh.volume), 6),
    }


def build_object(
    mesh: trimesh.Trimesh,
    spec: ObjectSpec,
    out_dir: Path,
    *,
    source: str = "generated",
    units: str = "m",
    scale: float = 1.0,
    mass: float | None = None,
    decompose: bool = True,
    coacd: tuple[tuple[tuple[float, int], ...], dict] | None = None,
) -> ObjectRecord:
    """Build an object directory at `out_dir` (replaced atomically) and return its record.

    `coacd`: (schedule, options) for the convex decomposition instead of COACD_SCHEDULE and CoACD's
    defaults (see `decompose_mesh`)."""
    mesh = prepare_mesh(mesh, source=source if source != "generated" else spec.name)
    com = np.asarray(mesh.center_mass, dtype=float)
    if mass is None:
        mass = float(np.clip(spec.density * mesh.volume, MIN_MASS, MASS_CAP))
    elif not (np.isfinite(mass) and mass > 0):
        raise InputError(f"mass {mass!r}: must be a positive number of kilograms")
    mesh.density = mass / mesh.volume
    inertia = np.asarray(mesh.moment_inertia, dtype=float)
    record = ObjectRecord(
        name=spec.name,
        set=spec.set,
        generator=spec.generator,
        params=spec.params,
        description=spec.description,
        source=source,
        units=units,
        scale=mesh_scale(units, scale),
        density=round(mesh.density, 6),
        mass=round(mass, 9),
        com=np.round(com, 9).tolist(),
        inertia=np.round(inertia, 12).tolist(),
        friction=spec.friction,
        volume=round(float(mesh.volume), 12),
        watertight=True,
        faces=len(mesh.faces),
        extents=np.round(mesh.extents, 9).tolist(),
        geometry_hash=geometry_hash(mesh),
        stable_poses=stable_poses(mesh, com),
        parts=[],
    )
    if decompose:  # before any folder exists: a failure leaves nothing behind
        schedule, options = coacd or (COACD_SCHEDULE, None)
        parts, record.decomposition = decompose_mesh(mesh, source, schedule, options)
    out_dir = Path(out_dir)
    try:
        out_dir.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.", dir=out_dir.parent))
    except OSError as exc:
        raise InputError(f"output '{out_dir}': cannot write there ({exc.strerror})") from None
    try:
        mesh.export(tmp / "mesh.stl")
        if decompose:
            (tmp / "parts").mkdir()
            for i, part in enumerate(parts):
                part.export(tmp / "parts" / f"part_{i:03d}.stl")
            record.parts = [f"parts/part_{i:03d}.stl" for i in range(len(parts))]
        (tmp / "object.toml").write_text(tomli_w.dumps(record.to_toml()))
        _replace_dir(tmp, out_dir)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    record.directory = out_dir
    return record


def _replace_dir(new: Path, target: Path) -> None:
    """Move directory `new` to `target`, replacing any old one (old removed only after the move)."""
    old = None
    if target.exists():
        old = target.with_name(f".{target.name}.old")
        shutil.rmtree(old, ignore_errors=True)
        target.rename(old)
    new.rename(target)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
