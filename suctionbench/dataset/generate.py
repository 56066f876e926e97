"""Dex-Net-style dataset generation (paper: "Dex-Net 3.0 Dataset", "Environment Model").

Per object: grasp candidates uniform on the surface with inward normals; for each of its most
probable stable poses, the robust label of every candidate (gravity rotated into that pose);
then images: a stable pose (uniform), a planar pose U([-0.1, 0.1]^2 x [0, 2pi)), a camera pose
from the paper's spherical distribution, a rendered depth image with the noise model
y = alpha y_hat + eps, and for every grasp visible at its pixel a 32 x 32 thumbnail, its pose
vector and its label.

Work is split into deterministic units, one per object with a fixed datapoint quota and its own
random stream (seed, unit index), so any engine (a local process pool or Ray) and any
interruption produce the same data. Units are written atomically to units/; shards in the Dex-Net
tensor layout are assembled from them in order.
"""

from __future__ import annotations

import hashlib
import json
import math
import threading
import time
from collections import OrderedDict
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from suctionbench.config import STANDARD_GRAVITY, LabelConfig, to_dict
from suctionbench.dataset.storage import FIELDS, SPLIT_DIR, TENSOR_DIR
from suctionbench.errors import InputError
from suctionbench.io import atomic_path, bytes_under
from suctionbench.sensing.noise import DepthNoiseConfig, check_noise_model
from suctionbench.sensing.thumbnails import THUMBNAIL_GQCNN, ThumbnailConfig

if TYPE_CHECKING:
    from suctionbench.sensing.camera import CameraIntrinsics

OBJECT_CLEARANCE = 1e-3
"""The object context's object pixels: those whose point in the clean render lies more than this
(m) above the table (exactly z = 0 there), i.e. the renderer's object mask, as the simulated
observation's segmentation gives the policies. Their points come from the noisy image; a height
threshold on the noisy image would not do (its per-image depth scale lifts the table by up to
~1 cm)."""

UNIT_FIELDS = tuple(FIELDS)
"""Per-datapoint arrays of a unit: exactly the fields of a shard (dataset.storage.FIELDS)."""

MAX_IMAGES_PER_UNIT = 100_000
"""Image ids are unit index x this + image number: unique without coordination."""


