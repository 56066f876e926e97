"""Reports built from run directories (their MCAP logs), never from memory: the side-by-side table
(policies x sets), precision-recall and success-vs-attempt-rate curves, a per-object breakdown,
a gallery of failures (depth crop around the executed grasp), and the paper's numbers beside ours."""

from __future__ import annotations

import html
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.errors import InputError
from suctionbench.evaluation.runner import summarize_run
from suctionbench.io import atomic_path

PAPER_RESULTS = {  # FACTS.md section 5: success rate (AP) in %, Basic / Typical / Adversarial
    "planarity": {"basic": (74, 81), "typical": (67, 69), "adversarial": (47, 48)},
    "centroid": {"basic": (92, 89), "typical": (78, 80), "adversarial": (38, 47)},
    "planarity-centroid": {"basic": (94, 98), "typical": (86, 94), "adversarial": (62, 64)},
    "gqcnn": {"basic": (98, 99), "typical": (82, 97), "adversarial": (58, 61)},
}
"""The paper's physical results (GQ-CNN: the Dex-Net 3.0 model) for the comparison table."""

GALLERY_SIZE = 12
"""Failed trials shown in the gallery."""


def _records(run_dir: Path) -> list[dict[str, Any]]:
    from suctionbench.runlog.reader import read_run

    return [e["result"] | {"_path": e["path"]} for e in read_run(run_dir / "trials") if e.get("result")]


