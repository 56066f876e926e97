"""Turn a mesh into an object directory: validated mesh, mass properties, stable poses and a
convex decomposition for simulation, described by object.toml. Written atomically (all or
nothing), and never in place of a directory holding files suctionbench did not write
(`suctionbench.objects.ownership`).

Layout of an object directory:
    object.toml         everything below, human readable
    mesh.stl            the (decimated) surface mesh used for labels, rendering and visuals
    parts/part_NNN.stl  convex parts (CoACD): one MuJoCo collision geom each
"""

from __future__ import annotations

import hashlib
import os
import shutil
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
from suctionbench.io import WRITE_ERRNOS, os_error_reason, publish_dir, staging_dir
from suctionbench.objects.decompose import CoacdFailed, CoacdRun
from suctionbench.objects.mass import (
    MassModel,
    MassProperties,
    above_cap_warning,
    mass_properties,
    over_cap_message,
    resolve_mass,
)
from suctionbench.objects.ownership import check_replaceable_objects
from suctionbench.objects.spec import ObjectSpec

MAX_FACES = 6000
"""Surface meshes above this many faces are decimated (quadric decimation) before anything else."""

MASS_CAP = CUP_DEFAULT.mass_cap_kg
"""Heaviest object (kg) the default cup carries: V / (S (g + a_peak)) = 0.411 kg (CupConfig.mass_cap_kg,
objects.mass.mass_cap). Building a set's object above it is an InputError (objects whose real item
is heavier are modelled as its lighter real variant: see each object's description); an imported
one is kept with a warning (`object_mass`)."""

MIN_MASS = 0.005
"""Lightest object mass (kg), so that no simulated object is a feather: a lighter mass model (a tiny
print) is scaled up to it, and its mass_source says so."""

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
    mass_source: str = ""
    """What the mass is and where its numbers come from (objects.mass)."""
    mass_model: dict[str, Any] = field(default_factory=dict)
    """The mass model's components (objects.mass.MassModel.to_dict); empty for a mass given directly."""
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


def prepare_mesh(mesh: trimesh.Trimesh, source: str, assembly: bool = False) -> trimesh.Trimesh:
    """Validate, decimate if large, and insist on one closed body (what simulation needs), or with
    `assembly` on closed bodies (separate pieces of one rigid body: `objects.repair`, ASSEMBLY)."""
    info = validate_mesh(mesh, source=source)
    mesh = info.mesh
    if not info.watertight:
        raise InputError(f"mesh '{source}': not watertight (has holes or inconsistent faces)")
    if not assembly:  # an assembly's pieces are its own (solidify counted them): no split to pay for
        bodies = mesh.split(only_watertight=False)
        if len(bodies) > 1:
            raise InputError(f"mesh '{source}': {len(bodies)} disconnected bodies, expected one")
    if len(mesh.faces) > MAX_FACES:
        reduced = mesh.simplify_quadric_decimation(face_count=MAX_FACES)
        if reduced.is_watertight and reduced.is_winding_consistent and reduced.volume > 0:
            mesh = reduced
    return mesh


def stable_poses(mesh: trimesh.Trimesh, com: np.ndarray) -> list[dict[str, Any]]:
    """Quasi-static stable resting poses (Goldberg et al.) with probabilities, most probable first.

    Poses of equal (rounded) probability - a symmetric object's faces - are ordered by their rounded
    transform, so the order does not depend on the order the hull's faces come out in."""
    transforms, probs = trimesh.poses.compute_stable_poses(mesh, center_mass=com, sigma=0.0, n_samples=1)
    poses = [
        {"probability": round(float(p), 6) + 0.0, "transform": (np.round(t, 9) + 0.0).tolist()}
        for t, p in zip(transforms, probs, strict=True)
    ]  # + 0.0 turns -0.0 into 0.0
    poses.sort(key=lambda pose: (-pose["probability"], np.ravel(pose["transform"]).tolist()))
    kept = [pose for pose in poses if pose["probability"] >= MIN_POSE_PROBABILITY][:MAX_STABLE_POSES]
    return kept or poses[:1]


