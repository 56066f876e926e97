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


def cpu_model() -> str:
    """The CPU's model name as the kernel reports it ("unknown" where it does not): timings depend on
    it, so every timing result names it (the same 2-core command took 0.050 s on one host's cores
    and 0.024 s on another's)."""
    try:
        with open("/proc/cpuinfo") as fh:
            return next((line.split(":", 1)[1].strip() for line in fh if line.startswith("model name")), "unknown")
    except OSError:
        return "unknown"


def _limit_cores(cores: int) -> int:
    """Pin this process to the first `cores` CPUs (0 = leave as is); returns the count in use.

    Must run before the first ray cast: Embree's thread pool sizes itself from the affinity mask.
    The mask binds the calling thread and the threads it starts later, not numpy's BLAS pool,
    started when numpy was imported with a thread per core: that pool is cut to `cores` threads.
    """
    available = sorted(os.sched_getaffinity(0))
    if cores < 0:
        raise InputError(f"--cores {cores}: must be >= 0")
    if cores:
        os.sched_setaffinity(0, set(available[:cores]))
        from threadpoolctl import threadpool_limits

        threadpool_limits(limits=cores)
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
    from suctionbench.validate import label_memory, require_memory

    if grasps < 1 or not 1 <= reference_grasps <= grasps or memory_grasps < 0:
        raise InputError("bench label: need grasps >= 1, 1 <= reference-grasps <= grasps, memory-grasps >= 0")
    largest = max(grasps, memory_grasps)
    require_memory(label_memory(largest, samples),
                   f"--{'grasps' if largest == grasps else 'memory-grasps'} {largest} x --samples {samples}")
    used_cores = _limit_cores(cores)
    path = mesh or str(asset_path("meshes", "soap_bar.ply"))
    info = load_mesh(path)
    config = LabelConfig(perturbation=PerturbationConfig(num_samples=samples))
    labeller = SuctionLabeller(info, config, mass=mass)
    rng = np.random.default_rng(seed)
    points, approaches = sample_surface_grasps(info.mesh, grasps, rng)

    labeller.robust(points[:2], approaches[:2], seed)  # warm-up: scene build, first-call costs
    result: dict[str, Any] = {
        "mesh": path,
        "faces": len(info.mesh.faces),
        "cores": used_cores,
        "samples_per_grasp": samples,
        "seal_model": config.cup.seal_model,
        "lip_samples": config.seal.lip_samples,
    }
    # Mix 1: uniform surface candidates (what dataset generation labels). Mix 2: only grasps that
    # hold nominally, so most samples pass every stage and cast every ray: the slow case.
    result.update(_time_fast_vs_reference(labeller, points, approaches, reference_grasps, seed, "uniform"))
    holds = labeller.wrench_resistance(points, approaches)
    result.update(
        _time_fast_vs_reference(labeller, points[holds], approaches[holds], reference_grasps, seed, "holding")
    )
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


def _time_fast_vs_reference(
    labeller: Any, points: np.ndarray, approaches: np.ndarray, reference_grasps: int, seed: int, tag: str
) -> dict[str, Any]:
    """Robust labels/s of both paths on the same grasps, the speedup and the agreement."""
    if len(points) == 0:
        return {f"{tag}_grasps": 0}
    wall, cpu = time.perf_counter(), time.process_time()
    fast_rwr, fast_samples = labeller.robust(points, approaches, seed)
    fast_s, fast_cpu = time.perf_counter() - wall, time.process_time() - cpu
    ref = slice(0, min(reference_grasps, len(points)))
    wall = time.perf_counter()
    ref_rwr, ref_samples = labeller.robust(points[ref], approaches[ref], seed, reference=True)
    ref_s = time.perf_counter() - wall
    fast_rate, ref_rate = len(points) / fast_s, (ref.stop - ref.start) / ref_s
    return {
        f"{tag}_grasps": len(points),
        f"{tag}_fast_labels_per_s": round(fast_rate, 1),
        f"{tag}_fast_cpu_per_wall": round(fast_cpu / fast_s, 2),
        f"{tag}_reference_grasps": ref.stop,
        f"{tag}_reference_labels_per_s": round(ref_rate, 2),
        f"{tag}_speedup": round(fast_rate / ref_rate, 1),
        f"{tag}_sample_agreement": float((fast_samples[ref] == ref_samples).mean()),
        f"{tag}_label_agreement": float((fast_rwr[ref] == ref_rwr).mean()),
        f"{tag}_rwr_mean": round(float(fast_rwr.mean()), 4),
    }