def success_attempt_curve(q: np.ndarray, success: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(attempt rate, success rate among attempts) when only grasps with q >= tau are attempted,
    over every threshold tau (the paper's appendix, "Performance Metrics")."""
    order = np.argsort(-q)
    attempted = np.arange(1, len(q) + 1)
    return attempted / len(q), np.cumsum(success[order]) / attempted


def build_report(run_dirs: list[Path], out: Path) -> dict[str, Any]:
    """Write out/report.md, out/index.html and the figures; returns the table rows."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from suctionbench.learning.metrics import precision_recall_curve

    if not run_dirs:
        raise InputError("report: give at least one run directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"output '{out}': cannot create it ({exc.strerror})") from None
    rows, figures, galleries, per_object = [], [], [], {}
    fig_pr, ax_pr = plt.subplots(figsize=(5, 4))
    fig_sa, ax_sa = plt.subplots(figsize=(5, 4))
    for run_dir in map(Path, run_dirs):
        summary = summarize_run(run_dir)
        records = [r for r in _records(run_dir) if r.get("valid")]
        label = f"{summary['policy']} / {summary['set']}"
        paper = PAPER_RESULTS.get(summary["policy"], {}).get(summary["set"])
        rows.append({
            "policy": summary["policy"], "set": summary["set"], "trials": summary["trials"],
            "AP": summary["ap"], "success": summary["success_rate"], "label precision": summary["label_precision"],
            "picks/hour": summary["picks_per_hour"],
            "paper success (AP)": f"{paper[0]} ({paper[1]})" if paper else "-",
        })
        per_object[label] = summary["per_object"]
        success = np.array([bool(r["success"]) for r in records])
        q = np.array([np.nan if r.get("policy_q") is None else float(r["policy_q"]) for r in records])
        if np.isfinite(q).any() and success.any():
            keep = np.isfinite(q)
            precision, recall, _ = precision_recall_curve(success[keep], q[keep])
            ax_pr.plot(recall, precision, label=label)
            attempt, rate = success_attempt_curve(q[keep], success[keep])
            ax_sa.plot(attempt, rate, label=label)
        galleries += _gallery(run_dir, [r for r in _records(run_dir) if not r.get("success")], out, label)
    for ax, fig, name, (xl, yl) in ((ax_pr, fig_pr, "precision_recall.png", ("recall", "precision")),
                                    (ax_sa, fig_sa, "success_attempt.png", ("attempt rate", "success rate"))):
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        ax.set_ylim(0, 1.02)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        with atomic_path(out / name) as tmp:
            fig.savefig(tmp, format="png", dpi=120)
        plt.close(fig)
        figures.append(name)
    _write_markdown(out, rows, figures, per_object, galleries)
    _write_html(out, rows, figures, per_object, galleries)
    return {"out": str(out), "rows": rows}


def _gallery(run_dir: Path, failed: list[dict[str, Any]], out: Path, label: str) -> list[tuple[str, str]]:
    """Depth crops (96 x 96 px) around the executed grasp of up to GALLERY_SIZE failed trials."""
    from suctionbench.runlog.reader import depth_image, iter_messages
    from suctionbench.sensing.image import save_png

    items = []
    for r in failed[: GALLERY_SIZE // 2]:
        path = Path(r["_path"])
        depth_msgs = list(iter_messages(path, "/camera/depth"))
        calib = list(iter_messages(path, "/camera/calibration"))
        if not depth_msgs or not calib:
            continue
        depth = depth_image(depth_msgs[0][1])
        k = np.asarray(calib[0][1]["K"], dtype=float).reshape(3, 3)
        meta_pose = _camera_pose(path)
        point = np.asarray(r["grasp_world"][:3])
        p_cam = (point - meta_pose[:3, 3]) @ meta_pose[:3, :3]
        u, v = (k @ p_cam)[:2] / p_cam[2]
        crop = _crop(depth, int(round(u)), int(round(v)), 48)
        name = f"fail_{run_dir.name}_{path.stem}.png"
        save_png(out / name, crop)
        items.append((name, f"{label}: {r['object']} - {r['failure']}"))
    return items


def _camera_pose(path: Path) -> np.ndarray:
    """World-from-camera pose from the log's /tf stream."""
    from suctionbench.runlog.reader import iter_messages

    for _, msg in iter_messages(path, "/tf"):
        for tf in msg.get("transforms", []):
            if tf.get("child_frame_id") == "camera":
                t, r = tf["translation"], tf["rotation"]
                return _transform(np.array([t["x"], t["y"], t["z"]]), np.array([r["w"], r["x"], r["y"], r["z"]]))
    raise InputError(f"run log '{path}': no camera transform")


def _transform(translation: np.ndarray, quat_wxyz: np.ndarray) -> np.ndarray:
    import mujoco

    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, quat_wxyz)
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rot.reshape(3, 3), translation
    return pose


def _crop(depth: np.ndarray, u: int, v: int, half: int) -> np.ndarray:
    padded = np.pad(depth, half)
    crop = padded[v : v + 2 * half, u : u + 2 * half].copy()
    crop[half - 1 : half + 1, :] = np.where(crop[half - 1 : half + 1, :] > 0, crop.max(), 0)  # cross-hair
    crop[:, half - 1 : half + 1] = np.where(crop[:, half - 1 : half + 1] > 0, crop.max(), 0)
    return crop


def _fmt(value: Any) -> str:
    return "-" if value is None else f"{value:.3g}" if isinstance(value, float) else str(value)


def _write_markdown(out: Path, rows, figures, per_object, galleries) -> None:
    lines = ["# suctionbench report", "", "Built from the MCAP logs of the runs by `suctionbench report`.", ""]
    lines += ["| " + " | ".join(rows[0]) + " |", "|" + "---|" * len(rows[0])]
    lines += ["| " + " | ".join(_fmt(v) for v in row.values()) + " |" for row in rows]
    lines += ["", "Paper: physical YuMi trials (Dex-Net 3.0, FACTS.md section 5); ours: simulation. Where they",
              "disagree the simulation is reported as is, never tuned toward the paper.", ""]
    lines += [f"![{f}]({f})" for f in figures]
    lines += ["", "## Per object (successes / trials)", ""]
    for label, table in per_object.items():
        lines.append(f"**{label}**: " + ", ".join(f"{k.split('/')[-1]} {s}/{n}" for k, (s, n) in table.items()))
        lines.append("")
    lines += ["## Failures (depth around the executed grasp)", ""]
    lines += [f"![{caption}]({name}) {caption}  " for name, caption in galleries]
    with atomic_path(out / "report.md") as tmp:
        tmp.write_text("\n".join(lines) + "\n")


def _write_html(out: Path, rows, figures, per_object, galleries) -> None:
    esc = html.escape
    head = "".join(f"<th>{esc(k)}</th>" for k in rows[0])
    body = "".join("<tr>" + "".join(f"<td>{esc(_fmt(v))}</td>" for v in row.values()) + "</tr>" for row in rows)
    objects = "".join(
        f"<h3>{esc(label)}</h3><p>" + ", ".join(f"{esc(k.split('/')[-1])} {s}/{n}" for k, (s, n) in t.items()) + "</p>"
        for label, t in per_object.items()
    )
    gallery = "".join(
        f'<figure><img src="{esc(n)}" width="192"><figcaption>{esc(c)}</figcaption></figure>' for n, c in galleries
    )
    page = f"""<!doctype html><html><head><meta charset="utf-8"><title>suctionbench report</title>
<style>body{{font-family:sans-serif;margin:2em}}table{{border-collapse:collapse}}td,th{{border:1px solid #999;
padding:4px 8px}}figure{{display:inline-block;margin:4px}}</style></head><body>
<h1>suctionbench report</h1><p>Built from the MCAP logs of the runs. Paper: physical trials (FACTS.md section 5);
ours: simulation, reported as is.</p><table><tr>{head}</tr>{body}</table>
{"".join(f'<img src="{esc(f)}" alt="{esc(f)}">' for f in figures)}
<h2>Per object (successes / trials)</h2>{objects}<h2>Failures</h2>{gallery}</body></html>"""
    with atomic_path(out / "index.html") as tmp:
        tmp.write_text(page)
