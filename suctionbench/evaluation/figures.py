"""Figures of the report: the headline figure (success and AP per policy and set beside the paper's
physical results), small shaded thumbnails of the objects (ray cast, no OpenGL needed) and a dense
policy's quality map over the depth image it planned on."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.evaluation.paper import PAPER_RESULTS
from suctionbench.io import atomic_path

THUMBNAIL_VIEW = np.array([0.55, -0.75, 0.65])
"""Direction from an object towards the thumbnail's viewer (object frame; z is up in the sets'
object frames): from the front right, above."""

THUMBNAIL_LIGHT = np.array([0.3, -0.4, 1.0])
"""Direction towards the thumbnail's light."""


def style_axes(ax: Any, xlabel: str, ylabel: str, title: str) -> None:
    """The report's look for a [0, 1] curve plot: labels, y from 0 to 1, a light grid, a legend."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_ylim(0, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title(title, fontsize=9)


def save_figure(fig: Any, out: Path, name: str) -> str:
    """Write a matplotlib figure as out/name (PNG, atomically), close it, and return `name`."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    with atomic_path(out / name) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)
    return name


def object_thumbnail(mesh: Any, size: int = 96) -> np.ndarray:
    """An (size, size, 3) uint8 picture of a mesh: orthographic view along -THUMBNAIL_VIEW,
    Lambertian shading of the first hit's face normal, white background."""
    from suctionbench.geometry.raycast import RayCaster

    view = THUMBNAIL_VIEW / np.linalg.norm(THUMBNAIL_VIEW)
    right = np.cross([0.0, 0.0, 1.0], view)
    right /= np.linalg.norm(right)
    up = np.cross(view, right)
    vertices = np.asarray(mesh.vertices, dtype=float)
    centre = (vertices.min(axis=0) + vertices.max(axis=0)) / 2
    extent = 1.08 * max(np.abs((vertices - centre) @ right).max(), np.abs((vertices - centre) @ up).max())
    steps = (np.arange(size) + 0.5) / size * 2 - 1
    grid_u, grid_v = np.meshgrid(steps * extent, -steps * extent)
    radius = float(np.linalg.norm(vertices - centre, axis=1).max())
    origins = centre + 2 * radius * view + grid_u[..., None] * right + grid_v[..., None] * up
    directions = np.broadcast_to(-view, origins.shape)
    hits = RayCaster(mesh).cast(origins.reshape(-1, 3), np.ascontiguousarray(directions.reshape(-1, 3)))
    hit = np.isfinite(hits.distance)
    normals = np.zeros((len(hit), 3))
    normals[hit] = np.asarray(mesh.face_normals)[hits.face[hit]]
    light = THUMBNAIL_LIGHT / np.linalg.norm(THUMBNAIL_LIGHT)
    shade = 0.35 + 0.65 * np.clip(np.abs(normals @ light), 0, 1)
    base = np.array([95.0, 140.0, 200.0])  # a muted blue
    colour = np.where(hit[:, None], shade[:, None] * base[None, :] + (1 - shade[:, None]) * 20, 255.0)
    return colour.reshape(size, size, 3).clip(0, 255).astype(np.uint8)


QUALITY_MARGIN = 12
"""Pixels of depth shown around the scored region of a quality map."""

QUALITY_ZOOM = 2
"""Each image pixel of a quality-map figure is drawn as this many pixels square."""


