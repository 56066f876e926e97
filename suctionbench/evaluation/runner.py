"""Run a benchmark: seeded trials (identical across policies), one MCAP log per trial, in parallel;
the results table is then computed from the logs (suctionbench.runlog.reader), never from memory."""

from __future__ import annotations

import dataclasses
import json
import math
import re
from collections import Counter
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.errors import InputError
from suctionbench.evaluation.cycle import CYCLE_MODEL, modelled_compute, picks_per_hour
from suctionbench.evaluation.tasks import Task
from suctionbench.io import atomic_path, json_safe, publish_dir, read_json
from suctionbench.validate import BYTES_PER_TRIAL_LOG, output_dir, require_disk

PREDICT_THRESHOLD = 0.5
"""An analytic label (rwr) above this predicts success, for the label-precision column."""


@dataclass(frozen=True)
class Trial:
    """One seeded pick of the benchmark."""

    index: int
    object_key: str
    seed: int
    placement: str
    stable_pose: int
    policy: str
    model: str | None
    metric: str
    cup: str
    policy_args: dict[str, Any] = field(default_factory=dict)
    camera: str = "primesense"


def plan_trials(task: Task, policy: str, *, model: str | None, trials: int | None, seed: int | None,
                metric: str = "rwr", cup: str = "default", policy_args: dict[str, Any] | None = None,
                camera: str = "primesense") -> list[Trial]:
    """Trial i: object i mod |set|, seed (base seed, i); cycles stable poses for 'stable' tasks."""
    from suctionbench.objects.registry import list_objects

    records = list_objects(task.set)
    if not records:
        raise InputError(f"task '{task.name}': object set '{task.set}' is empty")
    count, base = trials or task.trials, task.seed if seed is None else seed
    if count < 1:
        raise InputError(f"--trials {count}: must be at least 1")
    n = len(records)
    return [
        Trial(i, records[i % n].key, int(np.random.SeedSequence((base, i)).generate_state(1)[0] % 2**31),
              task.placement, (i // n) % max(task.stable_poses, 1), policy, model, metric, cup,
              dict(policy_args or {}), camera)
        for i in range(count)
    ]


def run_trial(trial: Trial, log_dir: str) -> dict[str, Any]:
    """Run one trial and write its MCAP log (runs in a worker)."""
    from suctionbench.config import cup_preset
    from suctionbench.sim.pick import PickRequest, PickRunner

    request = PickRequest(
        trial.object_key, seed=trial.seed, policy=trial.policy, placement=trial.placement,
        cup=cup_preset(trial.cup), model=trial.model, metric=trial.metric, stable_pose=trial.stable_pose,
        policy_args=dict(trial.policy_args), camera=trial.camera,
    )
    record = PickRunner(request).run(log=Path(log_dir) / f"trial_{trial.index:05d}.mcap")
    return {"trial": trial.index, **record}


def run_eval(task: Task, policy: str, out: Path, *, model: str | None = None, trials: int | None = None,
             seed: int | None = None, workers: int = 1, engine: str = "local", address: str | None = None,
             metric: str = "rwr", cup: str = "default", policy_args: dict[str, Any] | None = None,
             camera: str = "primesense", command: str | None = None, resume: bool = False, overwrite: bool = False,
             progress: Callable[[int], None] | None = None, notify: Callable[[str], None] | None = None
             ) -> dict[str, Any]:
    """Run the trials into out/ (trials/*.mcap + run.json) and return the summary from the logs.

    `policy` is a built-in name or any spec `suctionbench.policies.plugins` loads (a plug-in,
    PATH.py:FACTORY, package.module:FACTORY) with `policy_args` as its factory's options; it is
    built once here, so that a bad spec or option fails before any work, and then again in each
    worker from its spec string. `camera` is a preset name or an intrinsics TOML file. run.json
    records the policy's label (spec and options), the camera, `command` and the versions.

    The run is written into the sibling ``OUT.incomplete`` and renamed to `out` once every trial
    is logged, so `out` is a complete run or absent. A killed run stays in ``OUT.incomplete``:
    `resume` finishes it (same configuration; finished trial logs are kept, unfinished ones
    redone), `overwrite` starts it over. An existing run in `out` is replaced only with
    `overwrite`, and only if it is a run (run.json and trial logs, nothing else).

    `resume` with no interrupted run there is not an error (a job restarted with the same command
    until it finishes, say): the run starts afresh, `notify` (the CLI: a note on stderr) is told so
    before the first trial, and the summary's "resumed" is false. "resumed" is true where an
    interrupted run was finished, "trials_reused" counts its trial logs that were kept."""
    from suctionbench.policies.base import MODEL_POLICIES
    from suctionbench.policies.gqcnn import model_used
    from suctionbench.policies.plugins import builtin_name, canonical_spec, policy_label
    from suctionbench.sensing.camera import resolve_camera
    from suctionbench.sim.pick import KNOWN_STATE_POLICIES

    policy_args = dict(policy_args or {})
    label = policy_label(policy, policy_args)
    command = command or _invocation()
    reads_model = builtin_name(canonical_spec(policy)) in MODEL_POLICIES
    if model and not reads_model:
        raise InputError(f"--model: policy '{policy}' reads no model given this way (only "
                         f"{', '.join(MODEL_POLICIES)} do); a plug-in takes its options with --policy-arg")
    if policy in KNOWN_STATE_POLICIES:
        if policy_args:
            raise InputError(f"--policy-arg: the known-state policy '{policy}' takes no options")
        spec = policy
    else:
        spec = canonical_spec(policy)
        if reads_model:
            _check_model(policy_args.get("model", model))
    # Unknown policy or bad options -> InputError before any work.
    policy_config = built_policy_config(spec, policy_args, model)
    intrinsics = resolve_camera(camera)
    camera_spec = str(Path(camera).resolve()) if Path(str(camera)).is_file() else intrinsics.name
    from suctionbench.config import cup_preset
    from suctionbench.contact.metrics import METRICS
    from suctionbench.parallel import check_engine

    if metric not in METRICS:
        raise InputError(f"--metric '{metric}' is unknown (known: {', '.join(METRICS)})")
    cup_preset(cup)  # unknown preset -> InputError
    check_engine(engine)
    out = output_dir(out, "--out")
    count = trials or task.trials
    require_disk(out, count * BYTES_PER_TRIAL_LOG, f"--trials {count}")  # before planning them
    planned = plan_trials(task, spec, model=model, trials=trials, seed=seed, metric=metric, cup=cup,
                          policy_args=policy_args, camera=camera_spec)
    staging = staging_dir(out)
    if out.is_dir() and any(out.iterdir()):
        if not overwrite:
            raise InputError(f"--out '{out}': not empty (a finished run? pass --overwrite to replace a run, or "
                             "choose another --out)")
        check_removable_run(out)
    run = {"task": asdict(task), "policy": label, "policy_spec": spec, "policy_args": policy_args,
           "policy_config": policy_config, "model": model,
           "model_used": model_used(spec, model, policy_args),
           "metric": metric, "cup": cup, "camera": intrinsics.name, "trials": len(planned),
           "seed": seed if seed is not None else task.seed, "compute_model": CYCLE_MODEL.compute_time(spec),
           "command": command, "versions": _versions()}
    resumed = False
    if staging.exists():
        if overwrite:
            remove_run(staging)
        elif not resume:
            raise InputError(f"--out '{out}': an interrupted run is in '{staging}' (pass --resume to finish it or "
                             "--overwrite to start over)")
        else:
            _check_same_run(staging, run)
            resumed = True
    log_dir = staging / "trials"
    try:
        log_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"output '{out}': cannot create it ({exc.strerror})") from None
    for stale in log_dir.glob(".*.part"):  # logs a killed run did not finish: those trials run again
        stale.unlink()
    with atomic_path(staging / "run.json") as tmp:
        tmp.write_text(json.dumps(json_safe(run), indent=1, allow_nan=False))
    todo = [t for t in planned if not (log_dir / trial_log_name(t.index)).is_file()]
    if resume and not resumed and notify is not None:
        why = "started over (--overwrite)" if overwrite else f"nothing to resume: no '{staging}'"
        notify(f"--resume: {why}; running all {len(planned)} trials")
    if progress and len(todo) < len(planned):
        progress(len(planned) - len(todo))
    from suctionbench.parallel import map_ordered

    for _ in map_ordered(run_trial, [(t, str(log_dir)) for t in todo], engine=engine, workers=workers,
                         address=address):
        if progress:
            progress(1)
    status = run_status(staging)
    if not status["complete"]:
        raise RuntimeError(f"run '{staging}' is incomplete after all its trials ran: {status}")
    publish_dir(staging, out)
    return {**summarize_run(out), "resumed": resumed, "trials_reused": len(planned) - len(todo)}


