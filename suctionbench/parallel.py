"""Execution engines shared by dataset generation and evaluation: the same picklable task
function over a list of argument tuples, results yielded in input order, on a local process pool
or on Ray (an existing cluster via `address`, else a local one started for the call).

A local Ray dies with the process that started it, kill -9 included: Ray ties its GCS, raylet and
log monitor to that process (PR_SET_PDEATHSIG) and its workers exit with the raylet, but the
raylet's agents (ray::DashboardAgent, ray::RuntimeEnvAgent) notice its death only after seconds
and then wait on the dead GCS (seen alive well past 10 s). A small reaper process (`_RAY_REAPER`)
kills every process of that Ray once the starting process ends."""

from __future__ import annotations

import os
import subprocess
import sys
import uuid
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import Any

from suctionbench.errors import InputError
from suctionbench.lifeline import die_with_parent

ENGINES = ("local", "ray")
"""Available execution engines."""

RAY_SESSION_VAR = "SUCTIONBENCH_RAY_SESSION"
"""Marks the processes of a local Ray started by `map_ordered`: set (to a fresh token) while
ray.init starts them, so that the GCS, raylet and the processes they start inherit it."""

RAY_REAPER_WAIT_S = 15.0
"""How long a finished `map_ordered` waits for its reaper."""

_RAY_REAPER = r"""
import os, signal, sys, time
marker, driver, me = sys.argv[1].encode(), int(sys.argv[2]), os.getpid()
for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):  # outlive a Ctrl-C or hang-up to clean up after it
    signal.signal(sig, signal.SIG_IGN)
# One line per session directory, then end of file: the driver is done with Ray or has died (kill -9 too).
sessions = tuple(os.path.join(line.decode().strip(), "") for line in sys.stdin.buffer if line.strip())

def writes_into_session(pid):
    for fd in os.listdir(f"/proc/{pid}/fd"):
        try:
            if os.readlink(f"/proc/{pid}/fd/{fd}").startswith(sessions):
                with open(f"/proc/{pid}/fdinfo/{fd}") as fh:
                    flags = next(int(l.split()[1], 8) for l in fh if l.startswith("flags:"))
                if flags & 3:  # O_WRONLY or O_RDWR: a log of that session, kept open by a Ray process
                    return True
        except (OSError, StopIteration, ValueError):
            pass
    return False

def ours(pid):
    try:
        with open(f"/proc/{pid}/environ", "rb") as fh:
            if marker in fh.read().split(b"\0"):
                return True
        return bool(sessions) and writes_into_session(pid)
    except OSError:
        return False

quiet, deadline = 0, time.monotonic() + 10
while quiet < 3 and time.monotonic() < deadline:
    found = 0
    for name in os.listdir("/proc"):
        if name.isdigit() and int(name) not in (me, driver) and ours(name):
            try:
                os.kill(int(name), signal.SIGKILL)
                found += 1
            except OSError:
                pass
    quiet = 0 if found else quiet + 1
    time.sleep(0.1)
"""
"""Standard-library script of the reaper of a local Ray. Its stdin's write end is held by the
driver only, so end of file comes when the driver closes it or dies, however it dies. Then it
SIGKILLs, until a few scans in a row find none, every process (the driver excepted) that either
carries the marker (NAME=token, its first argument) in its environment, or holds a file of one of
the session directories the driver sent (a line each) open for writing. The second test is for the
raylet's agents (ray::DashboardAgent, ray::RuntimeEnvAgent): the raylet starts them with an
environment of its own making, and /proc/PID/environ of an agent lacked the marker in about one
run of five, but they always keep their logs in the session directory open.
Linux (/proc); elsewhere no reaper is started."""


def check_engine(engine: str) -> None:
    """InputError for an unknown engine; callers check before they write any output."""
    if engine not in ENGINES:
        raise InputError(f"--engine '{engine}': expected {' or '.join(ENGINES)}")


class _Pool(ProcessPoolExecutor):
    """A process pool that, left by an exception (a failed task, a full disk, Ctrl-C), cancels the
    tasks not started yet instead of running them all first: the error is reported after the tasks
    already running end, not after the whole queue."""

    def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> bool:
        self.shutdown(wait=True, cancel_futures=exc_type is not None)
        return False