@dataclass(frozen=True)
class GenerationConfig:
    """Everything that determines a dataset (two runs with equal configs write equal data)."""

    datapoints: int
    """Total number of datapoints."""

    seed: int = 0
    """Seed of every random draw (each unit draws from its own stream (seed, unit))."""

    grasps_per_object: int = 200
    """Grasp candidates sampled on each object's surface."""

    stable_poses: int = 5
    """The most probable stable poses of each object that are used (uniformly, as in the paper)."""

    planar_range: float = 0.1
    """Half-width (m) of the uniform planar translation of the object on the table."""

    max_approach_angle: float = math.radians(80.0)
    """Grasps whose approach is further than this from straight down are not recorded."""

    smoothed_approach_fraction: float = 0.5
    """Share of the candidates whose approach is the surface normal averaged over
    `approach_smoothing_radius` (as image-based policies estimate it from depth) instead of the
    exact face normal. Without them the network never sees, say, a straight-down approach on a
    prism's ridge - the grasp every depth-normal sampler proposes there. Labels are always
    computed for the approach actually recorded."""

    approach_smoothing_radius: float = 0.003
    """Radius (m) of that average: about the support of the policies' normal estimate (1 px
    Gaussian + central differences, ~3 px = ~3 mm at 0.6 m)."""

    max_images_per_object: int = 400
    """An object whose visible grasps cannot fill its quota stops after this many images."""

    grasps_per_image: int = 0
    """At most this many of an image's visible candidates are recorded, a uniform random draw of
    them; 0: all of them. With many candidates per object (a small set, whose few robust grasps
    only a dense sampling finds) it keeps the images many: without it an image records every one
    of its thousands of visible candidates and the object's quota is spent in a few views."""

    datapoints_per_shard: int = 1000
    """Datapoints per tensor file (Dex-Net: 1000)."""

    label_threshold: float = 0.2
    """Robust label above which a datapoint counts as positive (Dex-Net 3.0 training threshold)."""

    noise: DepthNoiseConfig = field(default_factory=DepthNoiseConfig)
    """Parameters of the paper's depth-image noise model (`noise_model` "paper")."""

    noise_model: str = "paper"
    """What noise the rendered images get (`sensing.noise.NOISE_MODELS`): "paper", Dex-Net's
    y = alpha y_hat + eps (`noise`: a ~3 % scale error and a correlated ~4 mm field, an augmentation
    harsher than a calibrated sensor), or "sensor", the simulated camera's own per-pixel axial noise
    (`sensing.noise.AxialNoiseConfig`, ~1.3 mm at 0.6 m): the images the benchmark's robot sees,
    or "none" (an ideal sensor, the same seed's "sensor" dataset but for the images)."""

    label: LabelConfig = field(default_factory=LabelConfig.for_episode)
    """Cup, seal, perturbation and metric configuration of the labels. By default the labels the
    benchmark scores a pick by (`LabelConfig.for_episode`: the pick's inertial load, its arrivals
    and the touch-down's press), so a network learns the verdict it is judged by; the paper's
    quasi-static model is `LabelConfig(cup=...)` (``generate --load static``)."""

    scene: str = "table"
    """"table": one object per image in a stable pose on the table (the paper's); "bin": a cluttered
    pick bin per unit (`suctionbench.dataset.clutter`)."""

    bin_objects: tuple[int, int] = (5, 10)
    """Scene "bin": smallest and largest object count of a bin (the bin tasks' range)."""

    bin_images: int = 4
    """Scene "bin": images per bin, one object taken out between them."""

    bin_datapoints: int = 1000
    """Scene "bin": datapoints per bin (the unit's quota)."""

    proposals: str | None = None
    """A trained model's directory: on every image its dense policy's best grasps
    (`dataset.proposals`) are labelled and recorded first, before the uniform surface grasps fill
    the rest of the image's share (grasp id -1 - rank). None: uniform surface grasps only."""

    proposals_per_image: int = 8
    """With `proposals`: how many of the policy's best grasps (at least 1 cm apart) per image."""

    thumbnail: ThumbnailConfig = THUMBNAIL_GQCNN
    """The grasp thumbnail's geometry and sampling (`sensing.thumbnails.ThumbnailConfig`; gqcnn's
    96 px crop at 32 x 32, point samples): a model trained on the dataset reads its grasps the same
    way (its card records this, `GQCNNModel.thumbnail`)."""


@dataclass(frozen=True)
class Unit:
    """One deterministic piece of work: `quota` datapoints from object number `index` (one unit
    per object)."""

    index: int
    quota: int


SCENES = ("table", "bin")
"""What `generate --scene` accepts."""


def plan_units(num_objects: int, datapoints: int, config: GenerationConfig | None = None) -> list[Unit]:
    """Split the datapoints as evenly as possible over the objects (one unit each), or, for the
    "bin" scene, over bins of `bin_datapoints` each (one unit per bin)."""
    if num_objects < 1:
        raise InputError("generate: no objects to generate from")
    if config is not None and config.scene == "bin":
        bins = max(1, math.ceil(datapoints / config.bin_datapoints))
        base, extra = divmod(datapoints, bins)
        return [Unit(i, base + (1 if i < extra else 0)) for i in range(bins)]
    base, extra = divmod(datapoints, num_objects)
    return [Unit(i, base + (1 if i < extra else 0)) for i in range(num_objects) if base or i < extra]