def quality_overlay(depth: np.ndarray, quality: np.ndarray, pixel: tuple[float, float] | None) -> np.ndarray:
    """An RGB uint8 picture of a quality map (H, W; q in [0, 1], NaN unscored) over its depth image:
    the square around the scored pixels (plus QUALITY_MARGIN), depth in grey (near light), each
    scored pixel coloured from red (q 0) through yellow to green (q 1), the executed grasp's image
    `pixel` (u, v) marked by a white cross; enlarged QUALITY_ZOOM times."""
    scored = np.isfinite(quality)
    if not scored.any():
        raise ValueError("quality map has no scored pixel")
    rows, cols = np.nonzero(scored)
    side = max(rows.max() - rows.min(), cols.max() - cols.min()) + 1 + 2 * QUALITY_MARGIN
    r0 = max((rows.min() + rows.max() + 1) // 2 - side // 2, 0)
    c0 = max((cols.min() + cols.max() + 1) // 2 - side // 2, 0)
    window = (slice(r0, r0 + side), slice(c0, c0 + side))  # clipped at the image's far edges
    d, q, seen = depth[window], quality[window], scored[window]
    valid = np.isfinite(d) & (d > 0)
    lo, hi = (d[valid].min(), d[valid].max()) if valid.any() else (0.0, 1.0)
    grey = np.where(valid, 230 - 160 * (d - lo) / max(hi - lo, 1e-9), 0)
    image = np.repeat(grey[..., None], 3, axis=2)
    value = np.clip(np.nan_to_num(q), 0, 1)
    heat = np.stack([np.clip(2 * (1 - value), 0, 1), np.clip(2 * value, 0, 1), np.zeros_like(value)], axis=-1)
    image[seen] = 0.25 * image[seen] + 0.75 * 255 * heat[seen]
    if pixel is not None:
        u, v = int(round(pixel[0])) - c0, int(round(pixel[1])) - r0
        for dv, du in [(k, 0) for k in range(-4, 5)] + [(0, k) for k in range(-4, 5)]:
            if 0 <= v + dv < image.shape[0] and 0 <= u + du < image.shape[1]:
                image[v + dv, u + du] = 255
    image = np.repeat(np.repeat(image, QUALITY_ZOOM, axis=0), QUALITY_ZOOM, axis=1)
    return image.clip(0, 255).astype(np.uint8)


SET_ORDER = ("basic", "typical", "adversarial")
"""Panel order of the headline figure (other sets follow, sorted)."""


def headline_figure(rows: list[dict[str, Any]], path: Path, policy_order: tuple[str, ...]) -> bool:
    """Bars of simulated success and AP (%) per policy, one panel per object set, with the paper's
    physical success (black diamond) and AP (open circle) as markers where it reports the pair.
    `rows`: dicts with policy, set, success (fraction) and ap (fraction or None). Returns False (and
    writes nothing) without rows."""
    if not rows:
        return False
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sets = sorted({r["set"] for r in rows}, key=lambda s: (SET_ORDER.index(s) if s in SET_ORDER else 9, s))
    fig, axes = plt.subplots(1, len(sets), figsize=(max(4.2 * len(sets), 7.0), 3.6), squeeze=False, sharey=True)
    for ax, set_name in zip(axes[0], sets, strict=True):
        mine = sorted((r for r in rows if r["set"] == set_name),
                      key=lambda r: (policy_order.index(r["policy"]) if r["policy"] in policy_order else 99,
                                     r["policy"]))
        x = np.arange(len(mine))
        success = [100 * r["success"] for r in mine]
        ap = [np.nan if r["ap"] is None else 100 * r["ap"] for r in mine]
        ax.bar(x - 0.2, success, 0.4, color="#4C78A8", label="success (sim)")
        ax.bar(x + 0.2, ap, 0.4, color="#F58518", label="AP (sim)")
        for i, r in enumerate(mine):
            paper = PAPER_RESULTS.get(r["policy"], {}).get(set_name)
            if paper:  # every marker is labelled; the figure's legend keeps one entry per label
                ax.plot(i - 0.2, paper[0], "D", color="black", ms=6, zorder=3, label="success (paper, physical)")
                ax.plot(i + 0.2, paper[1], "o", mfc="white", mec="black", ms=7, zorder=3, label="AP (paper, physical)")
            ax.text(i - 0.2, success[i] + 1.5, f"{success[i]:.0f}", ha="center", fontsize=7)
        ax.set_xticks(x, [_short(r["policy"]) for r in mine], rotation=25, ha="right", fontsize=8)
        ax.set_title(set_name, fontsize=10)
        ax.set_ylim(0, 105)
        ax.grid(axis="y", alpha=0.3)
    axes[0][0].set_ylabel("%")
    handles: dict[str, Any] = {}
    for ax in axes[0]:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, handle)
    fig.legend(list(handles.values()), list(handles), loc="upper center", ncol=4, fontsize=8, frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 0.9))
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)
    return True


def _short(policy: str) -> str:
    """A policy label short enough for a tick: a user spec's file name and factory."""
    if ":" in policy and ("/" in policy or "\\" in policy):
        head, _, tail = policy.rpartition(":")
        return f"{Path(head).name}:{tail}"
    return policy if len(policy) <= 28 else policy[:27] + "…"
