"""One validation layer for user input: numbers (range, finiteness, sign), sizes (memory and disk
estimated before anything is allocated or written) and input files (exists, right kind, readable,
not empty). Every check raises `InputError` with one line naming the input and what is wrong.

The CLI applies `OPTION_RULES` to every numeric option of every command by its name
(`suctionbench.cli.common`), so a new command's ``--seed`` or ``--workers`` is checked the same way
as the old ones; library functions call the same checks for the values they receive.
"""

from __future__ import annotations

import math
import os
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from suctionbench.errors import InputError

SEED_MAX = 2**32 - 1
"""Seeds are integers in [0, SEED_MAX]: what numpy's legacy and torch's generators both accept."""

COUNT_MAX = 10**9
"""No count option (trials, datapoints, grasps, epochs, ...) is meaningful beyond a billion; sizes
below it are still checked against the machine's memory and disk by `require_memory` / `require_disk`."""


@dataclass(frozen=True)
class Rule:
    """The valid values of one numeric option."""

    low: float | None = None
    """Smallest valid value (None: unbounded)."""

    high: float | None = None
    """Largest valid value (None: unbounded)."""

    low_open: bool = False
    """The value must be strictly greater than `low`."""

    meaning: str = ""
    """Why the bounds are what they are, appended to the message (e.g. '0 = all cores')."""

    def check(self, value: Any, what: str) -> Any:
        """`value` if it satisfies the rule, else InputError naming `what` (e.g. '--trials')."""
        if value is None:
            return value
        if isinstance(value, float) and not math.isfinite(value):
            raise InputError(f"{what} {value}: must be a finite number")
        note = f" ({self.meaning})" if self.meaning else ""
        if self.low is not None and (value <= self.low if self.low_open else value < self.low):
            bound = f"greater than {_num(self.low)}" if self.low_open else f"at least {_num(self.low)}"
            raise InputError(f"{what} {_num(value)}: must be {bound}{note}")
        if self.high is not None and value > self.high:
            raise InputError(f"{what} {_num(value)}: must be at most {_num(self.high)}{note}")
        return value


def _num(value: float) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


COUNT = Rule(1, COUNT_MAX)
CORES = Rule(0, 4096, meaning="0 = all cores")

OPTION_RULES: dict[str, Rule] = {
    # seeds and parallelism
    "seed": Rule(0, SEED_MAX, meaning="seeds are non-negative integers"),
    "workers": CORES,
    "cores": CORES,
    "load_threads": Rule(1, 4096, meaning="threads reading the dataset's shards"),
    # counts
    "trials": COUNT, "datapoints": COUNT, "grasps": COUNT, "grasps_per_object": COUNT, "samples": COUNT,
    "epochs": COUNT, "batch_size": Rule(1, 2**20), "max_datapoints": COUNT, "max_val_datapoints": COUNT,
    "max_objects": COUNT,
    "count": COUNT, "scenes": COUNT, "attempts": Rule(1, 1000, meaning="attempts timed per bin size"),
    "episodes": COUNT, "memory_grasps": COUNT, "reference_datapoints": COUNT, "reference_grasps": Rule(0, COUNT_MAX),
    "top": Rule(0, COUNT_MAX, meaning="rows of the table; 0 = none"),
    "proposals_per_image": COUNT,
    "grasps_per_image": Rule(0, COUNT_MAX, meaning="0 = every visible candidate"),
    "max_images_per_object": Rule(1, 100_000, meaning="image ids hold 100,000 images an object"),
    "thumbnail_crop": Rule(16, 96, meaning="image pixels the grasp thumbnail's 32 x 32 spans; at most gqcnn's "
                                           "96, the crop a grasp's visibility margin keeps inside the image"),
    "average": Rule(0.0, 1.0, low_open=True, meaning="the moving average's decay per step, below 1"),
    "learning_rate": Rule(0.0, 10.0, low_open=True, meaning="SGD's base step size"),
    # physical quantities and thresholds
    "mass": Rule(0.0, 1000.0, low_open=True, meaning="kg"),
    "threshold": Rule(0.0, 1.0, meaning="a robust wrench resistance"),
    "scale": Rule(),  # finite here; objects.importer checks it is positive, with its own message
    "depth_scale": Rule(0.0, 1.0, low_open=True, meaning="metres per depth unit, e.g. 0.001 for millimetres"),
    "table_height": Rule(-10.0, 10.0, meaning="m"),
}
"""Rule of each numeric CLI option, by parameter name. Every int or float option of every command
must have one (tests/test_fuzz.py checks this); a float option is finite in any case."""