def config_fingerprint(config: GenerationConfig, camera: dict[str, Any], objects: list[str]) -> str:
    """Hash of everything that determines the data: a resumed run must match it exactly (with
    `proposals`, the proposing model's weights too)."""
    from suctionbench.dataset.proposals import model_fingerprint

    settings = to_dict(config)
    what: dict[str, Any] = {"config": settings, "camera": camera, "objects": objects}
    if config.proposals is None:  # datasets from before proposals existed keep their fingerprint
        del settings["proposals"], settings["proposals_per_image"]
    else:
        what["proposal_weights"] = model_fingerprint(config.proposals)
    if config.noise_model == "paper":  # and those from before the noise model was a choice
        del settings["noise_model"]
    if config.thumbnail == THUMBNAIL_GQCNN:  # and before the thumbnail's sampling was
        del settings["thumbnail"]
    if config.grasps_per_image == 0:  # and before an image's share was capped
        del settings["grasps_per_image"]
    blob = json.dumps(what, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def generate_unit(unit: Unit, object_dir: str, camera: str, config: GenerationConfig) -> dict[str, np.ndarray]:
    """Generate one unit's datapoints (runs in a worker process or a Ray task)."""
    from suctionbench.contact import SuctionLabeller
    from suctionbench.dataset.render import TableScene
    from suctionbench.geometry.sampling import sample_surface_grasps, smoothed_approaches
    from suctionbench.objects.build import ObjectRecord
    from suctionbench.objects.liquid import Liquid, com_at_rest
    from suctionbench.sensing.camera import resolve_camera
    from suctionbench.sensing.camera_pose import CameraPoseConfig, sample_camera_pose
    from suctionbench.sensing.noise import noisy_image
    from suctionbench.sensing.thumbnails import (
        extract_context_thumbnails,
        pose_vector,
        project_grasps,
        sample_thumbnails,
        visible_mask,
    )

    rng = np.random.default_rng((config.seed, unit.index))
    record = ObjectRecord.load(Path(object_dir))
    intrinsics = resolve_camera(camera)
    mesh = record.mesh()
    points, approaches = sample_surface_grasps(mesh, config.grasps_per_object, rng)
    if config.smoothed_approach_fraction > 0.0:
        smoothed = smoothed_approaches(mesh, points, approaches, config.approach_smoothing_radius, rng)
        use = rng.random(len(points)) < config.smoothed_approach_fraction
        approaches = np.where(use[:, None], smoothed, approaches)
    poses = [np.asarray(p["transform"]) for p in record.stable_poses[: config.stable_poses]]
    liquid = Liquid.of(record, mesh)
    labellers: dict[int, Any] = {}
    labels: dict[int, Any] = {}

    def labeller_in_pose(s: int) -> Any:
        """The labeller of stable pose s (gravity rotated into the pose)."""
        if s not in labellers:
            gravity = poses[s][:3, :3].T @ np.array([0.0, 0.0, -STANDARD_GRAVITY])
            com = com_at_rest(record, poses[s][:3, :3], liquid)  # a liquid levels in the pose
            labellers[s] = SuctionLabeller(mesh, config.label, mass=record.mass, com=com, gravity=gravity)
        return labellers[s]

    def labels_in_pose(s: int) -> Any:
        """Robust labels of all candidates in stable pose s, computed on first use: each pose has
        its own seed, so laziness changes no value."""
        if s not in labels:
            label_seed = int(np.random.SeedSequence((config.seed, unit.index, s)).generate_state(1)[0])
            labels[s] = labeller_in_pose(s).label(points, approaches, label_seed, metrics=("wr", "rwr"))
        return labels[s]

    proposer = None
    if config.proposals is not None:
        from suctionbench.dataset.proposals import proposer as cached_proposer

        proposer = cached_proposer(config.proposals, config.proposals_per_image)
    camera_config = CameraPoseConfig().for_camera(intrinsics)
    out: dict[str, list[np.ndarray]] = {name: [] for name in UNIT_FIELDS}

    def record_grasps(noisy: np.ndarray, depth: np.ndarray, mask: np.ndarray, camera_pose: np.ndarray, image: int,
                      s: int, p_world: np.ndarray, v_world: np.ndarray, v_cam: np.ndarray, pixels: np.ndarray,
                      depths: np.ndarray, angles: np.ndarray, lab: Any, ids: np.ndarray) -> None:
        """Append the datapoints of grasps seen on one image (`mask`: the object's pixels): their
        labels `lab` (rwr, seal flags, wr; one row per grasp) and candidate ids `ids`."""
        rwr, seal, wr = lab
        out["depth_ims_tf_table"].append(sample_thumbnails(noisy, pixels, angles, config.thumbnail)[..., None]
                                         .astype(np.float32))
        context = extract_context_thumbnails(noisy, pixels, angles)
        out["context_ims_tf_table"].append(context[..., None].astype(np.float32))
        out["object_context"].append(image_object_context(intrinsics, depth, noisy, camera_pose, pixels, p_world,
                                                          v_world, object_mask=mask))
        out["hand_poses"].append(np.column_stack([pixels[:, 1], pixels[:, 0], pose_vector(depths, v_world), v_cam])
                                 .astype(np.float32))
        out["robust_suction_wrench_resistance"].append(rwr.astype(np.float32))
        out["object_labels"].append(np.full(len(ids), unit.index, np.int32))
        out["pose_labels"].append(np.full(len(ids), s, np.int32))
        out["image_labels"].append(np.full(len(ids), unit.index * MAX_IMAGES_PER_UNIT + image, np.int32))
        out["grasp_labels"].append(ids.astype(np.int32))
        out["seal_flags"].append(seal.astype(np.uint8))
        out["wrench_resistance"].append(wr.astype(np.uint8))

    count = 0
    with TableScene(record, intrinsics) as scene:
        for image in range(config.max_images_per_object):
            if count >= unit.quota:
                break
            s = int(rng.integers(len(poses)))
            x, y = rng.uniform(-config.planar_range, config.planar_range, 2)
            yaw = rng.uniform(0.0, 2.0 * math.pi)
            planar = np.eye(4)
            planar[:3, :3] = [[math.cos(yaw), -math.sin(yaw), 0], [math.sin(yaw), math.cos(yaw), 0], [0, 0, 1]]
            planar[:3, 3] = [x, y, 0.0]
            object_pose = planar @ poses[s]
            camera_pose = sample_camera_pose(rng, np.zeros(3), camera_config)
            depth = scene.render(object_pose, camera_pose)
            noisy = noisy_image(depth, rng, config.noise_model, config.noise)
            rot, origin = camera_pose[:3, :3], camera_pose[:3, 3]
            mask = rendered_object(intrinsics, depth, camera_pose)
            if proposer is not None:  # the policy's own best grasps first (module dataset.proposals)
                q_cam, a_cam = proposer.propose(noisy, mask, intrinsics, camera_pose,
                                                np.random.default_rng((config.seed, unit.index, image, 1)))
                q_world, a_world = q_cam @ rot.T + origin, a_cam @ rot.T
                steep = np.flatnonzero(-a_world[:, 2] >= math.cos(config.max_approach_angle))[: unit.quota - count]
                if len(steep):
                    q_cam, a_cam, q_world, a_world = q_cam[steep], a_cam[steep], q_world[steep], a_world[steep]
                    at, depths, angles = project_grasps(q_cam, a_cam, intrinsics)
                    turn, shift = object_pose[:3, :3], object_pose[:3, 3]
                    seed = int(np.random.SeedSequence((config.seed, unit.index, image, 2)).generate_state(1)[0])
                    lab = labeller_in_pose(s).label((q_world - shift) @ turn, a_world @ turn, seed,
                                                    metrics=("wr", "rwr"))
                    record_grasps(noisy, depth, mask, camera_pose, image, s, q_world, a_world, a_cam, at, depths,
                                  angles, (lab.rwr, lab.seal.seal, lab.wr), -1 - np.arange(len(steep)))
                    count += len(steep)
            p_world = points @ object_pose[:3, :3].T + object_pose[:3, 3]
            v_world = approaches @ object_pose[:3, :3].T
            p_cam, v_cam = (p_world - origin) @ rot, v_world @ rot
            pixels, depths, angles = project_grasps(p_cam, v_cam, intrinsics)
            keep = visible_mask(pixels, depths, depth) & (-v_world[:, 2] >= math.cos(config.max_approach_angle))
            idx = np.flatnonzero(keep)
            if 0 < config.grasps_per_image < len(idx):
                idx = np.sort(rng.choice(idx, config.grasps_per_image, replace=False))
            idx = idx[: unit.quota - count]
            if len(idx) == 0:
                continue
            lab = labels_in_pose(s)
            record_grasps(noisy, depth, mask, camera_pose, image, s, p_world[idx], v_world[idx], v_cam[idx],
                          pixels[idx], depths[idx], angles[idx], (lab.rwr[idx], lab.seal.seal[idx], lab.wr[idx]), idx)
            count += len(idx)
    return {name: np.concatenate(parts) if parts else _empty(name) for name, parts in out.items()}


def image_object_context(intrinsics: CameraIntrinsics, depth: np.ndarray, noisy: np.ndarray, camera_pose: np.ndarray,
                         pixels: np.ndarray, exact_points: np.ndarray, approaches: np.ndarray,
                         object_mask: np.ndarray | None = None) -> np.ndarray:
    """The object context (N, 6) of grasps at `pixels` (N, 2) = (u, v) along world `approaches`, as a
    policy planning on the `noisy` image computes it (`policies.gqcnn.network_poses`): the object's
    points and the grasp points both from the noisy image, in the world frame. The object's pixels
    are those whose clean `depth` lies `OBJECT_CLEARANCE` above the table (the simulator's mask).

    Each grasp point is the noisy image's point at its pixel, rounded as policies plan on whole
    pixels (the mesh point, `exact_points`, where that pixel has no depth). Taken from the mesh
    instead, the grasp point would miss the image's depth scale error (~3 % of the depth: 2 cm at
    0.6 m), which a policy's grasp point shares with its object points. `object_mask`: the object's
    pixels where the renderer gives them (a cluttered scene's instance mask), instead of the height
    above the table."""
    from suctionbench.sensing.object_context import object_context

    rot, origin = camera_pose[:3, :3], camera_pose[:3, 3]
    if object_mask is None:
        object_mask = rendered_object(intrinsics, depth, camera_pose)
    mask = (noisy > 0) & object_mask
    cloud = intrinsics.deproject(noisy)  # camera frame: only the object's and the grasps' pixels are moved
    cols = np.clip(np.rint(pixels[:, 0]).astype(np.intp), 0, noisy.shape[1] - 1)
    rows = np.clip(np.rint(pixels[:, 1]).astype(np.intp), 0, noisy.shape[0] - 1)
    grasps = np.where((noisy[rows, cols] > 0)[:, None], cloud[rows, cols] @ rot.T + origin, exact_points)
    return object_context(cloud[mask] @ rot.T + origin, grasps, approaches)


def rendered_object(intrinsics: CameraIntrinsics, depth: np.ndarray, camera_pose: np.ndarray) -> np.ndarray:
    """The object's pixels (H, W) bool in a clean table render: its points more than
    `OBJECT_CLEARANCE` above the table (z = 0), as the simulator's segmentation gives them."""
    rot, origin = camera_pose[:3, :3], camera_pose[:3, 3]
    return (intrinsics.deproject(depth) @ rot[2] + origin[2]) > OBJECT_CLEARANCE


def _empty(name: str) -> np.ndarray:
    """A zero-length array of the field's dtype and per-datapoint shape."""
    spec = FIELDS[name]
    return np.zeros((0, *spec.shape), spec.dtype)


# -- unit files (resume) ---------------------------------------------------------------------------


def unit_path(directory: Path, index: int) -> Path:
    return Path(directory) / "units" / f"unit_{index:05d}.npz"


def save_unit(directory: Path, index: int, arrays: dict[str, np.ndarray]) -> None:
    """Write a finished unit atomically (a killed run never leaves a partial unit)."""
    with atomic_path(unit_path(directory, index)) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, **arrays)


