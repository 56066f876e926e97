"""Locate shipped data (assets/, tasks/) both in a checkout and in an installed wheel."""

from __future__ import annotations

from importlib import resources
from pathlib import Path


def asset_path(*parts: str) -> Path:
    """Path to a file under assets/ (e.g. asset_path("meshes", "soap_bar.ply"))."""
    root = Path(str(resources.files("suctionbench.assets")))
    return root.joinpath(*parts)
