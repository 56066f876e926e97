"""Reports built from run directories (their MCAP logs), never from memory: a headline figure
(success and AP per policy and set beside the paper's physical results), the side-by-side tables
(policies x sets, known objects, the pick cycle), precision-recall and success-vs-attempt-rate
curves, per-object counts beside a thumbnail of each object, a gallery of failures (depth crop
around the executed grasp), and, at the bottom, each run's command and the software versions.
The paper's numbers live in `suctionbench.evaluation.paper` with their source."""

from __future__ import annotations

import html
import itertools
import shlex
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.errors import InputError
from suctionbench.evaluation.paper import CITATION, PAPER_KNOWN, PAPER_RANDOM, PAPER_RESULTS
from suctionbench.evaluation.runner import (
    INCOMPLETE_SUFFIX,
    describe_status,
    not_a_report,
    read_run_json,
    run_records,
    run_status,
    staging_dir,
    summarize_run,
)
from suctionbench.io import atomic_dir, atomic_path
from suctionbench.policies.base import (
    IMAGE_KNOWN_STATE_POLICIES,
    KNOWN_STATE_POLICIES,
    RANKING_POLICIES,
    UNIFORM_DENSITY_POLICIES,
)
from suctionbench.validate import output_dir

__all__ = ["PAPER_KNOWN", "PAPER_RANDOM", "PAPER_RESULTS", "build_report", "expand_run_dirs",
           "success_attempt_curve"]

POLICY_ORDER = ("random", "planarity", "centroid", "planarity-centroid", "gqcnn", "fc-gqcnn",
                "gqcnn-adv", "fc-gqcnn-adv")
"""Row order of the policies x sets table (the paper's, weakest baseline first)."""

GALLERY_PER_RUN = 6
"""Failed trials of each run shown in the gallery."""

QUALITY_MAPS_PER_RUN = 4
"""Trials of a dense policy's run whose quality map the report shows (successes and failures)."""

FAILURES = "Failures (depth around the executed grasp)"
QUALITY_MAPS = ("Quality maps (dense policy: q per pixel from red 0 to green 1 over the depth it planned on; "
                "white cross: the executed grasp)")
"""Titles of the report's galleries."""


@dataclass
class Table:
    """One table of the report."""

    title: str
    """Section heading."""

    note: str
    """What the table shows and how it compares with the paper."""

    rows: list[dict[str, Any]] = field(default_factory=list)
    """Rows with the same keys, in column order."""


def expand_run_dirs(paths: list[Path]) -> list[Path]:
    """Run directories: each path that holds a run.json, else the runs found below it (a directory
    of runs, or `eval --task known_objects` with one run per metric), in sorted order."""
    if not paths:
        raise InputError("report: give at least one run directory")
    runs = []
    for path in map(Path, paths):
        if not path.exists() and staging_dir(path).is_dir():
            path = staging_dir(path)  # an interrupted eval: reported as such, not as 'not found'
        found = [path] if (path / "run.json").is_file() else sorted(p.parent for p in path.glob("**/run.json"))
        if not found:
            raise InputError(f"run '{path}': no run.json in it or below it (not a suctionbench eval run)")
        runs += found
    return runs