def load_unit(directory: Path, index: int, fields: tuple[str, ...] = UNIT_FIELDS) -> dict[str, np.ndarray] | None:
    """A unit file's arrays (only `fields`: an ``.npz`` reads just the members asked for), or None
    if missing; raises InputError if it is corrupt."""
    path = unit_path(directory, index)
    if not path.exists():
        return None
    try:
        with np.load(path) as data:
            arrays = {name: data[name] for name in fields}
    except Exception as exc:  # zip/pickle/key errors all mean the same: not a valid unit
        raise InputError(f"unit file '{path}': corrupt ({type(exc).__name__})") from None
    lengths = {len(a) for a in arrays.values()}
    if len(lengths) != 1:
        raise InputError(f"unit file '{path}': corrupt (fields of different lengths)")
    return arrays


# -- engines ---------------------------------------------------------------------------------------


def run_units(
    units: list[Unit], object_dirs: list[str], camera: str, config: GenerationConfig, *,
    engine: str, workers: int, address: str | None,
) -> Iterator[tuple[Unit, dict[str, np.ndarray]]]:
    """Yield (unit, arrays) in unit order, computed by the chosen engine (suctionbench.parallel)."""
    from suctionbench.parallel import map_ordered

    if config.scene == "bin":
        from suctionbench.dataset.clutter import generate_bin_unit

        fn, args = generate_bin_unit, [(u, object_dirs, camera, config) for u in units]
    else:
        fn, args = generate_unit, [(u, object_dirs[u.index], camera, config) for u in units]
    results = map_ordered(fn, args, engine=engine, workers=workers, address=address)
    yield from zip(units, results, strict=True)