INCOMPLETE_SUFFIX = ".incomplete"
RUN_NAME = "run.json"
TRIAL_DIR = "trials"
_TRIAL_RE = re.compile(r"^trial_(\d{5,})\.mcap$")
_IDENTITY_SKIP = ("command", "versions")
"""run.json entries that may differ between a run and its resumption."""


def staging_dir(out: Path) -> Path:
    """Where a run is written until its last trial is logged: the sibling ``OUT.incomplete``."""
    out = Path(out)
    return out.with_name(out.name + INCOMPLETE_SUFFIX)


def trial_log_name(index: int) -> str:
    return f"trial_{index:05d}.mcap"


def read_run_json(run_dir: Path) -> dict[str, Any]:
    """A run's run.json, checked for what reports need; InputError naming the file otherwise."""
    path = Path(run_dir) / RUN_NAME
    if not path.exists():
        raise InputError(f"run '{run_dir}': no run.json (not a suctionbench eval run)")
    run = read_json(path, "run file", "not a suctionbench eval run", malformed="; truncated?")
    task = run.get("task") if isinstance(run, dict) else None
    problem = (
        "not a JSON object" if not isinstance(run, dict)
        else "'task' is not an object with a name and a set" if not (
            isinstance(task, dict) and isinstance(task.get("name"), str) and isinstance(task.get("set"), str))
        else "'policy' is not a name" if not isinstance(run.get("policy"), str)
        else "'trials' is not a positive count" if isinstance(run.get("trials"), bool)
        or not isinstance(run.get("trials"), int) or run["trials"] < 1
        else None
    )
    if problem:
        raise InputError(f"run file '{path}': {problem} (not a suctionbench run.json)")
    return run