def _hulls(raw: list[tuple[np.ndarray, np.ndarray]]) -> list[trimesh.Trimesh]:
    """CoACD's parts (`decompose.CoacdRun`: each run in a child process, so that a native crash
    raises CoacdFailed here) as convex hulls, which is how MuJoCo collides meshes, in a fixed order
    (by centroid). A part of fewer than 4 distinct points (CoACD leaves a stray triangle now and
    then) bounds no volume and has no hull: it is left out, and a run of nothing else failed."""
    solid = [(v, f) for v, f in raw if len(np.unique(np.asarray(v, dtype=float), axis=0)) >= 4]
    if not solid:
        raise CoacdFailed(f"none of its {len(raw)} parts bounds a volume")
    parts = [trimesh.Trimesh(v, f, process=True).convex_hull for v, f in solid]
    return sorted(parts, key=lambda p: tuple(np.round(p.centroid, 6)))


def decompose_mesh(
    mesh: trimesh.Trimesh, source: str = "mesh", schedule=COACD_SCHEDULE, options: dict | None = None,
    parallel: int = 1,
) -> tuple[list[trimesh.Trimesh], dict[str, Any]]:
    """Convex parts following `schedule`, and how well they fit (the last try if none fits); `options`
    are further CoACD keywords (imports use decompose.IMPORT_SCHEDULE and IMPORT_OPTIONS).

    The tries are judged in the schedule's order, the first that fits wins; with `parallel` > 1 the
    next tries already run beside the one being waited for (up to `parallel` CoACD children at
    once) and those not needed are stopped: the same parts (each run is seeded), sooner when the
    first tries do not fit, for a user waiting on an import with idle cores. The last try (the
    finest, and the slowest: a 4.8k-face CAD part's three took 3.1, 5.2 and 11.3 s) starts beside
    the first, so that where none fits, the slowest never waits for a core.

    A CoACD run that crashes moves on to the next threshold; if every run crashes, a convex object
    (hull within EXCESS_MAX of its volume) falls back to its hull, anything else is an InputError."""
    best, failures = None, []
    vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    schedule = list(schedule)
    count = len(schedule)
    parallel = max(1, parallel)
    # launch order: with two or more at once, tries 0..i are running by the time try i is judged
    launch = [0, count - 1, *range(1, count - 1)] if parallel > 1 and count > 2 else list(range(count))
    runs: dict[int, CoacdRun] = {}
    try:
        for index, (threshold, max_hulls) in enumerate(schedule):
            while launch and len(runs) < parallel:
                started = launch.pop(0)
                runs[started] = CoacdRun(vertices, faces, *schedule[started], options=options)
            run = runs.pop(index)
            try:
                parts = _hulls(run.parts())
            except CoacdFailed as exc:
                failures.append(f"threshold {threshold:g}: {exc}")
                continue
            quality = decomposition_quality(mesh, parts)
            best = parts, {"method": "coacd", "threshold": threshold, "max_convex_hull": max_hulls, **quality}
            if quality["excess"] <= EXCESS_MAX and quality["coverage"] >= COVERAGE_MIN:
                break
    finally:
        for run in runs.values():
            run.cancel()
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
    coacd_parallel: int = 1,
    reuse_parts: bool = False,
    cavities: trimesh.Trimesh | None = None,
    keep_above_cap: bool = False,
    assembly: bool = False,
) -> ObjectRecord:
    """Build an object directory at `out_dir` (replaced atomically) and return its record.

    An existing `out_dir` is replaced only if it is an object suctionbench wrote (or empty): one
    holding anything else is an InputError naming it, before any work and again just before the
    replacement. A write that fails (a full disk, no permission) is an InputError naming the file
    or folder that could not be written, and leaves nothing: no temporary folder, and none of the
    parent folders it created.

    `coacd`: (schedule, options) for the convex decomposition instead of COACD_SCHEDULE and CoACD's
    defaults (see `decompose_mesh`); `coacd_parallel`: how many of its tries may run at once.
    `reuse_parts`: where `out_dir` already holds this very mesh (same
    geometry hash) with its convex parts, keep those parts instead of running CoACD again (a rebuild
    that changes only masses; CoACD is deterministic, so a full rebuild gives the same parts).
    `cavities`: sealed cavities inside the mesh, facing inwards (`objects.repair.Solid.cavities`): the
    mass, centre of mass and inertia are the material's (mesh and cavities together), the volume and
    density the material's; surface, stable poses' hull and convex parts are the mesh's.
    `keep_above_cap`: keep a mass above the default cup's cap (`object_mass`), named in the record's
    ``params["warnings"]``, instead of refusing it. `assembly`: the mesh may be several closed
    bodies, separate pieces of one rigid body (`objects.repair`, ASSEMBLY)."""
    out_dir = Path(out_dir)
    check_replaceable_objects([out_dir])  # before the work: minutes of CoACD for nothing otherwise
    mesh = prepare_mesh(mesh, source=source if source != "generated" else spec.name, assembly=assembly)
    material = mesh if cavities is None else trimesh.util.concatenate([mesh, cavities])
    model, props = object_mass(material, spec, mass, keep_above_cap=keep_above_cap)
    params = spec.params
    if props.mass > MASS_CAP:
        params = {**params, "warnings": [*params.get("warnings", []), above_cap_warning(props.mass)]}
    density = props.mass / float(material.volume)
    record = ObjectRecord(
        name=spec.name,
        set=spec.set,
        generator=spec.generator,
        params=params,
        description=spec.description,
        source=source,
        units=units,
        scale=mesh_scale(units, scale),
        density=round(density, 6),
        mass=round(props.mass, 9),
        com=(np.round(props.com, 9) + 0.0).tolist(),
        inertia=(np.round(props.inertia, 12) + 0.0).tolist(),
        friction=spec.friction,
        volume=round(float(material.volume), 12),
        watertight=True,
        faces=len(mesh.faces),
        extents=np.round(mesh.extents, 9).tolist(),
        geometry_hash=geometry_hash(mesh),
        stable_poses=stable_poses(mesh, props.com),
        parts=[],
        mass_source=model.source,
        mass_model=model.to_dict() if mass is None else {},
    )
    kept = _reusable_parts(Path(out_dir), record.geometry_hash) if decompose and reuse_parts else None
    if kept is not None:
        part_bytes, record.decomposition = kept
    elif decompose:  # before any folder exists: a failure leaves nothing behind
        schedule, options = coacd or (COACD_SCHEDULE, None)
        parts, record.decomposition = decompose_mesh(mesh, source, schedule, options, parallel=coacd_parallel)
        part_bytes = [part.export(file_type="stl") for part in parts]
    files = {"mesh.stl": mesh.export(file_type="stl")}
    if decompose:
        record.parts = [f"parts/part_{i:03d}.stl" for i in range(len(part_bytes))]
        files.update(zip(record.parts, part_bytes, strict=True))
    files["object.toml"] = tomli_w.dumps(record.to_toml()).encode()
    write_object_dir(out_dir, files)
    record.directory = out_dir
    return record