def generate_dataset(
    out: Path, object_dirs: list[str], object_keys: list[str], camera: str, config: GenerationConfig, *,
    engine: str = "local", workers: int = 1, address: str | None = None, resume: bool = False,
    overwrite: bool = False, progress: Callable[[int], None] | None = None, holdout_like: Path | None = None,
) -> dict[str, Any]:
    """Generate (or resume) a dataset in `out`; returns its card.

    With `holdout_like` (another dataset of the same objects, or a model trained on one) the
    object-wise split holds out that dataset's held-out objects instead of drawing its own
    (`storage.write_splits`), so the two datasets train one model without leaking a validation
    object; the card records it.

    On resume, finished units are reused after checking them (a corrupt unit is reported and
    generated again) and every shard is rebuilt from the units, so a damaged shard is never
    trusted; problems found in the old shards are reported in the card.
    """
    from suctionbench import __version__
    from suctionbench.dataset.storage import (
        DatasetReader,
        DatasetWriter,
        read_card,
        write_card,
        write_splits,
    )
    from suctionbench.parallel import check_engine
    from suctionbench.sensing.camera import resolve_camera

    check_engine(engine)
    if config.scene not in SCENES:  # before anything is written
        raise InputError(f"--scene '{config.scene}': unknown (known: {', '.join(SCENES)})")
    if config.grasps_per_image and config.scene != "table":
        raise InputError(f"--grasps-per-image with --scene {config.scene}: the cap applies to table scenes only "
                         f"(a bin's images share its fixed quota)")
    if config.max_images_per_object != GenerationConfig.max_images_per_object and config.scene != "table":
        raise InputError(f"--max-images-per-object with --scene {config.scene}: it bounds a table scene's object "
                         f"(a bin's images are set by its quota)")
    if not 1 <= config.max_images_per_object <= MAX_IMAGES_PER_UNIT:  # image ids number MAX_IMAGES_PER_UNIT a unit
        raise InputError(f"--max-images-per-object {config.max_images_per_object}: must be 1 - {MAX_IMAGES_PER_UNIT:,}")
    if config.datapoints < 1:
        raise InputError(f"--datapoints {config.datapoints}: must be at least 1")
    check_noise_model(config.noise_model)
    out = Path(out)
    held_out = None
    if holdout_like is not None:  # read and checked before anything is written
        if Path(holdout_like).resolve() == out.resolve():
            raise InputError(f"--holdout-like '{holdout_like}': is --out itself")
        keys, source_fingerprint = _holdout_source(Path(holdout_like))
        index = {key: i for i, key in enumerate(object_keys)}
        unknown = [key for key in keys if key not in index]
        if unknown:
            raise InputError(f"--holdout-like '{holdout_like}': {len(unknown)} of its held-out objects are not among "
                             f"--objects (e.g. '{unknown[0]}'): not the same corpus")
        held_out = np.array(sorted(index[key] for key in keys), dtype=np.int64)
    camera_dict = to_dict(resolve_camera(camera))
    fingerprint = config_fingerprint(config, camera_dict, object_keys)
    if out.exists() and any(out.iterdir()):
        try:
            existing = read_card(out).get("fingerprint")
        except InputError:
            existing = None
        if overwrite:
            from suctionbench.dataset.verify import remove_dataset

            remove_dataset(out)  # only a dataset suctionbench wrote; refuses otherwise
        elif not resume:
            raise InputError(f"output '{out}' exists (pass --resume to continue it or --overwrite to replace it)")
        elif existing not in (None, fingerprint):
            raise InputError(f"output '{out}' holds a dataset with a different configuration (use --overwrite)")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"output '{out}': cannot create it ({exc.strerror})") from None
    shard_problems = DatasetReader(out).verify() if (out / "tensors").is_dir() else []
    runs = _earlier_runs(out) if resume else []
    card: dict[str, Any] = {
        "fingerprint": fingerprint, "suctionbench_version": __version__, "config": to_dict(config),
        "camera": camera_dict, "objects": object_keys, "status": "generating", "generation_runs": runs,
    }
    write_card(out, card, datapoints_per_shard=config.datapoints_per_shard)

    units = plan_units(len(object_dirs), config.datapoints, config)
    todo, corrupt = [], []
    for unit in units:
        try:
            done = load_unit(out, unit.index) is not None
        except InputError as exc:
            corrupt.append(str(exc))
            done = False
        if not done:
            todo.append(unit)
        elif progress:
            progress(unit.quota)
    this_run = {"engine": engine, "workers": workers, "units": 0, "datapoints": 0, "seconds": 0.0,
                "units_before": len(units) - len(todo)}
    runs.append(this_run)
    start = time.perf_counter()
    for unit, arrays in run_units(todo, object_dirs, camera, config, engine=engine, workers=workers, address=address):
        save_unit(out, unit.index, arrays)
        this_run["units"] += 1
        this_run["datapoints"] += len(arrays["image_labels"])
        this_run["seconds"] = round(time.perf_counter() - start, 1)
        write_card(out, card, datapoints_per_shard=config.datapoints_per_shard)  # an interrupted run keeps its record
        if progress:
            progress(unit.quota)

    writer = DatasetWriter(out, datapoints_per_shard=config.datapoints_per_shard)
    assemble = time.perf_counter()
    stats = _assemble_shards(out, units, writer, config.datapoints_per_shard, config.label_threshold, max(1, workers))
    write_splits(out, stats.pop("image_ids"), stats.pop("object_ids"), val_fraction=0.2, seed=config.seed,
                 held_out_objects=held_out)
    if holdout_like is not None:
        card["holdout_like"] = {"dataset": str(Path(holdout_like).resolve()), "objects": len(held_out),
                                "fingerprint": source_fingerprint}
    stats["short_units"] = short_units(units, stats.pop("unit_datapoints"), object_keys, config.scene)
    this_run["assembly_seconds"] = round(time.perf_counter() - assemble, 1)
    card.update(stats, status="complete", regenerated_corrupt_units=corrupt, rewritten_shard_problems=shard_problems,
                generation=_generation_summary(runs, len(units), out, stats["datapoints"]))
    write_card(out, card, datapoints_per_shard=config.datapoints_per_shard)
    return card