def bench_episode(*, object_key: str, episodes: int, cores: int, seed: int) -> dict[str, Any]:
    """Full pick episodes per second (observation rendering included) with the compliant, leak-aware
    cup, timed against the rigid reference cup (`SimCupConfig.rigid()`) on the same seeds in the
    same run, episode by episode in turn so both see the same machine load: wall and CPU time per
    episode of each and their ratios, the simulated-time / wall-time ratio, render time per depth
    frame, success rates, and the cup's peak accelerations in the lift and the transport (the
    inertial load of the labeller's disturbing wrench)."""
    from suctionbench.sensing.camera import DepthRenderer
    from suctionbench.sim.cup import SimCupConfig
    from suctionbench.sim.pick import PickRequest, PickRunner

    if episodes < 1:
        raise InputError(f"--episodes {episodes}: must be at least 1")
    used_cores = _limit_cores(cores)
    cups = {"compliant": SimCupConfig(), "rigid": SimCupConfig.rigid()}
    runners, renderers, stats = {}, {}, {}
    for name, sim_cup in cups.items():
        start = time.perf_counter()
        runners[name] = PickRunner(PickRequest(object_key, seed=seed, sim_cup=sim_cup))
        stats[name] = {"build_s": time.perf_counter() - start, "walls": [], "cpus": [], "sims": [], "renders": [],
                       "successes": 0, "accel": {"lift": [], "transport": []}}
    try:
        for name, runner in runners.items():
            renderers[name] = DepthRenderer(runner.scene.model, runner.intrinsics)
        for k in range(episodes):
            for name, runner in runners.items():
                st = stats[name]
                runner.request.seed = seed + k
                wall, cpu = time.perf_counter(), time.process_time()
                runner.episode.reset(np.random.default_rng((seed + k, 0)))
                t = time.perf_counter()
                renderers[name].render(runner.episode.data, runner.scene.camera)
                st["renders"].append(time.perf_counter() - t)
                result = runner.run_after_reset()
                st["walls"].append(time.perf_counter() - wall)
                st["cpus"].append(time.process_time() - cpu)
                st["sims"].append(result["sim_time"] + result.get("placement_time", 0.0))
                st["successes"] += bool(result["success"])
                for motion, value in result.get("peak_acceleration", {}).items():
                    st["accel"].setdefault(motion, []).append(value)
    finally:
        for renderer in renderers.values():
            renderer.close()
    compliant, rigid = stats["compliant"], stats["rigid"]
    mean_c, mean_r = float(np.mean(compliant["walls"])), float(np.mean(rigid["walls"]))
    accel = compliant["accel"]
    return {
        "object": object_key,
        "cores": used_cores,
        "episodes": episodes,
        "scene_build_s": round(compliant["build_s"], 3),
        "episode_wall_s_mean": round(mean_c, 4),
        "episode_wall_s_max": round(float(np.max(compliant["walls"])), 4),
        "episodes_per_s": round(1.0 / mean_c, 2),
        "rigid_episode_wall_s_mean": round(mean_r, 4),
        "compliant_over_rigid": round(mean_c / mean_r, 3),
        "episode_cpu_s_mean": round(float(np.mean(compliant["cpus"])), 4),
        "rigid_episode_cpu_s_mean": round(float(np.mean(rigid["cpus"])), 4),
        "compliant_over_rigid_cpu": round(float(np.sum(compliant["cpus"]) / np.sum(rigid["cpus"])), 3),
        "sim_to_wall_ratio": round(float(np.sum(compliant["sims"]) / np.sum(compliant["walls"])), 2),
        "render_ms_per_frame": round(1e3 * float(np.median(compliant["renders"] + rigid["renders"])), 2),
        "success_rate": round(compliant["successes"] / episodes, 3),
        "rigid_success_rate": round(rigid["successes"] / episodes, 3),
        "peak_acceleration_lift": round(max(accel["lift"]), 3) if accel["lift"] else None,
        "peak_acceleration_transport": round(max(accel["transport"]), 3) if accel["transport"] else None,
    }