def process_pool(workers: int) -> ProcessPoolExecutor:
    """A process pool of fresh interpreters (spawn) whose workers die with this process (`die_with_parent`).

    Spawn, not fork: a forked worker inherits locks and half-initialised libraries of every other
    thread of its parent. A parent that has rendered (an OpenGL context with llvmpipe's threads)
    forks workers whose first render waits forever on threads that do not exist in them; spawned
    workers start clean and see the parent's current environment and working directory. A worker
    imports only what its task needs (about 1 s, 3 s with torch).

    PR_SET_PDEATHSIG fires when the *thread* that started the worker ends; the pool starts its
    workers from the thread that submits work, so submit from a thread that outlives the pool
    (the main thread, as every command does). Used as a context manager, an exception cancels the
    tasks still queued (`_Pool`).
    """
    import multiprocessing

    threads = max(1, (os.cpu_count() or 1) // max(1, workers))
    return _Pool(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                 initializer=_start_worker, initargs=(os.getpid(), threads))


THREAD_VARIABLES = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")
"""Environment variables that size the math libraries' thread pools (torch's intra-op pool reads
OMP_NUM_THREADS when it is first imported)."""


def _start_worker(parent_pid: int, threads: int) -> None:
    """A pool worker's first call: die with the parent, and give the math libraries this worker's
    share of the cores (`threads`) unless the user sized them. N workers that each start a pool of
    every core's threads oversubscribe the machine: the small, many network calls of a GQ-CNN plan
    then wait on each other's spinning threads (20 fc-gqcnn trials on basic, 2 workers, 2 idle
    cores: plan time mean 1.745 s, median 0.487 s with full pools; 0.226 s, 0.106 s shared).

    The environment variables reach only libraries loaded later (torch). numpy's BLAS is already
    loaded when this runs (unpickling this function imports suctionbench, hence numpy) and sized
    its pool from every core: threadpoolctl limits the pools already loaded too. Unlimited, 16
    dataset workers on a 16-core machine ran 16 BLAS threads each, which spun: 10x the CPU time
    of the work, and no faster than 4 workers (eval/gqcnn/README.md, "On a lent GPU")."""
    die_with_parent(parent_pid)
    user_sized = any(name in os.environ for name in THREAD_VARIABLES)  # then their pools are as asked
    for name in THREAD_VARIABLES:
        os.environ.setdefault(name, str(threads))
    if not user_sized:
        from threadpoolctl import threadpool_limits

        threadpool_limits(limits=threads)


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
    reaper = None
    try:
        if started:
            local = address is None
            if local:
                token = uuid.uuid4().hex
                reaper = _start_ray_reaper(f"{RAY_SESSION_VAR}={token}")
                os.environ[RAY_SESSION_VAR] = token
            try:
                context = ray.init(address=address, num_cpus=None if address else workers, include_dashboard=False,
                                   log_to_driver=False, ignore_reinit_error=True)
            finally:
                if local:
                    os.environ.pop(RAY_SESSION_VAR, None)
            if reaper is not None:
                _tell_reaper(reaper, context.address_info.get("session_dir"))
        remote = ray.remote(fn)
        for ref in [remote.remote(*a) for a in args]:
            yield ray.get(ref)
    finally:
        if started:
            ray.shutdown()
        if reaper is not None:
            reaper.stdin.close()  # the reaper kills what is left of this Ray
            try:
                reaper.wait(timeout=RAY_REAPER_WAIT_S)
            except subprocess.TimeoutExpired:
                reaper.kill()
                reaper.wait()


def _start_ray_reaper(marker: str) -> subprocess.Popen | None:
    """Start the reaper of a local Ray whose processes carry `marker` (NAME=token) in their environment.

    Started before ray.init, from a process without the marker, so that a death during ray.init is
    covered too (the marked processes; the agents once the session directory is sent). It gets no
    signal of ours: the end of its stdin, closed by the kernel when this process dies however it
    dies, starts its work.
    """
    if not os.path.isdir("/proc"):
        return None
    return subprocess.Popen([sys.executable, "-I", "-c", _RAY_REAPER, marker, str(os.getpid())],
                            stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def _tell_reaper(reaper: subprocess.Popen, session_dir: str | None) -> None:
    """Send the reaper the session directory of the Ray just started (see `_RAY_REAPER`).

    Only that of a Ray this process started: ray.init without an address joins a running cluster
    found through RAY_ADDRESS or `ray start`, whose processes are not ours to kill. Ray names the
    session directory of a node it starts session_<time>_<pid of the starting process>.
    """
    if not session_dir or not os.path.basename(os.path.normpath(session_dir)).endswith(f"_{os.getpid()}"):
        return
    try:
        reaper.stdin.write(os.fsencode(os.path.realpath(session_dir)) + b"\n")
        reaper.stdin.flush()
    except OSError:  # the reaper is gone: nothing to tell
        pass