def _holdout_source(path: Path) -> tuple[list[str], str | None]:
    """The keys of the objects `--holdout-like` names as held out, sorted, and the fingerprint of
    the dataset they were held out of: `path` is a finished dataset (its object-wise val objects)
    or a trained model (the held-out objects its card records, so the GB-sized dataset it came
    from need not be kept). InputError if it is neither or records none."""
    from suctionbench.dataset.storage import held_out_keys, read_card
    from suctionbench.learning.checkpoint import CARD_NAME, read_model_card

    if (path / CARD_NAME).is_file():
        data = read_model_card(path).get("dataset")
        data = data if isinstance(data, dict) else {}
        keys = data.get("held_out_objects")
        if not isinstance(keys, list) or not keys or not all(isinstance(k, str) and k for k in keys):
            raise InputError(f"--holdout-like '{path}': a model whose card lists no held-out objects (trained on an "
                             "image-wise split, or before suctionbench recorded them)")
        return sorted(set(keys)), data.get("fingerprint")
    return held_out_keys(path), read_card(path).get("fingerprint")


def short_units(units: list[Unit], held: list[int], object_keys: list[str], scene: str) -> list[dict[str, Any]]:
    """The units that hold fewer datapoints than their quota, for the card's ``short_units``: an
    object whose visible candidates fill fewer than its quota in `max_images_per_object` images
    stops there, and the dataset is that much smaller than asked (a small set with few candidates
    per image, or a tiny object). Each: the unit, its object's key (table scene), held and quota."""
    return [{"unit": unit.index, "object": object_keys[unit.index] if scene == "table" else None,
             "datapoints": n, "quota": unit.quota}
            for unit, n in zip(units, held, strict=True) if n < unit.quota]