def bench_generate(*, objects: str, datapoints: int, workers: int, seed: int) -> dict[str, Any]:
    """Datapoints/s of dataset generation with all workers vs one worker (the serial reference)
    on the same configuration, and its shard assembly on `workers` threads vs one (the two
    datasets' shards must be the same bytes); render ms per frame, robust-label ms per grasp, and
    peak memory."""
    import tempfile
    from pathlib import Path

    from suctionbench.contact import SuctionLabeller
    from suctionbench.dataset.generate import GenerationConfig, generate_dataset
    from suctionbench.dataset.render import TableScene
    from suctionbench.geometry.sampling import sample_surface_grasps
    from suctionbench.objects.registry import resolve_objects
    from suctionbench.sensing.camera import camera_preset
    from suctionbench.sensing.camera_pose import CameraPoseConfig, sample_camera_pose
    from suctionbench.validate import BYTES_PER_DATAPOINT, require_disk

    if datapoints < 1 or workers < 1:
        raise InputError("bench generate: need --datapoints >= 1 and --workers >= 1")
    scratch = tempfile.gettempdir()  # both runs' datasets stay there until the end
    require_disk(scratch, 2 * datapoints * BYTES_PER_DATAPOINT,
                 f"--datapoints {datapoints} (two datasets in the temporary directory; TMPDIR sets another)")
    records = resolve_objects(objects)
    dirs, keys = [str(r.directory) for r in records], [r.key for r in records]
    config = GenerationConfig(datapoints=datapoints, seed=seed)
    rates, assembly = {}, {}
    with tempfile.TemporaryDirectory(dir=scratch) as tmp:
        for label, count in (("parallel", workers), ("serial", 1)):
            start = time.perf_counter()
            card = generate_dataset(Path(tmp) / label, dirs, keys, "primesense", config, workers=count)
            rates[label] = card["datapoints"] / (time.perf_counter() - start)
            assembly[label] = float(card["generation_runs"][-1]["assembly_seconds"])
        same_shards = _same_files(Path(tmp) / "parallel" / "tensors", Path(tmp) / "serial" / "tensors")
    intrinsics = camera_preset("primesense")
    rng = np.random.default_rng(seed)
    with TableScene(records[0], intrinsics) as scene:
        pose = records[0].most_probable_pose()
        cameras = [sample_camera_pose(rng, np.zeros(3), CameraPoseConfig()) for _ in range(20)]
        scene.render(pose, cameras[0])
        start = time.perf_counter()
        for cam in cameras:
            scene.render(pose, cam)
        render_ms = 1e3 * (time.perf_counter() - start) / len(cameras)
    mesh = records[0].mesh()
    points, approaches = sample_surface_grasps(mesh, 400, rng)
    labeller = SuctionLabeller(mesh, config.label, mass=records[0].mass, com=records[0].com)
    start = time.perf_counter()
    labeller.label(points, approaches, seed, metrics=("wr", "rwr"))
    label_ms = 1e3 * (time.perf_counter() - start) / len(points)
    return {
        "objects": objects,
        "datapoints": datapoints,
        "workers": workers,
        "datapoints_per_s": round(rates["parallel"], 1),
        "datapoints_per_s_per_core": round(rates["parallel"] / workers, 1),
        "serial_datapoints_per_s": round(rates["serial"], 1),
        "parallel_speedup": round(rates["parallel"] / rates["serial"], 2),
        "assembly_s": assembly["parallel"],  # the shards cut from the units on `workers` threads ...
        "serial_assembly_s": assembly["serial"],  # ... and on one
        "assembly_speedup": round(assembly["serial"] / max(assembly["parallel"], 1e-3), 2),
        "same_shards": same_shards,  # both runs' shard files byte for byte equal
        "render_ms_per_frame": round(render_ms, 2),
        "label_ms_per_grasp": round(label_ms, 3),
        "positive_rate": card["positive_rate"],
        "max_rss_mb_main": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
        "max_rss_mb_worker": round(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024, 1),
    }


def _same_files(a, b) -> bool:
    """Whether folders `a` and `b` hold the same file names with the same bytes."""
    import filecmp

    names = sorted(p.name for p in a.iterdir())
    return names == sorted(p.name for p in b.iterdir()) and all(
        filecmp.cmp(a / name, b / name, shallow=False) for name in names)