SIZE_OPTIONS = frozenset({"trials", "datapoints", "grasps", "grasps_per_object", "samples", "epochs", "batch_size",
                          "max_datapoints", "max_val_datapoints", "count", "scenes", "episodes", "memory_grasps",
                          "reference_grasps", "reference_datapoints"})
"""The options that set how much work, memory or disk a command takes: named when memory runs out."""


# -- sizes -----------------------------------------------------------------------------------------


def available_memory() -> int:
    """Bytes of memory the machine can still give (MemAvailable), or its physical size if unknown."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return 2**63


def _bytes(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if n < 1024 or unit == "PiB":
            return f"{n:.3g} {unit}"
        n /= 1024
    return f"{n:.3g} B"


def require_memory(nbytes: float, what: str) -> None:
    """InputError if `what` (e.g. '--grasps 1e12 x --samples 50') needs more memory than is available."""
    free = available_memory()
    if nbytes > free:
        raise InputError(f"{what}: needs about {_bytes(nbytes)} of memory, this machine has {_bytes(free)} "
                         "available (use fewer)")


def require_disk(path: str | Path, nbytes: float, what: str) -> None:
    """InputError if writing about `nbytes` under `path` (its nearest existing ancestor's file system)
    would not fit: `what` names the options behind the size."""
    probe = Path(path).absolute()
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    try:
        usage = shutil.disk_usage(probe)
    except OSError:
        return
    free = usage.free
    if usage.total == 0:  # a pseudo file system (/proc): writing there fails on its own, with its reason
        return
    if nbytes > free:
        raise InputError(f"{what}: needs about {_bytes(nbytes)} of disk under '{path}', {_bytes(free)} free "
                         "(use fewer or another directory)")


BYTES_PER_SAMPLE = 100e6 / 8192
"""Peak working memory of one perturbation sample of the robust labeller (its chunks of
`suctionbench.contact.robust.CHUNK_SAMPLES` samples take ~100 MB)."""

BYTES_PER_GRASP = 1024
"""Memory per labelled grasp besides its samples: point, approach, frame, seal and wrench results."""

BYTES_PER_DATAPOINT = 2 * (32 * 32 * 4 + 16 * 4)
"""Disk per generated datapoint, uncompressed: the thumbnail and its pose and labels, once in the
generation units and once in the shards."""

BYTES_PER_TRIAL_LOG = 1.5e6
"""Disk per eval trial: its MCAP log (about 1.3 MB with a 640 x 480 depth image)."""

BYTES_PER_LABEL = 160
"""Disk per grasp of `label --out`: its arrays uncompressed (points, approaches, seal diagnostics,
contact point, four metrics: 132 bytes; the compressed file holds about a third of that)."""

BYTES_PER_OBJECT = 2**20
"""Disk per built object with its convex parts (mesh.stl, parts/, object.toml): the largest of the
evaluation sets takes 0.6 MB."""

BYTES_PER_CORPUS_OBJECT = 2**17
"""Disk per training-corpus object (mesh and object.toml, no convex parts): up to about 70 KB."""


def label_memory(grasps: int, samples: int) -> float:
    """Bytes the robust labeller needs for `grasps` grasps of `samples` samples each."""
    from suctionbench.contact.robust import CHUNK_SAMPLES

    chunk = min(grasps * samples, max(samples, CHUNK_SAMPLES))
    return grasps * (samples + BYTES_PER_GRASP) + chunk * BYTES_PER_SAMPLE


MAX_GRASP_OFFSET = 0.005
"""A grasp point farther than this (m) from the mesh surface is rejected as a typo."""


def grasp_near_surface(mesh: Any, point: Any, what: str, source: str) -> None:
    """InputError if `point` (3,) lies farther than MAX_GRASP_OFFSET from the surface of `mesh`
    (a trimesh in the grasp's frame): one rule for `label --grasp` and `pick --grasp`."""
    import numpy as np

    _, distance, _ = mesh.nearest.on_surface(np.asarray(point, dtype=float)[None])
    if distance[0] > MAX_GRASP_OFFSET:
        raise InputError(f"{what} {np.asarray(point).tolist()} is {distance[0] * 1e3:.1f} mm from the surface of "
                         f"{source} (at most {MAX_GRASP_OFFSET * 1e3:g} mm)")


# -- files -----------------------------------------------------------------------------------------


def input_file(path: str | Path, what: str, *, suffixes: tuple[str, ...] = ()) -> Path:
    """`path` as an existing, readable, non-empty regular file; InputError naming `what` otherwise."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"{what} '{path}': not found")
    if not path.is_file():
        raise InputError(f"{what} '{path}': not a file")
    if suffixes and path.suffix.lower() not in suffixes:
        raise InputError(f"{what} '{path}': expected a {', '.join(suffixes)} file")
    try:
        with open(path, "rb") as fh:
            first = fh.read(1)
    except OSError as exc:
        raise InputError(f"{what} '{path}': cannot read ({exc.strerror})") from None
    if not first:
        raise InputError(f"{what} '{path}': empty file")
    return path


def input_dir(path: str | Path, what: str) -> Path:
    """`path` as an existing directory; InputError naming `what` otherwise."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"{what} '{path}': not found")
    if not path.is_dir():
        raise InputError(f"{what} '{path}': not a directory")
    return path


def _file_in_the_way(path: Path) -> Path | None:
    """The nearest existing ancestor of `path` if it is a file (so `path` cannot be created), else None."""
    for parent in path.absolute().parents:
        if parent.exists():
            return None if parent.is_dir() else parent
    return None


def _check_writable(path: Path, what: str, shown: Path) -> None:
    """InputError if the nearest existing directory at or above `path`, where the output (and its
    temporary file beside it) would be created, refuses writes: a read-only file system or no
    permission. Checked without writing anything (access(2), which sees read-only mounts too)."""
    directory = next((p for p in (path.absolute(), *path.absolute().parents) if p.is_dir()), None)
    if directory is None or os.access(directory, os.W_OK | os.X_OK):
        return
    try:
        read_only = bool(os.statvfs(directory).f_flag & os.ST_RDONLY)
    except (OSError, AttributeError):
        read_only = False
    reason = "read-only file system" if read_only else "no permission"
    raise InputError(f"{what} '{shown}': cannot write in '{directory}' ({reason}: write elsewhere)")


def output_dir(path: str | Path, what: str) -> Path:
    """`path` usable as an output directory: absent (creatable) or a directory, somewhere writable."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError(f"{what} '{path}': exists and is not a directory")
    blocker = _file_in_the_way(path)
    if blocker is not None:
        raise InputError(f"{what} '{path}': '{blocker}' is a file, not a directory")
    _check_writable(path, what, path)
    return path


def output_file(path: str | Path, what: str) -> Path:
    """`path` usable as an output file: not a directory, no file where a parent directory must be,
    and a writable directory to create it in (outputs are written beside, then renamed)."""
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{what} '{path}': is a directory, expected a file name")
    blocker = _file_in_the_way(path)
    if blocker is not None:
        raise InputError(f"{what} '{path}': '{blocker}' is a file, not a directory")
    _check_writable(path.absolute().parent, what, path)
    return path


def os_error_message(exc: OSError) -> str:
    """One line for a file-system error, naming the path when the error carries one."""
    from suctionbench.io import os_error_reason

    return f"'{exc.filename}': {os_error_reason(exc)}" if exc.filename else os_error_reason(exc)
