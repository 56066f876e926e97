"""Build many objects from specs in parallel (process pool), each written atomically."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from suctionbench.objects.build import ObjectRecord, build_object
from suctionbench.objects.ownership import check_replaceable_objects
from suctionbench.objects.spec import ObjectSpec
from suctionbench.parallel import process_pool


def _build_one(args: tuple[ObjectSpec, Path, bool, bool]) -> ObjectRecord:
    from suctionbench.objects.shapes import make_shape

    spec, out_dir, decompose, reuse_parts = args
    return build_object(make_shape(spec.generator, spec.params), spec, out_dir, decompose=decompose,
                        reuse_parts=reuse_parts)


def build_specs(
    specs: list[ObjectSpec],
    root: Path,
    *,
    workers: int = 1,
    decompose: bool = True,
    reuse_parts: bool = False,
    progress: Callable[[int], None] | None = None,
) -> list[ObjectRecord]:
    """Build every spec into root/<set>/<name>/ and return the records in spec order (`reuse_parts`:
    keep the convex parts of objects whose mesh is unchanged, see build_object). A target directory
    holding files suctionbench did not write is an InputError before any object is built."""
    jobs = [(spec, Path(root) / spec.set / spec.name, decompose, reuse_parts) for spec in specs]
    check_replaceable_objects(job[1] for job in jobs)
    records: list[ObjectRecord] = []
    if workers <= 1:
        for job in jobs:
            records.append(_build_one(job))
            if progress:
                progress(1)
        return records
    with process_pool(workers) as pool:
        for record in pool.map(_build_one, jobs, chunksize=1):
            records.append(record)
            if progress:
                progress(1)
    return records
