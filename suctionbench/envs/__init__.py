"""Gymnasium environments of suctionbench, all registered here and nowhere else.

Importing this package (``import suctionbench`` does) registers each environment id with a
string entry point, so registration costs only the import of gymnasium: MuJoCo, the scene and
the analytic labeller are imported when an environment is first made. Ids are versioned; a
change of physics, spaces or reward makes a new ``-vN`` rather than changing an existing one, so
results reported against an id stay comparable. v1 (2026-11-26): the simulated vacuum pulls along
the cup's axis however an object's collision geometry is decomposed; v2 (2026-11-26): the leak test
measures the object's real surface behind its convex parts (eval/README.md); v3 (2026-11-27): a
part-filled container's liquid levels in the pose the object rests in (`objects.liquid`), where it
stayed in the end that was its bottom when upright; v4 (2026-11-27): levelling turns the
inertial frame of a body built with an unrotated one (an upright can) in the kinematics too, so
its inertia and collision bounding boxes follow the levelled liquid (v3 left them turned: parts
missed contacts); SuctionBin-v5 (2026-11-28, the same physics as v4): its ``regions`` come from a
segmentation that no longer cuts an object at its own convex edges (`sensing.segmentation`), so
per-region policies see whole objects. Making an older id raises gymnasium's DeprecatedEnv, naming
the newest to use.

    >>> import gymnasium, suctionbench
    >>> env = gymnasium.make("suctionbench/SuctionPick-v4", object_set="basic")
    >>> bins = gymnasium.make("suctionbench/SuctionBin-v5", task="bin-basic")
"""

from __future__ import annotations

from typing import Any

import gymnasium

ENVIRONMENTS: dict[str, str] = {
    "suctionbench/SuctionPick-v4": "suctionbench.envs.suction_pick:SuctionPickEnv",
    "suctionbench/SuctionBin-v5": "suctionbench.envs.suction_bin:SuctionBinEnv",
}
"""Environment id -> entry point ("module:Class"), imported only by gymnasium.make."""

for _env_id, _entry_point in ENVIRONMENTS.items():
    if _env_id not in gymnasium.registry:  # a re-import (importlib.reload) must not warn about overriding
        gymnasium.register(id=_env_id, entry_point=_entry_point)


def __getattr__(name: str) -> Any:
    """`from suctionbench.envs import SuctionPickEnv` without importing MuJoCo at package import."""
    if name == "SuctionPickEnv":
        from suctionbench.envs.suction_pick import SuctionPickEnv

        return SuctionPickEnv
    if name == "SuctionBinEnv":
        from suctionbench.envs.suction_bin import SuctionBinEnv

        return SuctionBinEnv
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["ENVIRONMENTS", "SuctionBinEnv", "SuctionPickEnv"]