def run_status(run_dir: Path, run: dict[str, Any] | None = None) -> dict[str, Any]:
    """How complete a run directory is: its expected trials (run.json) against the trial logs found,
    unfinished logs (``.part``, left by a killed writer) and logs that are not among its trials."""
    run_dir = Path(run_dir)
    run = run if run is not None else read_run_json(run_dir)
    found, unfinished = set(), []
    log_dir = run_dir / TRIAL_DIR
    if log_dir.is_dir():
        for path in log_dir.iterdir():
            m = _TRIAL_RE.match(path.name)
            if m and path.is_file():
                found.add(int(m.group(1)))
            elif path.name.endswith(".part"):
                unfinished.append(path.name)
    expected = set(range(run["trials"]))
    missing, extra = sorted(expected - found), sorted(found - expected)
    return {"complete": not (missing or extra or unfinished),
            "expected_trials": run["trials"], "found_trials": len(found & expected), "missing_trials": missing,
            "extra_trials": extra, "unfinished_logs": sorted(unfinished)}


def describe_status(run_dir: Path, status: dict[str, Any]) -> str:
    """One line saying why a run is not complete."""
    parts = [f"{status['found_trials']} of {status['expected_trials']} trial logs"]
    if status["unfinished_logs"]:
        parts.append(f"{len(status['unfinished_logs'])} unfinished (.part)")
    if status["extra_trials"]:
        parts.append(f"{len(status['extra_trials'])} not among its trials "
                     f"({trial_log_name(status['extra_trials'][0])})")
    hint = ("interrupted: finish it with eval --resume" if Path(run_dir).name.endswith(INCOMPLETE_SUFFIX)
            or status["missing_trials"] or status["unfinished_logs"] else "stray trial logs")
    return f"run '{run_dir}': incomplete: {', '.join(parts)} ({hint})"


REPORT_SUFFIXES = (".html", ".md", ".png")
"""What a report directory holds (all written by `suctionbench.evaluation.report.build_report`)."""


def not_a_report(out: Path) -> str | None:
    """Why an existing, non-empty `out` is not a report that a new one may replace (None: it is one)."""
    entries = list(out.iterdir())
    other = next((e for e in entries if not (e.is_file() and e.suffix in REPORT_SUFFIXES)), None)
    if other is not None:
        return f"holds '{other.name}', which report did not write"
    if not any(e.name in ("index.html", "report.md") for e in entries):
        return "holds files but no report (index.html)"
    return None


def _run_entries_ok(run_dir: Path) -> str | None:
    """None if `run_dir` holds only what eval writes (run.json, trials/ logs) and reports built from it
    (`report RUN --out RUN/report`), else the first other entry."""
    for entry in sorted(run_dir.iterdir()):
        if entry.name == RUN_NAME and entry.is_file():
            continue
        if entry.name != TRIAL_DIR and entry.is_dir() and not entry.is_symlink() and not_a_report(entry) is None:
            continue
        if entry.name == TRIAL_DIR and entry.is_dir() and not entry.is_symlink():
            for log in sorted(entry.iterdir()):
                if not (log.is_file() and (_TRIAL_RE.match(log.name) or log.name.endswith((".part", ".tmp")))):
                    return str(log.relative_to(run_dir))
            continue
        return entry.name
    return None