def _earlier_runs(out: Path) -> list[dict[str, Any]]:
    """The record of the runs that generated what `out` already holds (the card's
    ``generation_runs``; empty for a dataset begun before suctionbench kept it)."""
    from suctionbench.dataset.storage import read_card

    try:
        runs = read_card(out).get("generation_runs")
    except InputError:
        return []
    return [dict(r) for r in runs if isinstance(r, dict)] if isinstance(runs, list) else []


def _generation_summary(runs: list[dict[str, Any]], units: int, out: Path, datapoints: int) -> dict[str, Any]:
    """Generation time and size for the card: the recorded runs' wall-clock seconds, datapoints and
    rate, how many units were made before any record (resumed from an older run), and the bytes on
    disk of the shards and splits (not the per-unit files resuming needs)."""
    seconds = sum(float(r.get("seconds", 0.0)) for r in runs)
    made = sum(int(r.get("datapoints", 0)) for r in runs)
    timed_units = sum(int(r.get("units", 0)) for r in runs)
    size = sum(bytes_under(out / sub) for sub in (TENSOR_DIR, SPLIT_DIR))
    return {"recorded_seconds": round(seconds, 1), "recorded_datapoints": made,
            "datapoints_per_s": round(made / seconds, 1) if seconds > 0 else None,
            "untimed_units": units - timed_units, "bytes": size,
            "bytes_per_datapoint": round(size / max(datapoints, 1), 1)}


