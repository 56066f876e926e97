"""The bin-picking sections of `suctionbench report`: a table of policies x bin tasks, clearance
curves (objects removed against attempts, per task), and a gallery of each task's first bin as the
first policy saw it, with every attempt's grasp marked."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.clutter.benchmark import LOG_DIR, RUN_KIND, bin_log_name
from suctionbench.clutter.runner import bin_metrics
from suctionbench.evaluation.cycle import modelled_compute

BIN_GALLERY = ("Bins (first bin of each task: the depth image before the first attempt; grasps green = success, "
               "red = failure)")
"""The gallery's section title."""

POLICY_ORDER = ("gqcnn", "fc-gqcnn", "planarity-centroid", "centroid", "planarity", "random", "analytic")


def is_bin_run(run_dir: Path) -> bool:
    """Whether a run directory holds a bin run (`eval --task bin-*`)."""
    try:
        return json.loads((Path(run_dir) / "run.json").read_text()).get("kind") == RUN_KIND
    except (OSError, ValueError, AttributeError):
        return False


def _label(run: dict[str, Any]) -> str:
    """The policy, the model it was given (by its directory's name) and the masks if not from depth."""
    model = f" [{Path(run['model']).name}]" if run.get("model") else ""
    return run["policy"] + model + (" (oracle masks)" if run.get("masks") == "oracle" else "")


def _order(run: dict[str, Any]) -> tuple:
    policy = run["policy"]
    return (run["task"], POLICY_ORDER.index(policy) if policy in POLICY_ORDER else len(POLICY_ORDER),
            policy, run.get("masks", ""))


def _pct(value: float | None) -> float | None:
    return None if value is None else round(100.0 * value, 1)


def bin_sections(run_dirs: list[Path], out: Path) -> dict[str, Any]:
    """Tables (title, note, rows), figure file names and gallery items (png, caption) of the bin runs,
    the figures and images written into `out`; plus the runs' footer entries."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from suctionbench.evaluation.figures import save_figure, style_axes

    runs = sorted(((json.loads((Path(d) / "run.json").read_text()), Path(d)) for d in run_dirs),
                  key=lambda item: _order(item[0]))
    rows, failure_rows = [], []
    for run, _ in runs:
        m = bin_metrics(run["bins"], modelled_compute(run))  # from the records: one formula for every run
        rows.append({"task": run["task"], "policy": _label(run), "bins": m["bins"], "objects": m["objects"],
                     "clearance %": _pct(m["clearance"]), "success / attempt %": _pct(m["success_per_attempt"]),
                     "attempts / object": m["attempts_per_object"], "picks/hour": m["picks_per_hour"],
                     "label precision %": _pct(m["label_precision"])})
        top = sorted(m["failures"].items(), key=lambda kv: -kv[1])
        failure_rows.append({"task": run["task"], "policy": _label(run), "attempts": m["attempts"],
                             "failures": ", ".join(f"{k} {v}" for k, v in top) or "-",
                             "bins ended by": ", ".join(f"{k} {v}" for k, v in m["ended"].items())})
    label_rows = [label_agreement(task, [r for r, _ in runs if r["task"] == task])
                  for task in sorted({run["task"] for run, _ in runs})]
    tables = [
        ("Bin picking: policies x bin tasks",
         "Each bin is filled with 5-15 objects (the task's range) and picked until clear, K failed attempts "
         "in a row, or twice its object count in attempts; the same bins for every policy. Clearance: objects "
         "that end in the receptacle (carried there, or dropped there on a failed attempt) / objects in the "
         "bins; picks/hour: objects carried per hour of simulated "
         "motion plus modelled compute; label precision: success among grasps the analytic label (rwr > 0.5, "
         "the target object alone) calls robust. Image policies plan once per object region of the image.",
         rows),
        ("Bin picking: failure reasons", "Attempts by failure reason (suctionbench.clutter.episode).",
         failure_rows),
        ("Bin picking: the analytic label against the simulation",
         "Every executed attempt of every run of the task with a target under its grasp point (runs of "
         "different policies pooled): the target's robust label (rwr, with what its neighbours press onto it) "
         "against the simulated outcome. Precision and recall at rwr > 0.5; AP of rwr.", label_rows),
    ]
    figures = []
    for task in sorted({run["task"] for run, _ in runs}):
        fig, ax = plt.subplots(figsize=(6, 4))
        for run, _ in [(r, d) for r, d in runs if r["task"] == task]:
            x, y = clearance_curve(run["bins"])
            ax.step(x, y, where="post", label=_label(run), lw=1.2)
        style_axes(ax, "attempts per object in the bin", "share of objects removed",
                   f"{task}: clearance against attempts")
        figures.append(save_figure(fig, out, f"bin_clearance_{task}.png"))
    gallery = []
    for task in sorted({run["task"] for run, _ in runs}):
        run, run_dir = next((r, d) for r, d in runs if r["task"] == task)
        item = _bin_view(run, run_dir, out)
        if item:
            gallery.append(item)
    footer = [{"run": f"{_label(run)} / {run['task']}", "trials": run["trials"], "seed": run.get("seed"),
               "camera": run.get("camera"), "cup": run.get("cup"), "model": run.get("model_used"),
               "command": run.get("command") or "-", "versions": run.get("versions") or {}} for run, _ in runs]
    return {"tables": tables, "figures": figures, "gallery": gallery, "footer": footer}


def label_agreement(task: str, runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Pooled agreement of the attempts' analytic labels with their simulated outcomes (one row)."""
    from suctionbench.learning.metrics import average_precision

    pairs = [(float(a["label_rwr"]), bool(a["success"])) for run in runs for b in run["bins"]
             for a in b["attempts"] if a.get("label_rwr") is not None]
    rwr = np.array([p[0] for p in pairs])
    success = np.array([p[1] for p in pairs], dtype=bool)
    robust = rwr > 0.5
    return {"task": task, "attempts": len(pairs), "successes": int(success.sum()), "labelled robust": int(robust.sum()),
            "precision %": _pct(float(success[robust].mean())) if robust.any() else None,
            "recall %": _pct(float(robust[success].mean())) if success.any() else None,
            "AP %": _pct(average_precision(success, rwr)) if success.any() else None}


