"""Image files: depth and colour images to PNG, written atomically."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from suctionbench.io import atomic_path


def save_png(path: str | Path, image: np.ndarray) -> None:
    """Save an (H, W, 3) uint8 colour image, or an (H, W) float depth image (scaled to 8 bits
    between its smallest and largest non-zero depth, 0 staying black), as a PNG."""
    image = np.asarray(image)
    if image.ndim == 2 and image.dtype != np.uint8:
        valid = image > 0
        lo, hi = (image[valid].min(), image[valid].max()) if valid.any() else (0.0, 1.0)
        scaled = np.where(valid, 255 - 200 * (image - lo) / max(hi - lo, 1e-9), 0)
        image = scaled.astype(np.uint8)
    with atomic_path(path) as tmp:
        Image.fromarray(image).save(tmp, format="PNG")