def _reusable_parts(out_dir: Path, geometry: str) -> tuple[list[bytes], dict[str, Any]] | None:
    """The convex parts (file contents) and decomposition record of the object built at `out_dir`,
    if it is the same mesh (geometry hash) and all its parts are there; None otherwise."""
    try:
        old = ObjectRecord.load(out_dir)
        if old.geometry_hash != geometry or not old.parts or not old.decomposition:
            return None
        return [(out_dir / p).read_bytes() for p in old.parts], old.decomposition
    except (InputError, TypeError, OSError):
        return None


def object_mass(mesh: trimesh.Trimesh, spec: ObjectSpec, mass: float | None = None, *,
                keep_above_cap: bool = False) -> tuple[MassModel, MassProperties]:
    """The mass model an object is built with and its mass properties: a given `mass` (kg) spread
    uniformly, else the spec's model (objects.mass) or the first of its lighter variants under the
    cap (MASS_CAP). Above the cap: InputError (the object sets, whose objects the default cup must
    be able to carry), or with `keep_above_cap` kept (imports: a given mass as given, else the
    lightest variant; `build_object` records the warning). A model lighter than MIN_MASS is
    scaled up to it."""
    if mass is not None:
        if not (isinstance(mass, int | float) and np.isfinite(mass) and mass > 0):
            raise InputError(f"mass {mass!r}: must be a positive number of kilograms")
        if mass > MASS_CAP and not keep_above_cap:
            raise InputError(over_cap_message(spec.name, float(mass)))
        model = MassModel("given with the object (--mass), spread uniformly", density=float(mass) / float(mesh.volume))
        return model, mass_properties(mesh, model)
    model, props = resolve_mass(mesh, spec.mass_model(), spec.name, spec.params, keep_above_cap=keep_above_cap)
    if props.mass < MIN_MASS:
        factor = MIN_MASS / props.mass
        note = f"; {props.mass * 1000:.2g} g raised to the {MIN_MASS * 1000:g} g floor of simulated objects"
        props = MassProperties(MIN_MASS, props.com, props.inertia * factor)
        model = MassModel(model.source + note, density=model.density * factor, shell=model.shell * factor,
                          contents=model.contents * factor, contents_volume=model.contents_volume, liquid=model.liquid,
                          part=model.part, part_density=model.part_density * factor)
    return model, props