def clearance_curve(bins: list[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
    """Share of all objects removed (y) after k attempts per object (x = k / objects in each bin),
    pooled over bins: a bin that ended early keeps its final share."""
    grid = np.linspace(0.0, 2.0, 81)
    total = sum(len(b["in_bin"]) for b in bins)
    removed = np.zeros_like(grid)
    for b in bins:
        n = len(b["in_bin"])
        if n == 0:
            continue
        counts = np.cumsum([len(a["transported"]) for a in b["attempts"]])
        steps = (np.arange(len(counts)) + 1) / n
        idx = np.searchsorted(steps, grid, side="right") - 1
        removed += np.where(idx >= 0, counts[np.clip(idx, 0, None)] if len(counts) else 0, 0)
    return grid, removed / total if total else removed


def _bin_view(run: dict[str, Any], run_dir: Path, out: Path) -> tuple[str, str] | None:
    """The first bin's first depth image with its attempts' grasps marked (None without a log)."""
    from suctionbench.evaluation.report import first_view
    from suctionbench.sensing.image import save_png

    path = run_dir / LOG_DIR / bin_log_name(0)
    view = first_view(path) if path.is_file() else None
    if view is None:
        return None
    depth = view.depth
    valid = depth > 0
    # grey from the nearest 1 % (white) to the median depth, mostly the table and the bin's floor (black)
    lo, hi = (np.percentile(depth[valid], 1), np.median(depth[valid])) if valid.any() else (0.0, 1.0)
    grey = np.where(valid, np.clip((hi - depth) / max(hi - lo, 1e-6), 0, 1), 0.0)
    image = (np.repeat(grey[..., None], 3, axis=2) * 255).astype(np.uint8)
    for attempt in run["bins"][0]["attempts"]:
        g = attempt.get("grasp_world")
        if not g:
            continue
        u, v = view.pixel(g)
        colour = (40, 200, 60) if attempt["success"] else (220, 40, 40)
        r0, c0 = int(round(v)), int(round(u))
        image[max(r0 - 3, 0):r0 + 4, max(c0 - 3, 0):c0 + 4] = colour
    name = f"bin_{run['task']}_{run_dir.name}.png"
    save_png(out / name, image)
    first = run["bins"][0]
    return name, (f"{_label(run)} / {run['task']} bin 0: {len(first['in_bin'])} objects, "
                  f"{first['transported']} removed in {len(first['attempts'])} attempts")