def bench_plan(*, policies: list[str], model: str | None, scenes: int, seed: int, cores: int) -> dict[str, Any]:
    """Seconds per planned grasp of each image policy on rendered scenes of the typical set; for
    gqcnn also the reference (the same CEM with one network call per candidate, unbatched), for
    fc-gqcnn the same dense policy scoring every window of its lattices (`DenseConfig.window_pitch`
    under the thumbnail's pitch)."""
    from suctionbench.objects.registry import list_objects
    from suctionbench.policies.base import MODEL_POLICIES, make_policy
    from suctionbench.sim.pick import PickRequest, PickRunner

    used_cores = _limit_cores(cores)
    typical = list_objects("typical")
    if scenes > len(typical):
        raise InputError(f"--scenes {scenes}: at most {len(typical)} (one scene per object of the typical set)")
    records = typical[:: max(1, len(typical) // scenes)][:scenes]
    observations = []
    for i, record in enumerate(records):
        runner = PickRunner(PickRequest(record.key, seed=seed + i, record=record))
        runner.reset()
        observations.append(runner.observe())
    result: dict[str, Any] = {"scenes": len(observations), "cores": used_cores, "cpu": cpu_model()}
    for name in policies:
        policy = make_policy(name, **({"model": model} if name in MODEL_POLICIES and model else {}))
        result[f"{name}_s_per_grasp"] = _seconds_per_grasp(policy, observations, seed)
        if name == "gqcnn":
            scorer = policy.model
            unbatched = _Unbatched(scorer)
            policy.model = unbatched
            start = time.perf_counter()
            policy.plan(observations[0], np.random.default_rng(seed))
            result["gqcnn_reference_unbatched_s_per_grasp"] = round(time.perf_counter() - start, 4)
            result["gqcnn_batching_speedup"] = round(
                result["gqcnn_reference_unbatched_s_per_grasp"] / result["gqcnn_s_per_grasp"], 1
            )
            policy.model = scorer
        if name == "fc-gqcnn":  # the reference: every window of the thumbnail's lattice (stride 1)
            every = make_policy(name, window_pitch=_EVERY_WINDOW, **({"model": model} if model else {}))
            result["fc-gqcnn_reference_every_window_s_per_grasp"] = _seconds_per_grasp(every, observations, seed)
            result["fc-gqcnn_window_pitch_speedup"] = round(
                result["fc-gqcnn_reference_every_window_s_per_grasp"] / result["fc-gqcnn_s_per_grasp"], 2)
    return result


def _seconds_per_grasp(policy: Any, observations: list, seed: int) -> float:
    """Mean seconds of `policy.plan` over the observations, after one untimed plan (model load, caches)."""
    policy.plan(observations[0], np.random.default_rng(seed))
    start = time.perf_counter()
    for k, obs in enumerate(observations):
        policy.plan(obs, np.random.default_rng(seed + k))
    return round((time.perf_counter() - start) / len(observations), 4)


_EVERY_WINDOW = 1e-3
"""A dense window pitch (image pixels) under any thumbnail's pitch: every lattice window scored."""


class _Unbatched:
    """A model wrapper evaluating one candidate per network call (the timing reference)."""

    def __init__(self, model: Any):
        self.model = model

    def __getattr__(self, name: str) -> Any:
        """Everything else the policy asks of a model (its image channels, its pose vector's
        length, ...) is the wrapped model's."""
        return getattr(self.model, name)

    def predict(self, images: np.ndarray, poses: np.ndarray) -> np.ndarray:
        return np.concatenate([self.model.predict(images[i : i + 1], poses[i : i + 1]) for i in range(len(images))])


def bench_bin(*, counts: list[int], policy: str, attempts: int, seed: int, cores: int) -> dict[str, Any]:
    """A pick in clutter, timed against a single-object pick of the same policy in the same run:
    per bin size, the wall time of building the scene, of filling the bin (drops and settling) and
    of one attempt (observation, segmentation, planning per region, motion, settling), with the
    simulated time; the reference is `PickRunner`'s episode on the bin's first object. Bins are
    `bin-mixed` draws with the count fixed."""
    from dataclasses import replace

    from suctionbench.clutter.runner import BinRequest, BinRunner
    from suctionbench.clutter.tasks import load_bin_task
    from suctionbench.sim.pick import PickRequest, PickRunner

    if not counts or any(n < 1 or n > 20 for n in counts):
        raise InputError(f"--counts {counts}: object counts must be in [1, 20]")
    if attempts < 1:
        raise InputError(f"--attempts {attempts}: must be at least 1")
    used_cores = _limit_cores(cores)
    rows = []
    for n in counts:
        task = replace(load_bin_task("bin-mixed"), objects=(n, n), seed=seed, max_failures=10**6)
        start = time.perf_counter()
        runner = BinRunner(BinRequest(task, trial=0, policy=policy))
        build = time.perf_counter() - start
        start = time.perf_counter()
        runner.episode.reset(np.random.default_rng((seed, 0, 0)))
        fill, fill_sim = time.perf_counter() - start, float(runner.episode.data.time)
        walls, sims, single = [], [], []
        for k in range(attempts):
            if not runner.episode.present or runner.episode.placement_error:
                break
            start = time.perf_counter()
            record = runner.attempt(k)
            walls.append(time.perf_counter() - start)
            sims.append(float(record["sim_time"]))
            reference = PickRunner(PickRequest(runner.keys[0], seed=seed + k, policy=policy))
            start = time.perf_counter()
            reference.run()
            single.append(time.perf_counter() - start)
        attempt_s, single_s = float(np.mean(walls)), float(np.mean(single))
        rows.append({"objects": n, "spilled": len(runner.episode.spilled),
                     "scene_build_s": round(build, 3), "fill_s": round(fill, 3), "fill_sim_s": round(fill_sim, 2),
                     "attempts": len(walls), "attempt_s": round(attempt_s, 3),
                     "attempt_sim_s": round(float(np.mean(sims)), 3),
                     "single_pick_s": round(single_s, 3), "attempt_over_single": round(attempt_s / single_s, 2)})
    return {"policy": policy, "cores": used_cores, "seed": seed, "rows": rows}


def bench_import(*, mesh: str, units: str, scale: float, cores: int) -> dict[str, Any]:
    """Seconds to import `mesh` (read, repair, decompose, stable poses) with the convex
    decomposition's tries side by side on `cores` against the reference, one after another, in
    one run (temporary object roots), and whether both give the same object."""
    import tempfile
    from pathlib import Path

    from suctionbench.objects.importer import import_mesh

    used_cores = _limit_cores(cores)
    seconds, records = {}, {}
    with tempfile.TemporaryDirectory(prefix="suctionbench-bench-import-") as folder:
        for name, parallel in (("one_by_one", 1), ("side_by_side", used_cores)):
            start = time.perf_counter()
            records[name] = import_mesh(mesh, set_name="bench", name=name.replace("_", "-"), units=units,
                                        scale=scale, root=Path(folder), coacd_parallel=parallel)
            seconds[name] = time.perf_counter() - start
    fast, reference = records["side_by_side"], records["one_by_one"]
    same = fast.geometry_hash == reference.geometry_hash and fast.decomposition == reference.decomposition
    return {
        "mesh": mesh, "faces": fast.faces, "units": fast.units, "cores": used_cores,
        "decomposition": {k: fast.decomposition.get(k) for k in ("method", "threshold", "max_convex_hull",
                                                                 "coverage", "excess")},
        "parts": len(fast.parts), "seconds_side_by_side": round(seconds["side_by_side"], 2),
        "seconds_one_by_one": round(seconds["one_by_one"], 2),
        "speedup": round(seconds["one_by_one"] / seconds["side_by_side"], 2), "same_object": bool(same),
    }


def _write_timing_dataset(directory, datapoints: int, seed: int) -> None:
    """A dataset of `datapoints` random table-top thumbnails for timing the trainer: planes at
    0.55-0.65 m tilted up to ~30 degrees with 1 mm noise, random poses and metrics. Its content
    does not matter (the work per image is the network's and the loader's); its shape, fields and
    splits are those `generate` writes, so the trainer reads it as it reads a real one."""
    from suctionbench.dataset.storage import DatasetWriter, write_splits
    from suctionbench.dataset.storage.format import FIELDS

    rng = np.random.default_rng(seed)
    per_shard = 1000
    yy, xx = np.mgrid[0:32, 0:32].astype(np.float32) - 15.5
    writer = DatasetWriter(directory, per_shard)
    positives = 0
    for shard, start in enumerate(range(0, datapoints, per_shard)):
        k = min(per_shard, datapoints - start)
        slope = rng.uniform(-0.6, 0.6, (2, k, 1, 1)).astype(np.float32) * 0.001  # m per pixel at 1 mm/px
        depth = rng.uniform(0.55, 0.65, (k, 1, 1)).astype(np.float32)
        plane = (depth + slope[0] * xx + slope[1] * yy)[..., None]  # (k, 32, 32, 1), as generate stores
        metric = rng.uniform(0, 1, k).astype(np.float32)
        robust = metric > 0.2
        positives += int(robust.sum())
        fields = {
            "depth_ims_tf_table": plane + rng.normal(0, 0.001, plane.shape).astype(np.float32),
            "context_ims_tf_table": plane + rng.normal(0, 0.001, plane.shape).astype(np.float32),
            "robust_suction_wrench_resistance": metric, "wrench_resistance": robust.astype(np.uint8),
            "seal_flags": np.ones(k, np.uint8),
            "object_labels": (np.arange(start, start + k) // 100).astype(np.int32),
            "image_labels": (np.arange(start, start + k) // 10).astype(np.int32),
            "pose_labels": np.zeros(k, np.int32), "grasp_labels": np.arange(k, dtype=np.int32) % 10,
        }
        for name in ("hand_poses", "object_context"):
            spec = FIELDS[name]
            fields[name] = rng.uniform(0, 1, (k, *spec.shape)).astype(spec.dtype)
        writer.write_shard(shard, fields)
    writer.write_card({
        "config": {"label_threshold": 0.2}, "camera": {"name": "primesense", "fx": 525.0, "fy": 525.0},
        "fingerprint": f"bench-train-{datapoints}-{seed}", "datapoints": datapoints,
        "positive_rate": positives / datapoints,
    })
    ids = np.arange(datapoints)
    write_splits(directory, ids // 10, ids // 100, seed=seed)


def bench_train(*, archs: list[str], datapoints: int, reference_datapoints: int, device: str,
                batch_size: int, seed: int, cores: int) -> dict[str, Any]:
    """Training images/s of each network on `device` (cuda: bfloat16 autocast) against the CPU in
    float32 (the reference) in the same run: one epoch of gqcnn's recipe (SGD, noise and flip
    augmentation, shard pooling) on a written dataset of `datapoints` random thumbnails (the CPU
    on the first `reference_datapoints` of them), and the hours 25 epochs of 2.8 M datapoints (the
    Dex-Net 3.0 schedule) would take at each rate. Validation and fit scoring are not timed."""
    import tempfile
    from pathlib import Path

    import torch

    from suctionbench.learning.models import build_model, count_parameters
    from suctionbench.learning.train import _device, train
    from suctionbench.learning.train_config import TrainConfig

    used_cores = _limit_cores(cores)
    if datapoints < 1000 or not 1000 <= reference_datapoints <= datapoints:
        raise InputError("bench train: need --datapoints >= 1000 and 1000 <= --reference-datapoints <= --datapoints")
    if not archs:
        raise InputError("--archs: name at least one network")
    parameters = {arch: count_parameters(build_model(arch)) for arch in archs}  # InputError for an unknown one
    fast = _device(device)
    torch.set_num_threads(used_cores)
    result: dict[str, Any] = {"device": torch.cuda.get_device_name(fast) if fast.type == "cuda" else "cpu",
                              "cores": used_cores, "datapoints": datapoints, "batch_size": batch_size}
    dex_net_images = 25 * 2_800_000
    with tempfile.TemporaryDirectory(prefix="suctionbench-bench-train-") as folder:
        data = Path(folder) / "data"
        _write_timing_dataset(data, datapoints, seed)
        devices = [("cpu", "cpu", reference_datapoints)]
        if fast.type != "cpu":
            devices.append((fast.type, str(fast), datapoints))
        for arch in archs:
            result[f"{arch}_parameters"] = parameters[arch]
            rates = {}
            for name, where, limit in devices:
                config = TrainConfig(arch=arch, epochs=1, batch_size=batch_size, device=where, seed=seed,
                                     max_train_datapoints=limit, max_val_datapoints=1000, fit_datapoints=1000)
                metrics = train(data, Path(folder) / f"{arch}-{name}", config, command="bench train")
                rates[name] = float(metrics["train_images_per_s"])
                result[f"{arch}_{name}_images_per_s"] = round(rates[name], 1)
                result[f"{arch}_{name}_hours_dex_net_schedule"] = round(dex_net_images / rates[name] / 3600, 2)
            if fast.type != "cpu":
                result[f"{arch}_{fast.type}_speedup"] = round(rates[fast.type] / rates["cpu"], 1)
    return result