class _RecentUnits:
    """The last `keep` units the shard writers read, each decompressed once (`_assemble_shards`):
    shards are written in order, so the few in flight read the same one or two units."""

    def __init__(self, out: Path, units: list[Unit], keep: int):
        self.out, self.units, self.keep = out, units, max(1, keep)
        self.loaded: OrderedDict[int, dict[str, np.ndarray]] = OrderedDict()
        self.lock = threading.Lock()

    def get(self, position: int) -> dict[str, np.ndarray]:
        """The arrays of the unit at `position` in `units` (loaded under the lock, so once)."""
        with self.lock:
            if position not in self.loaded:
                self.loaded[position] = load_unit(self.out, self.units[position].index)
                while len(self.loaded) > self.keep:
                    self.loaded.popitem(last=False)
            self.loaded.move_to_end(position)
            return self.loaded[position]


def _assemble_shards(out: Path, units: list[Unit], writer: Any, per_shard: int, threshold: float,
                     threads: int = 1) -> dict[str, Any]:
    """Cut the units, in order, into fixed-size shards, `threads` shards at a time.

    A first pass reads each unit's three small label arrays (an ``.npz`` decompresses only the
    members asked for) to place every unit in the datapoint order; then each shard takes its slice
    of the one to three units it spans and is written on its own (`DatasetWriter` writes shards
    independently; compression and hashing release the GIL, so threads run in parallel). A unit is
    decompressed once for all its shards (`_RecentUnits`): a unit of 120,000 datapoints (a small
    set's object) spans 120 shards, and reading it whole for each made assembly quadratic in the
    unit's size. The shards are the same bytes for any thread count; memory holds at most
    `threads` + 1 units. The returned ``unit_datapoints`` are what each unit holds, in order.
    """
    counts, positives, image_ids, object_ids = [], 0, [], []
    for unit in units:
        labels = load_unit(out, unit.index, ("image_labels", "object_labels", "robust_suction_wrench_resistance"))
        image_ids.append(labels["image_labels"])
        object_ids.append(labels["object_labels"])
        positives += int((labels["robust_suction_wrench_resistance"] > threshold).sum())
        counts.append(len(image_ids[-1]))
    starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    total = int(starts[-1])
    shards = -(-total // per_shard)

    recent = _RecentUnits(out, units, threads + 1)

    def write(shard: int) -> None:
        lo, hi = shard * per_shard, min((shard + 1) * per_shard, total)
        first = int(np.searchsorted(starts, lo, side="right")) - 1  # the unit holding datapoint lo
        last = int(np.searchsorted(starts, hi, side="left"))  # one past the unit holding datapoint hi - 1
        spans = [(recent.get(u), max(lo - int(starts[u]), 0), min(hi, int(starts[u + 1])) - int(starts[u]))
                 for u in range(first, last)]  # (unit, its first and one-past-last datapoint in the shard)
        writer.write_shard(shard, {name: np.concatenate([part[name][a:b] for part, a, b in spans])
                                   for name in UNIT_FIELDS})

    if threads <= 1:
        for shard in range(shards):
            write(shard)
    else:
        with ThreadPoolExecutor(max_workers=threads) as pool:
            for _ in pool.map(write, range(shards)):  # re-raises the first failure
                pass
    return {
        "datapoints": total, "shards": shards, "positive_rate": round(positives / total, 4) if total else 0.0,
        "image_ids": np.concatenate(image_ids) if image_ids else np.zeros(0, np.int32),
        "object_ids": np.concatenate(object_ids) if object_ids else np.zeros(0, np.int32),
        "unit_datapoints": counts,
    }