def check_removable_run(run_dir: Path) -> None:
    """InputError unless `run_dir` is an eval run that --overwrite may replace (nothing else in it)."""
    read_run_json(run_dir)
    other = _run_entries_ok(run_dir)
    if other:
        raise InputError(f"--overwrite '{run_dir}': holds '{other}', which eval did not write; nothing removed "
                         "(choose another --out)")


def remove_run(run_dir: Path) -> None:
    """Delete an eval run directory after `check_removable_run` (never a directory with other files)."""
    import shutil

    check_removable_run(run_dir)
    shutil.rmtree(run_dir)


def built_policy_config(spec: str, policy_args: dict[str, Any], model: str | None) -> dict[str, Any] | None:
    """Build the policy `spec` with `policy_args` (and `model` where it reads one) and return its
    config as a dict, every field with defaults included, so that a run stays readable when a
    default changes; None for the known-state policies (planned in the simulation, not built) and
    for a plug-in without a dataclass config. InputError for an unknown policy or bad options,
    before any work."""
    from suctionbench.config import to_dict
    from suctionbench.policies.base import MODEL_POLICIES
    from suctionbench.policies.plugins import builtin_name, load_policy
    from suctionbench.sim.pick import KNOWN_STATE_POLICIES

    if spec in KNOWN_STATE_POLICIES:
        return None
    kwargs = dict(policy_args)
    if model and builtin_name(spec) in MODEL_POLICIES:
        kwargs.setdefault("model", model)
    config = getattr(load_policy(spec, kwargs), "config", None)
    return to_dict(config) if dataclasses.is_dataclass(config) and not isinstance(config, type) else None


def _check_same_run(staging: Path, run: dict[str, Any]) -> None:
    """InputError if the interrupted run in `staging` has another configuration than `run`."""
    old = read_run_json(staging)
    new = json.loads(json.dumps(json_safe(run)))
    changed = sorted(k for k in set(old) | set(new) if k not in _IDENTITY_SKIP and old.get(k) != new.get(k))
    if changed:
        raise InputError(f"--resume: the interrupted run in '{staging}' has another configuration (differs in: "
                         f"{', '.join(changed)}); pass --overwrite to start over")


def _invocation() -> str | None:
    """This process's command line when it is the `suctionbench` CLI (for run.json), else None."""
    import shlex
    import sys

    if Path(sys.argv[0]).name not in ("suctionbench", "__main__.py") or len(sys.argv) < 2:
        return None
    return " ".join(["suctionbench", *map(shlex.quote, sys.argv[1:])])


def _versions() -> dict[str, str]:
    """Versions of the software a run's numbers depend on (recorded in run.json, shown by reports)."""
    import platform

    import mujoco

    from suctionbench import __version__

    versions = {"suctionbench": __version__, "python": platform.python_version(), "numpy": np.__version__,
                "mujoco": mujoco.__version__}
    try:
        from importlib.metadata import version

        versions["torch"] = version("torch")
    except Exception:  # torch is a dependency; a broken install only loses the entry
        pass
    return versions


def _check_model(model: str | None) -> None:
    from suctionbench.learning.checkpoint import load_model
    from suctionbench.policies.gqcnn import default_model_dir

    load_model(model or default_model_dir())


def run_records(run_dir: Path) -> list[dict[str, Any]]:
    """The result record of each of a run's trials whose log exists (only its own trials, by index),
    each with its log's path under "log"."""
    from suctionbench.runlog.reader import read_episode

    run_dir = Path(run_dir)
    logs = [run_dir / TRIAL_DIR / trial_log_name(i) for i in range(read_run_json(run_dir)["trials"])]
    episodes = [read_episode(path) for path in logs if path.is_file()]
    return [episode["result"] | {"log": episode["path"]} for episode in episodes if episode.get("result")]


def summarize_run(run_dir: Path, records: list[dict[str, Any]] | None = None) -> dict[str, Any]:
    """Results table of a run directory, computed from its MCAP logs (`records`: those logs'
    `run_records`, when the caller has read them already). "label" names the run in tables: the
    policy, with the metric for the analytic one."""
    run_dir = Path(run_dir)
    run = read_run_json(run_dir)
    if records is None:
        records = run_records(run_dir)
    status = run_status(run_dir, run)
    from suctionbench.policies.base import RANKING_POLICIES

    label = f"{run['policy']}-{run.get('metric')}" if run["policy"] in RANKING_POLICIES else run["policy"]
    return {"policy": run["policy"], "label": label, "task": run["task"]["name"], "set": run["task"]["set"],
            "metric": run.get("metric"), "seed": run.get("seed"), **trial_metrics(records, modelled_compute(run)),
            "complete": status["complete"], "expected_trials": status["expected_trials"]}


