"""Execution engines shared by dataset generation and evaluation: the same picklable task
function over a list of argument tuples, results yielded in input order, on a local process pool
or on Ray (an existing cluster via `address`, else a local one started for the call)."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import Any

from suctionbench.errors import InputError
from suctionbench.lifeline import die_with_parent

ENGINES = ("local", "ray")
"""Available execution engines."""


def check_engine(engine: str) -> None:
    """InputError for an unknown engine; callers check before they write any output."""
    if engine not in ENGINES:
        raise InputError(f"--engine '{engine}': expected {' or '.join(ENGINES)}")


def process_pool(workers: int) -> ProcessPoolExecutor:
    """A process pool of fresh interpreters (spawn) whose workers die with this process (`die_with_parent`).

    Spawn, not fork: a forked worker inherits locks and half-initialised libraries of every other
    thread of its parent. A parent that has rendered (an OpenGL context with llvmpipe's threads)
    forks workers whose first render waits forever on threads that do not exist in them; spawned
    workers start clean and see the parent's current environment and working directory. A worker
    imports only what its task needs (about 1 s, 3 s with torch).

    PR_SET_PDEATHSIG fires when the *thread* that started the worker ends; the pool starts its
    workers from the thread that submits work, so submit from a thread that outlives the pool
    (the main thread, as every command does).
    """
    import multiprocessing

    return ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                               initializer=die_with_parent, initargs=(os.getpid(),))


def map_ordered(
    fn: Callable[..., Any], args: Sequence[tuple], *, engine: str = "local", workers: int = 1,
    address: str | None = None,
) -> Iterator[Any]:
    """Yield fn(*a) for every a in args, in order, computed by `engine`."""
    check_engine(engine)
    if not args:
        return
    if engine == "local":
        if workers <= 1:
            for a in args:
                yield fn(*a)
            return
        with process_pool(workers) as pool:
            futures = [pool.submit(fn, *a) for a in args]
            for future in futures:
                yield future.result()
        return
    try:
        import ray
    except ImportError:
        raise InputError("--engine ray: Ray is not installed (pip install 'suctionbench[ray]')") from None
    started = not ray.is_initialized()
    if started:
        ray.init(address=address, num_cpus=None if address else workers, include_dashboard=False,
                 log_to_driver=False, ignore_reinit_error=True)
    try:
        remote = ray.remote(fn)
        for ref in [remote.remote(*a) for a in args]:
            yield ray.get(ref)
    finally:
        if started:
            ray.shutdown()
