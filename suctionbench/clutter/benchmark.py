"""`suctionbench eval --task bin-*`: every bin of a task for one policy, one MCAP log per bin (each
attempt's observation, candidates, grasp and outcome), run.json with every attempt and the task's
figures (`bin_metrics`).

The run appears in --out only when every bin is done (written to a hidden sibling first,
`io.atomic_dir`); a failure leaves --out as it was.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

from suctionbench.clutter.runner import BinRequest, BinRunner
from suctionbench.clutter.tasks import BinTask
from suctionbench.errors import InputError
from suctionbench.policies.base import IMAGE_KNOWN_STATE_POLICIES

RUN_KIND = "bin"
"""run.json's "kind" for a bin run (single-object runs have none)."""

LOG_DIR = "bins"
"""Sub-directory of a bin run holding one MCAP log per bin."""


def bin_log_name(trial: int) -> str:
    return f"bin_{trial:04d}.mcap"


def run_bin(request: BinRequest, log_path: str | None) -> dict[str, Any]:
    """One bin (a worker's job): its record, logged to `log_path` if given."""
    runner = BinRunner(request)
    if log_path is None:
        return runner.run()
    from suctionbench.runlog.writer import EpisodeLog

    metadata = {"task": request.task.name, "trial": request.trial, "policy": request.policy,
                "masks": request.masks, "objects": runner.keys}
    with EpisodeLog(log_path, metadata) as log:
        def record(attempt: dict[str, Any]) -> None:
            t = float(runner.episode.data.time)
            if runner.observation is not None:
                obs = runner.observation
                log.log_observation(t, obs.depth, obs.intrinsics.matrix, obs.intrinsics.width, obs.intrinsics.height,
                                    obs.camera_pose)
            if attempt["grasp_world"] is not None:
                g = attempt["grasp_world"]
                log.log_grasps(t, [g[:3]], [g[3:]], None if attempt["policy_q"] is None else [attempt["policy_q"]], 0)
            log.log_result(t, attempt)

        return runner.run(log=record)


def _refuse(out: Path) -> str | None:
    """Why an existing, non-empty --out may not be replaced by a bin run (None: it is one)."""
    try:
        run = json.loads((out / "run.json").read_text())
    except (OSError, ValueError):
        return "holds files but no bin run (run.json)"
    if not isinstance(run, dict) or run.get("kind") != RUN_KIND:
        return "holds a run that is not a bin run"
    other = [e.name for e in out.iterdir() if e.name not in ("run.json", LOG_DIR)]
    return f"holds '{other[0]}', which eval did not write" if other else None


def run_bin_eval(task: BinTask, policy: str, out: Path, *, model: str | None = None, trials: int | None = None,
                 seed: int | None = None, workers: int = 1, engine: str = "local", address: str | None = None,
                 masks: str = "depth", cup: str = "default", camera: str = "primesense",
                 policy_args: dict[str, Any] | None = None, overwrite: bool = False,
                 progress: Any = None) -> dict[str, Any]:
    """Run every bin of `task` with `policy`; returns the run's summary (run.json without the bins)."""
    from suctionbench.clutter.runner import MASK_SOURCES, bin_metrics
    from suctionbench.config import cup_preset
    from suctionbench.evaluation.cycle import CYCLE_MODEL
    from suctionbench.evaluation.runner import _invocation, _versions, built_policy_config
    from suctionbench.io import atomic_dir, json_safe
    from suctionbench.parallel import map_ordered
    from suctionbench.policies.gqcnn import model_used
    from suctionbench.sensing.camera import resolve_camera

    if masks not in MASK_SOURCES:
        raise InputError(f"--masks '{masks}': expected one of {', '.join(MASK_SOURCES)}")
    if policy in IMAGE_KNOWN_STATE_POLICIES:
        raise InputError(f"--policy {policy}: single-object tasks only (it ranks the grasps the image "
                         "offers on the one object whose state it knows)")
    cup_config = cup_preset(cup)
    resolve_camera(camera)  # a bad camera fails before any work
    policy_config = built_policy_config(policy, policy_args or {}, model)  # bad options fail before any work
    if out.is_dir() and any(out.iterdir()) and not overwrite:
        raise InputError(f"--out '{out}': not empty; pass --overwrite to replace a bin run there")
    if seed is not None:
        task = replace(task, seed=seed)
    count = trials or task.trials
    compute = CYCLE_MODEL.compute_time(policy)
    with atomic_dir(out, _refuse) as staging:
        (staging / LOG_DIR).mkdir()
        requests = [(BinRequest(task, trial=i, policy=policy, policy_args=dict(policy_args or {}), model=model,
                                masks=masks, cup=cup_config, camera=camera),
                     str(staging / LOG_DIR / bin_log_name(i))) for i in range(count)]
        bins = []
        for record in map_ordered(run_bin, requests, engine=engine, workers=workers, address=address):
            bins.append(record)
            if progress is not None:
                progress(1)
        run = {
            "kind": RUN_KIND, "task": task.name, "policy": policy, "policy_args": policy_args or {},
            "policy_config": policy_config,
            "model": model, "model_used": model_used(policy, model, policy_args), "masks": masks, "cup": cup,
            "camera": camera, "seed": task.seed, "trials": count,
            "compute_model": compute, "command": _invocation(), "versions": _versions(),
            "metrics": bin_metrics(bins, compute), "bins": bins,
        }
        (staging / "run.json").write_text(json.dumps(json_safe(run), indent=1))
    summary = {k: v for k, v in run.items() if k != "bins"}
    return {"out": str(out), **summary}