def write_object_dir(out_dir: Path, files: dict[str, bytes]) -> None:
    """Write `files` (path inside the object directory -> content) as the object directory
    `out_dir`, all or nothing: into a temporary sibling first, which then takes the place of
    `out_dir` (`suctionbench.io.publish_dir`) if that is still an object suctionbench wrote.

    A file system that refuses a write (full, read-only, no permission) is an InputError naming
    the file or folder of `out_dir` that could not be written; the temporary folder and the parent
    folders this call created are removed, so nothing is left behind."""
    out_dir = Path(out_dir)
    created = [p for p in (out_dir.parent, *out_dir.parent.parents) if not p.exists()]  # deepest first
    staging, writing = None, out_dir.parent
    try:
        out_dir.parent.mkdir(parents=True, exist_ok=True)
        writing = out_dir
        staging = staging_dir(out_dir)
        for name, data in files.items():
            writing = out_dir / name
            (staging / name).parent.mkdir(parents=True, exist_ok=True)
            (staging / name).write_bytes(data)
        writing = out_dir
        check_replaceable_objects([out_dir])  # again: a user's file may have appeared meanwhile
        publish_dir(staging, out_dir)
    except OSError as exc:
        if exc.errno not in WRITE_ERRNOS:
            raise
        failed = Path(exc.filename) if exc.filename else writing  # a failed write() carries no file name
        if staging is not None and failed.is_relative_to(staging):  # name the output, not the temporary folder
            failed = out_dir / failed.relative_to(staging)
        raise InputError(f"output '{failed}': cannot write there ({os_error_reason(exc)})") from None
    except InputError as exc:
        if staging is not None:  # name the output, not its temporary folder
            raise InputError(str(exc).replace(str(staging), str(out_dir))) from None
        raise
    finally:
        if staging is not None:
            shutil.rmtree(staging, ignore_errors=True)
        if not out_dir.is_dir():
            for parent in created:  # deepest first; only empty ones (another writer may have filled one)
                try:
                    os.rmdir(parent)
                except OSError:
                    break
