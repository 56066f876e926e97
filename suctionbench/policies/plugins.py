"""User policies: load a grasp policy from a spec string, the way `--policy` takes one.

A policy spec is one of

- a built-in name: ``random``, ``centroid``, ``planarity``, ``planarity-centroid``, ``gqcnn`` (alias
  ``gqcnn-cem``), from `suctionbench.policies.base.POLICIES`;
- the name of an installed plug-in: a distribution that declares, in its ``pyproject.toml``::

      [project.entry-points."suctionbench.policies"]
      lowest-point = "my_package.policies:make_policy"

  registers ``lowest-point`` (built-in names win over plug-ins of the same name, so the benchmark's
  names always mean the same policy);
- ``PATH.py:FACTORY``: a Python file and the name of a factory in it (the file is imported under a
  private module name; it need not be on ``sys.path``);
- ``package.module:FACTORY``: an importable module and a factory in it.

The factory is called with keyword options (``--policy-arg key=value``, parsed by
`parse_policy_args`) and must return an object with ``plan(observation, rng) -> GraspAction`` (the
`suctionbench.policies.base.Policy` protocol). Everything a user can get wrong - a missing file, an
import error in it, no such factory, bad options, a factory that returns something without
``plan`` - raises `suctionbench.errors.InputError` naming the spec. User policies are wrapped in
`PluginPolicy`, which checks what ``plan`` returns, so that a wrong return value is reported as the
policy's fault rather than as a crash deep inside the episode.

Specs travel as strings (`canonical_spec` makes a file path absolute), so evaluation workers, local
processes or Ray tasks, each load the policy themselves from the same spec.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.metadata
import importlib.util
import inspect
import sys
import tomllib
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.errors import InputError
from suctionbench.policies.base import ALIASES, POLICIES, GraspAction, Observation

ENTRY_POINT_GROUP = "suctionbench.policies"
"""Entry-point group through which installed distributions register policy factories."""

_FILE_MODULES: dict[Path, Any] = {}
"""Modules imported from policy files, by resolved path (each file is imported once per process)."""


# --------------------------------------------------------------------------------------------------
# Spec strings
# --------------------------------------------------------------------------------------------------


def builtin_name(spec: str) -> str | None:
    """The registry name of a built-in policy spec (aliases resolved, case and spaces ignored), else None."""
    key = str(spec).strip().lower()
    key = ALIASES.get(key, key)
    return key if key in POLICIES else None


def split_spec(spec: str) -> tuple[str, str] | None:
    """(target, factory) of a ``TARGET:FACTORY`` spec, else None. The factory is what follows the
    last colon, so a Windows path (``C:\\...\\p.py:make``) splits correctly."""
    text = str(spec).strip()
    target, sep, factory = text.rpartition(":")
    if not sep:
        return None
    if not target or not factory.isidentifier():
        raise InputError(f"--policy '{spec}': expected NAME, PATH.py:FACTORY or package.module:FACTORY "
                         f"(the factory '{factory}' is not a Python identifier)")
    return target, factory


def _is_file_target(target: str) -> bool:
    return target.endswith(".py") or "/" in target or "\\" in target


def canonical_spec(spec: str) -> str:
    """The spec as workers should load it: built-in names normalised, a policy file's path made
    absolute (workers may run in another directory); InputError for a malformed spec."""
    name = builtin_name(spec)
    if name is not None:
        return name
    parts = split_spec(spec)
    if parts is None:
        return str(spec).strip()
    target, factory = parts
    if _is_file_target(target):
        return f"{Path(target).expanduser().resolve()}:{factory}"
    return f"{target}:{factory}"


def plugin_entry_points() -> dict[str, importlib.metadata.EntryPoint]:
    """Installed plug-ins: entry-point name -> entry point, in the `ENTRY_POINT_GROUP` group."""
    return {ep.name: ep for ep in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP)}


def known_policies() -> list[str]:
    """Every policy name `--policy` accepts without a colon: built-ins, then installed plug-ins."""
    return sorted(POLICIES) + sorted(set(plugin_entry_points()) - set(POLICIES))


# --------------------------------------------------------------------------------------------------
# Factories
# --------------------------------------------------------------------------------------------------


def _import_file(spec: str, path: Path) -> Any:
    """Import a policy file under a private module name (cached per resolved path)."""
    path = path.expanduser().resolve()
    if path in _FILE_MODULES:
        return _FILE_MODULES[path]
    if not path.is_file():
        raise InputError(f"--policy '{spec}': file '{path}' not found")
    if path.suffix != ".py":
        raise InputError(f"--policy '{spec}': '{path}' is not a Python file (.py)")
    digest = hashlib.sha1(str(path).encode()).hexdigest()[:10]
    module_name = f"suctionbench_user_policy_{path.stem.replace('-', '_')}_{digest}"
    loader_spec = importlib.util.spec_from_file_location(module_name, path)
    if loader_spec is None or loader_spec.loader is None:
        raise InputError(f"--policy '{spec}': cannot import '{path}'")
    module = importlib.util.module_from_spec(loader_spec)
    sys.modules[module_name] = module  # dataclasses and pickling look classes up there
    try:
        loader_spec.loader.exec_module(module)
    except Exception as exc:
        del sys.modules[module_name]
        raise InputError(f"--policy '{spec}': importing '{path}' failed ({type(exc).__name__}: {exc})") from None
    _FILE_MODULES[path] = module
    return module


def _import_module(spec: str, name: str) -> Any:
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as exc:
        if exc.name and name.startswith(exc.name):
            raise InputError(f"--policy '{spec}': no module named '{exc.name}' (a file needs the .py suffix; "
                             f"known names: {', '.join(known_policies())})") from None
        raise InputError(f"--policy '{spec}': importing '{name}' failed ({exc})") from None
    except Exception as exc:
        raise InputError(f"--policy '{spec}': importing '{name}' failed ({type(exc).__name__}: {exc})") from None


def resolve_factory(spec: str) -> Callable[..., Any]:
    """The factory a policy spec names (see the module docstring); InputError when there is none."""
    name = builtin_name(spec)
    if name is not None:
        entry = POLICIES[name]
        if callable(entry):
            return entry
        module, _, attribute = entry.partition(":")
        return getattr(importlib.import_module(module), attribute)
    parts = split_spec(spec)
    if parts is None:
        plugins = plugin_entry_points()
        key = str(spec).strip()
        if key not in plugins:
            raise InputError(f"policy '{spec}' is unknown (known: {', '.join(known_policies())}; "
                             "or give PATH.py:FACTORY or package.module:FACTORY)")
        try:
            factory = plugins[key].load()
        except Exception as exc:
            raise InputError(f"policy '{spec}': loading plug-in {plugins[key].value} failed "
                             f"({type(exc).__name__}: {exc})") from None
    else:
        target, attribute = parts
        module = _import_file(spec, Path(target)) if _is_file_target(target) else _import_module(spec, target)
        if not hasattr(module, attribute):
            public = sorted(n for n, v in vars(module).items() if callable(v) and not n.startswith("_"))
            raise InputError(f"--policy '{spec}': no factory '{attribute}' in '{target}' "
                             f"(callables there: {', '.join(public) or 'none'})")
        factory = getattr(module, attribute)
    if not callable(factory):
        raise InputError(f"--policy '{spec}': '{factory!r}' is not callable (expected a factory returning a policy)")
    return factory


# --------------------------------------------------------------------------------------------------
# Options and loading
# --------------------------------------------------------------------------------------------------


def parse_policy_args(items: Iterable[str]) -> dict[str, Any]:
    """``key=value`` strings (``--policy-arg``, repeatable) as keyword options. Values are read as
    TOML values where they parse as one (``3``, ``0.5``, ``true``, ``"text"``, ``[1, 2]``) and are
    kept as strings otherwise (``model=runs/m1``)."""
    options: dict[str, Any] = {}
    for item in items:
        key, sep, raw = str(item).partition("=")
        key = key.strip()
        if not sep or not key.isidentifier():
            raise InputError(f"--policy-arg '{item}': expected key=value with a Python identifier as the key")
        if key in options:
            raise InputError(f"--policy-arg '{item}': '{key}' is given twice")
        try:
            options[key] = tomllib.loads(f"v = {raw.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            options[key] = raw.strip()
    return options


def policy_label(spec: str, options: dict[str, Any] | None = None) -> str:
    """How run logs and reports name a policy: its spec as the user gave it (built-in names
    normalised) with its options, e.g. ``examples/policy_plugin.py:make_policy(clearance=0.01)``."""
    name = builtin_name(spec) or str(spec).strip()
    if not options:
        return name
    return f"{name}({', '.join(f'{k}={v!r}' if isinstance(v, str) else f'{k}={v}' for k, v in options.items())})"


class PluginPolicy:
    """A user's policy with its return values checked: `plan` must give a `GraspAction` with a
    finite point and a non-zero finite approach (normalised here); a chosen index is added when
    the action lists candidates without one."""

    def __init__(self, inner: Any, name: str) -> None:
        self.inner = inner
        self.name = name

    def __repr__(self) -> str:
        return f"PluginPolicy({self.inner!r}, name={self.name!r})"

    def plan(self, observation: Observation, rng: np.random.Generator) -> GraspAction:
        action = self.inner.plan(observation, rng)
        if not isinstance(action, GraspAction):
            raise InputError(f"policy '{self.name}': plan() returned {type(action).__name__}, expected a "
                             "suctionbench.policies.base.GraspAction")
        point = np.asarray(action.point, dtype=float).reshape(-1)
        approach = np.asarray(action.approach, dtype=float).reshape(-1)
        norm = float(np.linalg.norm(approach)) if approach.shape == (3,) else 0.0
        if point.shape != (3,) or not np.isfinite(point).all() or not (np.isfinite(norm) and norm > 1e-9):
            raise InputError(f"policy '{self.name}': plan() returned a grasp without a finite point (3,) "
                             f"and a non-zero approach (3,): point {action.point!r}, approach {action.approach!r}")
        action.point, action.approach = point, approach / norm
        action.policy = action.policy or self.name
        points = action.candidates.get("points")
        if points is not None and "chosen" not in action.info:
            action.info["chosen"] = int(np.argmin(np.linalg.norm(np.asarray(points) - point, axis=1)))
        return action


def load_policy(spec: str, options: dict[str, Any] | None = None) -> Any:
    """Build the policy a spec names with keyword `options`. Built-in policies come back as they
    are; user and plug-in policies wrapped in `PluginPolicy`. InputError for anything wrong."""
    options = dict(options or {})
    factory = resolve_factory(spec)
    builtin = builtin_name(spec)
    try:
        policy = factory(**options)
    except InputError:
        raise
    except TypeError as exc:
        raise InputError(f"policy '{spec}': bad options {sorted(options)} ({exc})") from None
    except Exception as exc:
        if builtin is not None:
            raise
        raise InputError(f"policy '{spec}': its factory raised {type(exc).__name__}: {exc}") from None
    if builtin is not None:
        return policy
    plan = getattr(policy, "plan", None)
    if not callable(plan):
        raise InputError(f"policy '{spec}': the factory returned {type(policy).__name__}, which has no "
                         "plan(observation, rng) method")
    try:
        inspect.signature(plan).bind(None, None)
    except TypeError:
        raise InputError(f"policy '{spec}': {type(policy).__name__}.plan{inspect.signature(plan)} cannot be "
                         "called as plan(observation, rng)") from None
    except ValueError:  # no signature (a builtin): call it and see
        pass
    name = getattr(policy, "name", None)
    return PluginPolicy(policy, name if isinstance(name, str) and name else policy_label(spec))