def success_attempt_curve(q: np.ndarray, success: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(attempt rate, success rate among attempts) when only grasps with q >= tau are attempted,
    over every threshold tau (the paper's appendix, "Performance Metrics")."""
    order = np.argsort(-q)
    attempted = np.arange(1, len(q) + 1)
    return attempted / len(q), np.cumsum(success[order]) / attempted


def _percent(value: float | None) -> float | None:
    return None if value is None else round(100.0 * value, 1)


def _delta(ours: float | None, paper: float | None) -> str:
    """Ours minus the paper's, in percentage points."""
    return "-" if ours is None or paper is None else f"{ours - paper:+.0f}"


def _order(set_name: str, policy: str) -> tuple[int, int, str]:
    """Rows by set (basic, typical, adversarial, others), then by policy (POLICY_ORDER, others)."""
    sets = ("basic", "typical", "adversarial")
    return (sets.index(set_name) if set_name in sets else len(sets),
            POLICY_ORDER.index(policy) if policy in POLICY_ORDER else len(POLICY_ORDER), policy)


def _sum(*values: float | None) -> float | None:
    return None if any(v is None for v in values) else round(sum(values), 4)


def _tables(summaries: list[dict[str, Any]]) -> list[Table]:
    """The report's tables: policies x sets, known objects per metric, random-grasp
    classification per metric, and where the time of a pick goes."""
    novel = Table("Novel objects: policies x sets",
                  "AP of the policy's q against simulated success; label precision: share of simulated "
                  "successes among executed grasps the analytic label (rwr > 0.5) calls robust. Paper: "
                  "physical YuMi trials (Dex-Net 3.0, table \"Performance on Novel Objects\").")
    known = Table("Known objects: top-ranked grasp per 3D metric",
                  "Shape and pose known; the grasp with the highest score of the metric is executed. "
                  "AP of that score against simulated success. Paper: 75 physical trials.")
    classified = Table("Known objects: random-grasp classification",
                       "Random reachable surface grasps, each scored by every 3D metric in the true state; "
                       "AP, accuracy (score > 0.5) and Spearman rank correlation against simulated success.")
    timing = Table("The pick cycle (means per trial)",
                   "Picks per hour = success rate / cycle, the cycle being the simulated motion (approach, "
                   "lift, transport) plus a modelled compute time (one 30 Hz depth frame and the policy's "
                   "planning time, suctionbench.evaluation.cycle), so the same seeds give the same figure. "
                   "Measured wall times of this run (rendering the noisy depth image, planning) and the "
                   "picks per hour they would give are reported beside it; they vary with the machine's load.")
    seeded = _seeded(_studies(summaries))
    for s in summaries:
        label = s["label"]
        success = _percent(s["success_rate"])
        mark = "" if s.get("complete", True) else f" (incomplete {s['trials']}/{s['expected_trials']})"
        mark += seeded(s)
        if s["policy"] in RANKING_POLICIES:
            image = s["policy"] in IMAGE_KNOWN_STATE_POLICIES
            paper = PAPER_KNOWN.get(s["metric"]) if s["set"] == "adversarial" and not image else None
            name = s["metric"] + (" of the image's grasps" if image else "")
            name += ", uniform density believed" if s["policy"] in UNIFORM_DENSITY_POLICIES else ""
            known.rows.append({"metric": name + mark, "set": s["set"], "trials": s["trials"],
                               "AP %": _percent(s["ap"]), "success %": success,
                               "paper AP / success %": f"{paper[0]} / {paper[1]}" if paper else "-",
                               "success - paper (points)": _delta(success, paper and paper[1])})
        elif s["policy"] == "random-surface":
            for metric, stats in s["by_metric"].items():
                paper = PAPER_RANDOM.get(metric) if s["set"] == "adversarial" else None
                classified.rows.append({
                    "metric": metric + mark, "set": s["set"], "grasps": s["trials"], "successes": round(
                        s["success_rate"] * (s["trials"] - s["invalid"])),
                    "AP %": _percent(stats["ap"]), "accuracy %": _percent(stats["accuracy"]),
                    "Spearman": stats["spearman"],
                    "paper AP / acc. % / Spearman": f"{paper[0]} / {paper[1]} / {paper[2]}" if paper else "-"})
        else:
            paper = PAPER_RESULTS.get(s["policy"], {}).get(s["set"])
            novel.rows.append({"policy": s["policy"] + mark, "set": s["set"], "trials": s["trials"],
                               "AP %": _percent(s["ap"]), "success %": success,
                               "label precision %": _percent(s["label_precision"]),
                               "picks/hour": s["picks_per_hour"],
                               "paper success (AP) %": f"{paper[0]} ({paper[1]})" if paper else "-",
                               "success - paper (points)": _delta(success, paper and paper[0])})
        timing.rows.append({"run": f"{label}{seeded(s)} / {s['set']}", "motion s": s["mean_motion_s"],
                            "compute s (model)": _sum(s.get("modelled_sensing_s"), s.get("modelled_plan_s")),
                            "cycle s": s["mean_cycle_s"], "success %": success, "picks/hour": s["picks_per_hour"],
                            "sensing s (wall)": s["mean_sensing_s"], "planning s (wall)": s["mean_plan_s"],
                            "picks/hour (wall)": s.get("picks_per_hour_wall")})
    pooled = _pooled(summaries)
    novel.rows.sort(key=lambda r: _order(r["set"], r["policy"].split(" ")[0]))
    timing.rows.sort(key=lambda r: _order(*reversed(r["run"].split(" / "))))
    known.rows.sort(key=lambda r: list(PAPER_KNOWN).index(r["metric"]) if r["metric"] in PAPER_KNOWN else 0)
    return [t for t in (novel, pooled, known, classified, timing) if t.rows]


def _pool(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Runs' trials pooled: successes / valid trials of each run, the pooled success rate (None
    without a valid trial) and the mean of the runs' APs (None where none has one)."""
    per_run = [(round(r["success_rate"] * (r["trials"] - r["invalid"])), r["trials"] - r["invalid"]) for r in runs]
    valid = sum(v for _, v in per_run)
    aps = [r["ap"] for r in runs if r["ap"] is not None]
    return {"per_run": per_run, "valid": valid, "success": sum(w for w, _ in per_run) / valid if valid else None,
            "ap": sum(aps) / len(aps) if aps else None}


def _studies(summaries: list[dict[str, Any]]) -> dict[tuple[str, str, str], list[dict[str, Any]]]:
    """The runs grouped into studies, (label, task, set) -> runs in order: the runs of one policy on
    one task and set are seeds of one study."""
    studies: dict[tuple[str, str, str], list[dict[str, Any]]] = {}
    for s in summaries:
        studies.setdefault((s["label"], s["task"], s["set"]), []).append(s)
    return studies


def _several_seeds(runs: list[dict[str, Any]]) -> bool:
    """Whether a study's runs hold more than one seed (two tasks of one policy and set are not seeds)."""
    return len({r.get("seed") for r in runs}) > 1


def _seeded(studies: dict[tuple[str, str, str], list[dict[str, Any]]]):
    """A function giving a run's " [seed N]" where its study (`_studies`) holds more than one seed,
    "" otherwise, so one run's report reads as before."""
    several = {key for key, runs in studies.items() if _several_seeds(runs)}
    return lambda s: f" [seed {s.get('seed')}]" if (s["label"], s["task"], s["set"]) in several else ""


def _pooled(summaries: list[dict[str, Any]]) -> Table:
    """Policies (and the known-state analytic policy) run on one set with several seeds, their trials
    pooled: one seeded run of ~100 trials has a standard error of ~4.5 points, so a ranking of
    policies is read here, not from any one seed's row."""
    table = Table("Novel objects: pooled over seeds",
                  "Runs of one policy on one set with different seeds (the same seed's scenes are the same "
                  "for every policy): successes over all valid trials with the binomial standard error, "
                  "each seed's successes / valid trials, and the mean of the seeds' AP.")
    for (label, _, set_name), runs in _studies(summaries).items():
        if runs[0]["policy"] == "random-surface" or not _several_seeds(runs):
            continue
        runs = sorted(runs, key=lambda r: (r.get("seed") is None, r.get("seed") or 0))
        pool = _pool(runs)
        rate, n = pool["success"], pool["valid"]
        table.rows.append({
            "policy": label, "set": set_name, "seeds": ", ".join(str(r.get("seed")) for r in runs),
            "trials": n, "success %": _percent(rate),
            "+- se (points)": None if rate is None else round(100 * (rate * (1 - rate) / n) ** 0.5, 1),
            "per seed": ", ".join(f"{w}/{v}" for w, v in pool["per_run"]), "mean AP %": _percent(pool["ap"])})
    table.rows.sort(key=lambda r: _order(r["set"], r["policy"]))
    return table


def build_report(run_dirs: list[Path], out: Path, command: str | None = None,
                 allow_incomplete: bool = False) -> dict[str, Any]:
    """Write out/report.md, out/index.html and the figures; returns the tables. `command` is the
    command line that built the report (shown at the bottom; default: this process's).

    A run whose trial logs do not match its run.json (killed, or stray logs) is refused, or with
    `allow_incomplete` reported with "(incomplete k/n)" after its name and listed under
    "incomplete" in the result. The report is written to a temporary sibling of `out` and renamed
    into place at the end (all or nothing); an `out` that holds anything but an old report is
    refused."""
    from suctionbench.clutter.report import is_bin_run

    run_dirs = expand_run_dirs(run_dirs)
    bin_dirs = [d for d in run_dirs if is_bin_run(d)]  # bin runs are written whole: never incomplete
    run_dirs = [d for d in run_dirs if d not in bin_dirs]
    incomplete = []
    for run_dir in run_dirs:
        status = run_status(run_dir)
        if not status["complete"] or run_dir.name.endswith(INCOMPLETE_SUFFIX):
            if not allow_incomplete:
                raise InputError(describe_status(run_dir, status) + "; or pass --allow-incomplete")
            incomplete.append({"run": str(run_dir), **status})
    output_dir(out, "--out")
    all_records = [run_records(run_dir) for run_dir in run_dirs]  # each log is read once
    summaries = [summarize_run(run_dir, records) for run_dir, records in zip(run_dirs, all_records, strict=True)]
    for s, run_dir in zip(summaries, run_dirs, strict=True):
        if any(i["run"] == str(run_dir) for i in incomplete):
            s["complete"] = False
            s["label"] += f" (incomplete {s['trials']}/{s['expected_trials']})"
    final = Path(out)
    with atomic_dir(final, not_a_report) as out:
        result = _write_report(run_dirs, summaries, all_records, out, command, bin_dirs)
    return {"out": str(final), **result, "incomplete": incomplete}


def _write_report(run_dirs: list[Path], summaries: list[dict[str, Any]], all_records: list[list[dict[str, Any]]],
                  out: Path, command: str | None, bin_dirs: list[Path] = ()) -> dict[str, Any]:
    """The report's files in `out` (a fresh directory); returns the tables and figure names. Bin
    runs (`bin_dirs`) add their sections (`suctionbench.clutter.report`)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from suctionbench.evaluation.figures import headline_figure, save_figure, style_axes
    from suctionbench.learning.metrics import precision_recall_curve

    galleries: dict[str, list[tuple[str, str]]] = {FAILURES: [], QUALITY_MAPS: []}  # title -> (png, caption)
    per_object = {}
    curves: dict[str, list[tuple[str, np.ndarray, np.ndarray]]] = {}  # figure group -> (label, q, success)
    studies = _studies(summaries)
    seeded = _seeded(studies)
    tasks: dict[tuple[str, str], set] = {}  # two tasks of one policy and set (known_objects) keep apart
    for label, task, set_name in studies:
        tasks.setdefault((label, set_name), set()).add(task)
    for run_dir, summary, records in zip(run_dirs, summaries, all_records, strict=True):
        valid = [r for r in records if r.get("valid")]
        known = summary["policy"] in RANKING_POLICIES
        label = summary["label"] + seeded(summary)
        task = f" ({summary['task']})" if len(tasks[(summary["label"], summary["set"])]) > 1 else ""
        counts = per_object.setdefault(f"{summary['label']} / {summary['set']}{task}", {})  # seeds add up
        for key, (wins, trials) in summary["per_object"].items():
            before = counts.get(key, (0, 0))
            counts[key] = [before[0] + wins, before[1] + trials]
        success = np.array([bool(r["success"]) for r in valid])
        q = np.array([np.nan if r.get("policy_q") is None else float(r["policy_q"]) for r in valid])
        keep = np.isfinite(q)
        if keep.any() and success[keep].any():
            group = f"{summary['set']}_known" if known else summary["set"]
            curves.setdefault(group, []).append((label, q[keep], success[keep]))
        caption = f"{label} / {summary['set']}"
        galleries[FAILURES] += _gallery(run_dir, [r for r in records if not r.get("success")], out, caption)
        galleries[QUALITY_MAPS] += _quality_gallery(run_dir, records, out, caption)
    figures = []
    headline = [{"policy": label, "set": set_name, "success": pool["success"] or 0.0, "ap": pool["ap"]}
                for (label, _, set_name), runs in studies.items()  # one bar per study, seeds pooled
                if runs[0]["policy"] not in KNOWN_STATE_POLICIES for pool in [_pool(runs)]]
    if headline_figure(headline, out / "headline.png", POLICY_ORDER):
        figures.append("headline.png")
    for group in sorted(curves, key=lambda g: _order(g.removesuffix("_known"), "") + (g,)):
        lines = curves[group]  # one pair of figures per set, so the lines stay readable
        fig, (ax_pr, ax_sa) = plt.subplots(1, 2, figsize=(10, 4))
        for label, q, success in lines:
            precision, recall, _ = precision_recall_curve(success, q)
            ax_pr.plot(recall, precision, label=label, lw=1)
            ax_sa.plot(*success_attempt_curve(q, success), label=label, lw=1)
        for ax, (xl, yl) in ((ax_pr, ("recall", "precision")), (ax_sa, ("attempt rate", "success rate"))):
            style_axes(ax, xl, yl, f"{group.replace('_', ' ')}: {yl} vs {xl}")
        figures.append(save_figure(fig, out, f"curves_{group}.png"))
    tables = _tables(summaries)
    objects = _object_cards(per_object, out)
    runs = [_run_info(run_dir, summary) for run_dir, summary in zip(run_dirs, summaries, strict=True)]
    if bin_dirs:
        from suctionbench.clutter.report import BIN_GALLERY, bin_sections

        sections = bin_sections(list(bin_dirs), out)
        tables += [Table(title, note, rows) for title, note, rows in sections["tables"]]
        figures += sections["figures"]
        galleries[BIN_GALLERY] = sections["gallery"]
        runs += sections["footer"]
    footer = {"runs": runs, "versions": _versions(runs),
              "report_command": command or " ".join(["suctionbench", *map(_quote, sys.argv[1:])])}
    _write_markdown(out, tables, figures, objects, galleries, footer)
    _write_html(out, tables, figures, objects, galleries, footer)
    return {"tables": {t.title: t.rows for t in tables}, "rows": tables[0].rows if tables else [],
            "figures": figures}


def _quote(arg: str) -> str:
    return shlex.quote(arg)


def _run_info(run_dir: Path, summary: dict[str, Any]) -> dict[str, Any]:
    """What the bottom of the report says about a run: label, set, trials, seed, camera, command."""

    run = read_run_json(Path(run_dir))
    return {"run": f"{summary['label']} / {summary['set']}", "trials": summary["trials"], "seed": run.get("seed"),
            "camera": run.get("camera", "primesense"), "cup": run.get("cup"), "model": run.get("model_used"),
            "command": run.get("command") or "-", "versions": run.get("versions") or {}}


def _versions(runs: list[dict[str, Any]]) -> dict[str, str]:
    """Software versions of the runs (one value per package, or the distinct values joined)."""
    found: dict[str, list[str]] = {}
    for run in runs:
        for name, version in run["versions"].items():
            if version not in found.setdefault(name, []):
                found[name].append(version)
    if not found:  # runs that predate recorded versions: the report's own
        from suctionbench import __version__

        found = {"suctionbench": [__version__]}
    return {name: " / ".join(values) for name, values in found.items()}


def _object_cards(per_object: dict[str, dict[str, list[int]]], out: Path) -> list[dict[str, Any]]:
    """One card per object of the runs: its thumbnail (ray-cast from its mesh; None when the
    object is no longer built) and its successes / trials in each run, objects by set then name."""
    from suctionbench.evaluation.figures import object_thumbnail
    from suctionbench.objects.registry import load_object
    from suctionbench.sensing.image import save_png

    keys = sorted({k for counts in per_object.values() for k in counts},
                  key=lambda k: _order(k.split("/")[0], "")[:1] + (k,))
    cards = []
    for key in keys:
        image = f"object_{key.replace('/', '_')}.png"
        try:
            save_png(out / image, object_thumbnail(load_object(key).mesh(), size=96))
        except (InputError, OSError, ValueError):
            image = None
        cards.append({"object": key, "image": image,
                      "counts": [(run, *counts[key]) for run, counts in per_object.items() if key in counts]})
    return cards


def _gallery(run_dir: Path, failed: list[dict[str, Any]], out: Path, label: str) -> list[tuple[str, str]]:
    """Depth crops (96 x 96 px) around the executed grasp of up to GALLERY_PER_RUN failed trials."""
    from suctionbench.sensing.image import save_png

    items = []
    for r in [r for r in failed if r.get("grasp_world")][:GALLERY_PER_RUN]:  # failures that executed a grasp
        path = Path(r["log"])
        view = _planned_view(path, r)
        if view is None:
            continue
        depth, (u, v) = view
        name = f"fail_{run_dir.name}_{path.stem}.png"
        save_png(out / name, _crop(depth, int(round(u)), int(round(v)), 48))
        items.append((name, f"{label}: {r['object']} - {r['failure']}"))
    return items


def _quality_gallery(run_dir: Path, records: list[dict[str, Any]], out: Path, label: str) -> list[tuple[str, str]]:
    """Quality maps (`figures.quality_overlay`) of up to QUALITY_MAPS_PER_RUN trials whose log has
    one (a dense policy's), successes and failures alternating."""
    from suctionbench.evaluation.figures import quality_overlay
    from suctionbench.runlog.reader import float_image, iter_messages
    from suctionbench.runlog.writer import TOPIC_QUALITY_MAP
    from suctionbench.sensing.image import save_png

    executed = [r for r in records if r.get("grasp_world") and r.get("log")]
    good, bad = [r for r in executed if r.get("success")], [r for r in executed if not r.get("success")]
    chosen = [r for pair in itertools.zip_longest(good, bad) for r in pair if r is not None]
    items = []
    for r in chosen:
        if len(items) == QUALITY_MAPS_PER_RUN:
            break
        path = Path(r["log"])
        quality_msg = next(iter_messages(path, TOPIC_QUALITY_MAP), None)
        if quality_msg is None:  # not a dense policy's log: none of this run's trials has one
            break
        quality = float_image(quality_msg[1], "quality map")
        view = _planned_view(path, r)
        if view is None or not np.isfinite(quality).any():
            continue
        name = f"quality_{run_dir.name}_{path.stem}.png"
        save_png(out / name, quality_overlay(view[0], quality, view[1]))
        outcome = "success" if r.get("success") else r.get("failure") or "failure"
        q = r.get("policy_q")
        items.append((name, f"{label}: {r['object']} - {outcome}" + ("" if q is None else f", q {q:.2f}")))
    return items


@dataclass(frozen=True)
class LoggedView:
    """A log's first depth frame with its camera: what a policy planned on."""

    depth: np.ndarray
    k: np.ndarray
    pose: np.ndarray
    """World-from-camera (OpenCV frame)."""

    def pixel(self, point_world: Any) -> tuple[float, float]:
        """Image (u, v) of a world point."""
        p_cam = (np.asarray(point_world, dtype=float)[:3] - self.pose[:3, 3]) @ self.pose[:3, :3]
        u, v = (self.k @ p_cam)[:2] / p_cam[2]
        return float(u), float(v)


def first_view(path: Path) -> LoggedView | None:
    """The first depth frame of a run log with its calibration and camera pose; None if it lacks them."""
    from suctionbench.runlog.reader import depth_image, frame_pose, iter_messages

    depth_msg = next(iter_messages(path, "/camera/depth"), None)
    calib = next(iter_messages(path, "/camera/calibration"), None)
    if depth_msg is None or calib is None:
        return None
    k = np.asarray(calib[1]["K"], dtype=float).reshape(3, 3)
    return LoggedView(depth_image(depth_msg[1]), k, frame_pose(path, "camera"))


def _planned_view(path: Path, record: dict[str, Any]) -> tuple[np.ndarray, tuple[float, float]] | None:
    """The depth image a trial's policy planned on (its log's first frame) and the image (u, v) of
    the executed grasp point in that camera; None if the log lacks them."""
    view = first_view(path) if record.get("grasp_world") else None
    return None if view is None else (view.depth, view.pixel(record["grasp_world"]))


def _crop(depth: np.ndarray, u: int, v: int, half: int) -> np.ndarray:
    padded = np.pad(depth, half)
    crop = padded[v : v + 2 * half, u : u + 2 * half].copy()
    crop[half - 1 : half + 1, :] = np.where(crop[half - 1 : half + 1, :] > 0, crop.max(), 0)  # cross-hair
    crop[:, half - 1 : half + 1] = np.where(crop[:, half - 1 : half + 1] > 0, crop.max(), 0)
    return crop


def _fmt(value: Any) -> str:
    return "-" if value is None else f"{value:.3g}" if isinstance(value, float) else str(value)


INTRO = ("Built from the MCAP logs of the runs by `suctionbench report`. Ours: simulation; where it disagrees "
         f"with the physical trials of {CITATION} it is reported as is, never tuned toward them.")
"""The report's opening paragraph."""


def _write_markdown(out: Path, tables: list[Table], figures, objects, galleries, footer) -> None:
    lines = ["# suctionbench report", "", INTRO, ""]
    if figures and figures[0] == "headline.png":
        lines += ["![Success and AP per policy and set, with the paper's physical results](headline.png)", "",
                  "Bars: simulated success and AP (%); markers: the paper's physical success (diamond) and AP "
                  "(circle).", ""]
    for table in tables:
        keys = list(table.rows[0])
        lines += [f"## {table.title}", "", table.note, "", "| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
        lines += ["| " + " | ".join(_fmt(row[k]) for k in keys) + " |" for row in table.rows]
        lines.append("")
    curves = [f for f in figures if f != "headline.png"]
    lines += ["## Curves", ""] + [f"![{f}]({f})" for f in curves]
    if objects:
        lines += ["", "## Per object (successes / trials)", "", "| object | | runs |", "|---|---|---|"]
    for card in objects:
        image = f"![{card['object']}]({card['image']})" if card["image"] else ""
        counts = "<br>".join(f"{run}: {s}/{n}" for run, s, n in card["counts"])
        lines.append(f"| {card['object']} | {image} | {counts} |")
    for title, items in galleries.items():
        if items or (title == FAILURES and objects):
            lines += ["", f"## {title}", ""]
            lines += [f"![{caption}]({name}) {caption}  " for name, caption in items]
    lines += ["", "## Runs and versions", ""]
    for run in footer["runs"]:
        model = f", model {run['model']}" if run.get("model") else ""
        lines.append(f"- **{run['run']}**: {run['trials']} trials, seed {run['seed']}, camera {run['camera']}, "
                     f"cup {run['cup']}{model}; `{run['command']}`")
    lines += ["", f"Report: `{footer['report_command']}`", "",
              "Versions: " + ", ".join(f"{k} {v}" for k, v in footer["versions"].items())]
    with atomic_path(out / "report.md") as tmp:
        tmp.write_text("\n".join(lines) + "\n")


def _write_html(out: Path, tables: list[Table], figures, objects, galleries, footer) -> None:
    esc = html.escape
    sections = []
    if figures and figures[0] == "headline.png":
        sections.append('<img class="headline" src="headline.png" alt="Success and AP per policy and set, with '
                        'the paper\'s physical results"><p class="caption">Bars: simulated success and AP (%); '
                        "markers: the paper's physical success (diamond) and AP (circle).</p>")
    for table in tables:
        keys = list(table.rows[0])
        head = "".join(f"<th>{esc(k)}</th>" for k in keys)
        body = "".join("<tr>" + "".join(f"<td>{esc(_fmt(row[k]))}</td>" for k in keys) + "</tr>" for row in table.rows)
        sections.append(f"<h2>{esc(table.title)}</h2><p>{esc(table.note)}</p><table><tr>{head}</tr>{body}</table>")
    curves = "".join(f'<img src="{esc(f)}" alt="{esc(f)}">' for f in figures if f != "headline.png")
    cards = "".join(
        '<figure class="object">'
        + (f'<img src="{esc(c["image"])}" width="96" height="96" alt="{esc(c["object"])}">' if c["image"] else "")
        + f"<figcaption><b>{esc(c['object'])}</b>"
        + "".join(f"<br>{esc(run)}: {s}/{n}" for run, s, n in c["counts"]) + "</figcaption></figure>"
        for c in objects
    )
    gallery = "".join(
        f"<h2>{esc(title)}</h2>" + "".join(
            f'<figure><img src="{esc(n)}" width="192" alt="{esc(c)}"><figcaption>{esc(c)}</figcaption></figure>'
            for n, c in items)
        for title, items in galleries.items() if items or (title == FAILURES and objects)
    )
    runs = "".join(
        f"<li><b>{esc(r['run'])}</b>: {r['trials']} trials, seed {esc(str(r['seed']))}, camera "
        f"{esc(str(r['camera']))}, cup {esc(str(r['cup']))}"
        f"{', model ' + esc(str(r['model'])) if r.get('model') else ''}; <code>{esc(r['command'])}</code></li>"
        for r in footer["runs"]
    )
    versions = ", ".join(f"{esc(k)} {esc(v)}" for k, v in footer["versions"].items())
    page = f"""<!doctype html><html><head><meta charset="utf-8"><title>suctionbench report</title>
<style>body{{font-family:sans-serif;margin:2em;max-width:80em}}table{{border-collapse:collapse;margin-bottom:1em}}
td,th{{border:1px solid #999;padding:4px 8px;text-align:right}}td:first-child,th{{text-align:left}}
img{{max-width:100%}}figure{{display:inline-block;margin:4px;width:192px;font-size:small;vertical-align:top}}
figcaption{{overflow-wrap:anywhere}}figure.object{{display:inline-flex;gap:8px;width:330px;align-items:flex-start}}
figure.object img{{flex:none}}code{{font-size:small;overflow-wrap:anywhere}}.caption{{font-size:small}}
footer{{margin-top:2em;border-top:1px solid #999;font-size:small}}</style></head><body>
<h1>suctionbench report</h1><p>{esc(INTRO)}</p>
{"".join(sections)}<h2>Curves</h2>{curves}
{"<h2>Per object (successes / trials)</h2>" + cards if objects else ""}{gallery}
<footer><h2>Runs and versions</h2><ul>{runs}</ul><p>Report: <code>{esc(footer["report_command"])}</code></p>
<p>Versions: {versions}</p></footer></body></html>"""
    with atomic_path(out / "index.html") as tmp:
        tmp.write_text(page)
