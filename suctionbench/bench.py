"""Performance measurements behind `suctionbench bench`: each fast path timed against its
reference in the same run, on the same inputs, reporting rates, the speedup and agreement."""

from __future__ import annotations

import os
import resource
import time
import tracemalloc
from typing import Any

import numpy as np

from suctionbench.config import LabelConfig, PerturbationConfig
from suctionbench.errors import InputError


def _limit_cores(cores: int) -> int:
    """Pin this process to the first `cores` CPUs (0 = leave as is); returns the count in use.

    Must run before the first ray cast: Embree's thread pool sizes itself from the affinity mask.
    """
    available = sorted(os.sched_getaffinity(0))
    if cores < 0:
        raise InputError(f"--cores {cores}: must be >= 0")
    if cores:
        os.sched_setaffinity(0, set(available[:cores]))
    return len(os.sched_getaffinity(0))


def bench_label(
    *,
    mesh: str | None,
    mass: float,
    grasps: int,
    reference_grasps: int,
    samples: int,
    memory_grasps: int,
    cores: int,
    seed: int,
) -> dict[str, Any]:
    """Time robust labelling: vectorised path vs per-sample reference on the same grasps."""
    from suctionbench.contact import SuctionLabeller
    from suctionbench.geometry.mesh import load_mesh
    from suctionbench.geometry.sampling import sample_surface_grasps
    from suctionbench.resources import asset_path

    if grasps < 1 or not 1 <= reference_grasps <= grasps or memory_grasps < 0:
        raise InputError("bench label: need grasps >= 1, 1 <= reference-grasps <= grasps, memory-grasps >= 0")
    used_cores = _limit_cores(cores)
    path = mesh or str(asset_path("meshes", "soap_bar.ply"))
    info = load_mesh(path)
    config = LabelConfig(perturbation=PerturbationConfig(num_samples=samples))
    labeller = SuctionLabeller(info, config, mass=mass)
    rng = np.random.default_rng(seed)
    points, approaches = sample_surface_grasps(info.mesh, grasps, rng)

    labeller.robust(points[:2], approaches[:2], seed)  # warm-up: scene build, first-call costs
    wall, cpu = time.perf_counter(), time.process_time()
    fast_rwr, fast_samples = labeller.robust(points, approaches, seed)
    fast_s, fast_cpu = time.perf_counter() - wall, time.process_time() - cpu

    ref = slice(0, reference_grasps)
    wall = time.perf_counter()
    ref_rwr, ref_samples = labeller.robust(points[ref], approaches[ref], seed, reference=True)
    ref_s = time.perf_counter() - wall

    fast_rate, ref_rate = grasps / fast_s, reference_grasps / ref_s
    result: dict[str, Any] = {
        "mesh": path,
        "faces": len(info.mesh.faces),
        "cores": used_cores,
        "samples_per_grasp": samples,
        "fast_grasps": grasps,
        "fast_labels_per_s": round(fast_rate, 1),
        "fast_cpu_s_per_wall_s": round(fast_cpu / fast_s, 2),
        "reference_grasps": reference_grasps,
        "reference_labels_per_s": round(ref_rate, 2),
        "speedup": round(fast_rate / ref_rate, 1),
        "sample_agreement": float((fast_samples[ref] == ref_samples).mean()),
        "label_agreement": float((np.abs(fast_rwr[ref] - ref_rwr) < 1e-12).mean()),
        "rwr_mean": round(float(fast_rwr.mean()), 4),
        "positive_rate": round(float((fast_rwr > 0.2).mean()), 4),
    }
    if memory_grasps:
        mem_points, mem_approaches = sample_surface_grasps(info.mesh, memory_grasps, rng)
        tracemalloc.start()
        labeller.robust(mem_points, mem_approaches, seed)
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        result["memory_grasps"] = memory_grasps
        result["peak_traced_mb"] = round(peak / 2**20, 1)
        result["max_rss_mb"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)
    return result
