"""Where objects live and how to find them: committed evaluation sets under assets/objects/,
user objects (import, corpus) under the user data directory."""

from __future__ import annotations

import os
from pathlib import Path

from suctionbench.errors import InputError
from suctionbench.objects.build import ObjectRecord
from suctionbench.objects.spec import SETS, ObjectSpec
from suctionbench.resources import asset_path


def eval_specs() -> dict[str, list[ObjectSpec]]:
    """The committed evaluation sets' specs, by set name."""
    from suctionbench.objects.adversarial import ADVERSARIAL_SPECS
    from suctionbench.objects.sets import BASIC_SPECS
    from suctionbench.objects.typical import TYPICAL_SPECS

    return {"basic": BASIC_SPECS, "typical": TYPICAL_SPECS, "adversarial": ADVERSARIAL_SPECS}


def assets_root() -> Path:
    """Committed objects: assets/objects/<set>/<name>/."""
    return asset_path("objects")


def user_root() -> Path:
    """User objects (imported meshes): $SUCTIONBENCH_HOME/objects, default ~/.local/share/suctionbench."""
    home = os.environ.get("SUCTIONBENCH_HOME") or Path.home() / ".local" / "share" / "suctionbench"
    return Path(home) / "objects"


def set_dir(set_name: str) -> Path:
    """Directory holding a set's objects (evaluation sets in assets, others in the user root)."""
    return (assets_root() if set_name in SETS else user_root()) / set_name


def list_objects(set_name: str | None = None) -> list[ObjectRecord]:
    """Records of all built objects (of one set), sorted by set then name."""
    sets = [set_name] if set_name else [*SETS, *_user_sets()]
    if set_name and set_name not in SETS and set_name not in _user_sets():
        raise InputError(f"object set '{set_name}' is unknown (known: {', '.join([*SETS, *_user_sets()])})")
    records = []
    for name in sets:
        directory = set_dir(name)
        if directory.is_dir():
            records += [ObjectRecord.load(d) for d in sorted(directory.iterdir()) if (d / "object.toml").is_file()]
    return records


def load_object(key: str) -> ObjectRecord:
    """The object called SET/NAME, or InputError naming what is known."""
    if key.count("/") != 1:
        raise InputError(f"object '{key}': expected SET/NAME, e.g. basic/box_cereal")
    set_name, name = key.split("/")
    directory = set_dir(set_name) / name
    if not (directory / "object.toml").is_file():
        known = [r.name for r in list_objects(set_name)]
        hint = f" (known in '{set_name}': {', '.join(known[:8])}{', ...' if len(known) > 8 else ''})"
        raise InputError(f"object '{key}' is unknown{hint}")
    return ObjectRecord.load(directory)


def _user_sets() -> list[str]:
    root = user_root()
    # hidden folders are temp or old copies of a write in progress (see build_object), never sets
    return sorted(d.name for d in root.iterdir() if d.is_dir() and not d.name.startswith(".")) if root.is_dir() else []


def resolve_objects(source: str) -> list[ObjectRecord]:
    """Objects named by a set (basic, typical, adversarial, or a user set) or found in a directory:
    a corpus (its train/ subfolder), a set folder of object folders, or one object folder."""
    path = Path(source)
    if not path.exists() and "/" not in source:
        return list_objects(source)
    if not path.is_dir():
        raise InputError(f"objects '{source}': neither a known set nor a directory")
    if (path / "object.toml").is_file():
        return [ObjectRecord.load(path)]
    root = path / "train" if (path / "corpus.json").is_file() else path
    records = [ObjectRecord.load(d) for d in sorted(root.iterdir()) if (d / "object.toml").is_file()]
    if not records:
        raise InputError(f"objects '{source}': no object folders (with object.toml) found there")
    return records
