"""Generate and cache the training corpus: specs from corpus.py, built without convex parts
(training needs meshes, labels and renders, not simulation), checked disjoint from the
evaluation sets by geometry hash and by (generator, parameters)."""

from __future__ import annotations

import json
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

from suctionbench.errors import InputError
from suctionbench.io import atomic_path
from suctionbench.objects.batch import build_specs
from suctionbench.objects.build import ObjectRecord
from suctionbench.objects.registry import eval_specs, list_objects
from suctionbench.objects.spec import SETS


def _cached(directory: Path, spec: Any) -> ObjectRecord | None:
    """The built object at `directory` if it exists and was built from exactly `spec`: same generator
    and parameters, and its mass from the spec's mass model, or from the lighter variant the mass
    cap chooses for this shape, so objects built before real masses, or with another `--masses`
    mode into the same folder (an empty bottle where this spec fills it), are rebuilt."""
    from suctionbench.objects.mass import resolve_mass, variants

    try:
        record = ObjectRecord.load(directory)
    except (InputError, TypeError):
        return None
    if (record.generator, record.params) != (spec.generator, spec.params):
        return None
    chain = variants(spec.mass_model())
    matched = next((v for v in chain  # "; ...": a floor note
                    if record.mass_source == v.source or record.mass_source.startswith(v.source + "; ")), None)
    if matched is None:
        return None
    if matched is chain[0]:
        return record
    chosen, _ = resolve_mass(record.mesh(), chain[0], spec.name, spec.params, keep_above_cap=True)
    return record if chosen.source == matched.source else None


def evaluation_fingerprints() -> tuple[set[str], set[str]]:
    """Geometry hashes of the committed evaluation objects and their (generator, params) keys."""
    hashes = {r.geometry_hash for s in SETS for r in list_objects(s)}
    keys = {_spec_key(spec) for group in eval_specs().values() for spec in group}
    return hashes, keys


def _spec_key(spec: Any) -> str:
    return json.dumps([spec.generator, spec.params], sort_keys=True)


def generate_corpus(
    count: int, seed: int, out: Path, *, workers: int = 1, progress: Callable[[int], None] | None = None,
    masses: str = "material", sizes: str = "family",
) -> dict[str, Any]:
    """Build `count` corpus objects into out/train/ (reusing cached ones); write out/corpus.json.
    `masses`: each shape's own material, the training mass prior, or containers part-filled
    (corpus_priors.MASS_MODES); `sizes`: each family's own size range or real items'
    (corpus_priors.SIZE_MODES)."""
    from suctionbench.objects.corpus import corpus_specs

    start = time.perf_counter()
    specs = corpus_specs(count, seed, masses, sizes)
    eval_hashes, eval_keys = evaluation_fingerprints()
    clashing = [s.name for s in specs if _spec_key(s) in eval_keys]
    if clashing:
        raise RuntimeError(f"corpus specs equal to evaluation objects: {clashing[:5]}")
    root = Path(out)
    records: dict[str, ObjectRecord] = {}
    todo = []
    for spec in specs:
        cached = _cached(root / spec.set / spec.name, spec)
        if cached is None:
            todo.append(spec)
        else:
            records[spec.name] = cached
            if progress:
                progress(1)
    for record in build_specs(todo, root, workers=workers, decompose=False, progress=progress):
        records[record.name] = record
    ordered = [records[s.name] for s in specs]
    overlap = [r.name for r in ordered if r.geometry_hash in eval_hashes]
    if overlap:
        raise RuntimeError(f"corpus objects identical to evaluation objects: {overlap[:5]}")
    categories = Counter(name.split("_", 2)[2] for name in records)
    manifest = {
        "count": count,
        "seed": seed,
        "masses": masses,
        "sizes": sizes,
        "categories": dict(sorted(categories.items())),
        "objects": [{"name": r.name, "generator": r.generator, "geometry_hash": r.geometry_hash} for r in ordered],
    }
    with atomic_path(root / "corpus.json") as tmp:
        tmp.write_text(json.dumps(manifest, indent=1))
    return {
        "count": count,
        "seed": seed,
        "masses": masses,
        "sizes": sizes,
        "built": len(todo),
        "cached": count - len(todo),
        "seconds": round(time.perf_counter() - start, 1),
        "eval_overlap": len(overlap),
        "categories": manifest["categories"],
        "manifest": str(root / "corpus.json"),
    }