def score_stats(scores: np.ndarray, success: np.ndarray) -> dict[str, float | None]:
    """How well scores in [0, 1] predict simulated success: average precision, accuracy of the
    0.5 threshold and Spearman rank correlation (the paper's classification columns); NaN scores
    are left out, and a statistic that is undefined (no success, constant input) is None."""
    from scipy.stats import spearmanr

    from suctionbench.learning.metrics import average_precision

    keep = np.isfinite(scores)
    scores, success = scores[keep], success[keep]
    if not len(scores):
        return {"ap": None, "accuracy": None, "spearman": None}
    ap = float(average_precision(success, scores)) if success.any() else None
    rho = None
    if len(scores) > 2 and success.std() > 0 and scores.std() > 0:
        rho = float(spearmanr(scores, success).statistic)
    return {
        "ap": None if ap is None else round(ap, 4),
        "accuracy": round(float(((scores > 0.5) == success).mean()), 4),
        "spearman": None if rho is None or math.isnan(rho) else round(rho, 4),
    }


def trial_metrics(records: list[dict[str, Any]], compute: dict[str, float] | None = None) -> dict[str, Any]:
    """AP of the policy's q against simulated success, success rate, analytic-label precision,
    picks per hour with the mean time per phase, how well each 3D metric's score of the executed
    grasp predicts success, and outcome counts.

    Picks per hour (and `mean_cycle_s`) come from the deterministic cycle of
    `suctionbench.evaluation.cycle`: the mean simulated motion time plus `compute`, the modelled
    sensing and planning seconds of one attempt (default: none). The measured wall times of
    sensing and planning are reported separately (`mean_sensing_s`, `mean_plan_s`) with the picks
    per hour they would give (`picks_per_hour_wall`), which varies from run to run."""
    compute = compute or {"sensing_s": 0.0, "planning_s": 0.0}
    valid = [r for r in records if r.get("valid")]
    success = np.array([bool(r["success"]) for r in valid])
    q = np.array([np.nan if r.get("policy_q") is None else float(r["policy_q"]) for r in valid])
    rwr = np.array([np.nan if r.get("label_rwr") is None else float(r["label_rwr"]) for r in valid])
    q_stats = score_stats(q, success)
    predicted = rwr > PREDICT_THRESHOLD
    phases = {name: np.array([float(r.get(key) or 0.0) for r in valid])
              for name, key in (("sensing", "sensing_time"), ("plan", "plan_time"), ("motion", "sim_time"))}
    wall_cycle = sum(phases.values()) if valid else np.zeros(0)
    modelled = float(compute["sensing_s"]) + float(compute["planning_s"])
    cycle = phases["motion"] + modelled
    rate = float(success.mean()) if len(valid) else 0.0
    scored = [r for r in valid if r.get("label_scores")]
    by_metric = {
        name: score_stats(np.array([r["label_scores"][name] for r in scored]),
                          np.array([bool(r["success"]) for r in scored]))
        for name in (scored[0]["label_scores"] if scored else ())
    }
    return {
        "trials": len(records),
        "invalid": len(records) - len(valid),
        "success_rate": round(rate, 4),
        "ap": q_stats["ap"],
        "accuracy_q": q_stats["accuracy"],
        "spearman_q": q_stats["spearman"],
        "label_precision": round(float(success[predicted].mean()), 4) if predicted.any() else None,
        "label_positive_rate": round(float(predicted.mean()), 4) if len(valid) else None,
        "mean_cycle_s": round(float(cycle.mean()), 3) if len(valid) else None,
        "picks_per_hour": picks_per_hour(rate, float(cycle.mean())) if len(valid) else None,
        "modelled_sensing_s": round(float(compute["sensing_s"]), 4),
        "modelled_plan_s": round(float(compute["planning_s"]), 4),
        "picks_per_hour_wall": picks_per_hour(rate, float(wall_cycle.mean())) if len(valid) else None,
        **{f"mean_{name}_s": round(float(t.mean()), 4) if len(valid) else None for name, t in phases.items()},
        "by_metric": by_metric,
        "outcomes": dict(sorted(Counter(r["failure"] or "success" for r in records).items())),
        "per_object": _per_object(valid),
    }


def _per_object(valid: list[dict[str, Any]]) -> dict[str, list[int]]:
    table: dict[str, list[int]] = {}
    for r in valid:
        table.setdefault(r["object"], [0, 0])
        table[r["object"]][0] += bool(r["success"])
        table[r["object"]][1] += 1
    return dict(sorted(table.items()))
