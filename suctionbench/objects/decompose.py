"""CoACD convex decomposition in a child process.

CoACD is native code: on some meshes it aborts (SIGABRT) or runs away, and in-process that kills
the caller without a JSON line and leaves its temp folders behind. Here each run is a child
Python process (``python .../objects/decompose.py IN.npz OUT.npz``) that reads the mesh
and the parameters from IN.npz and writes the parts to OUT.npz, both in a private temp folder
outside any object set, removed when the run ends however it ends. A crash, a kill or a run past
COACD_TIMEOUT becomes `CoacdFailed`, which the caller turns into a fallback or a clean error.
The child dies with the process that started it (`suctionbench.lifeline`): a killed import or
build leaves no CoACD computing for no one.

The child imports only numpy and coacd (it runs this file as a script, without the package), so
it starts in about 0.1 s.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

COACD_TIMEOUT = 300.0
"""Seconds one CoACD run may take before it is stopped (the slowest objects take ~20 s)."""

COACD_OPTIONS = {
    # Our meshes are validated closed manifolds before they get here, so CoACD's own manifold
    # remeshing (on by default, "auto") only costs time: it was 80 % of a 1k-face gripper's 60 s.
    "preprocess_mode": "off",
}
"""Options passed to coacd.run_coacd besides threshold, max_convex_hull and seed (every object)."""

IMPORT_SCHEDULE = ((0.08, 24), (0.05, 32), (0.03, 48))
"""(concavity threshold, max parts) tried in turn for imported meshes (see build.COACD_SCHEDULE):
a coarser first try, since an imported mesh is decomposed while its user waits."""

IMPORT_OPTIONS = {"resolution": 1000, "mcts_iterations": 50, "mcts_max_depth": 2, "mcts_nodes": 10}
"""Lighter tree search and sampling for imported meshes (CoACD's defaults: 2000, 150, 3, 20).
Measured on dm_control's dog bones with the first threshold: a 4.4k-face sacrum 20 -> 3.5 s and a
1k-face carpal 20 -> 1.4 s, union still within 1.18 x of the volume and covering 99.9 % of it."""


PARENT_ENV = "SUCTIONBENCH_COACD_PARENT"
"""Environment variable with the process id of the child's parent, which the child dies with."""


class CoacdFailed(RuntimeError):
    """CoACD crashed, was killed or ran past its time; the message says which."""


def _child_command(job: Path, result: Path) -> list[str]:
    """The child's command line (a test swaps it for one that aborts)."""
    # run as a script, not `-m suctionbench...`: importing the package would import gymnasium (0.2 s)
    return [sys.executable, str(Path(__file__).resolve()), str(job), str(result)]


class CoacdRun:
    """One CoACD run in its child process, started when the object is made; `parts()` waits for its
    result, `cancel()` stops it. Several may run at once (`build.decompose_mesh` starts the next
    tries of its schedule beside the first). The private temp folder is removed however it ends."""

    def __init__(
        self,
        vertices: np.ndarray,
        faces: np.ndarray,
        threshold: float,
        max_hulls: int,
        seed: int = 0,
        options: dict | None = None,
    ) -> None:
        self._folder = tempfile.TemporaryDirectory(prefix="suctionbench-coacd-")
        folder = Path(self._folder.name)
        self._job, self._result, self._stderr = folder / "job.npz", folder / "parts.npz", folder / "stderr.txt"
        try:
            np.savez(
                self._job,
                vertices=np.ascontiguousarray(vertices, dtype=np.float64),
                faces=np.ascontiguousarray(faces, dtype=np.int64),
                threshold=float(threshold),
                max_hulls=int(max_hulls),
                seed=int(seed),
                options=json.dumps({**COACD_OPTIONS, **(options or {})}),
            )
            env = {**os.environ, "PYTHONFAULTHANDLER": "0", PARENT_ENV: str(os.getpid())}
            with open(self._stderr, "wb") as stderr:  # a file, not a pipe: runs side by side never block
                self._process = subprocess.Popen(
                    _child_command(self._job, self._result), stdout=subprocess.DEVNULL, stderr=stderr, env=env
                )
        except BaseException:
            self._folder.cleanup()
            raise
        self._deadline = time.monotonic() + COACD_TIMEOUT

    def parts(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """(vertices, faces) of each convex part, once the child has finished; CoacdFailed if it
        crashed, failed or ran past COACD_TIMEOUT (then it is stopped)."""
        try:
            try:
                code = self._process.wait(timeout=max(0.0, self._deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                raise CoacdFailed(f"CoACD ran past {COACD_TIMEOUT:g} s and was stopped") from None
            if code != 0 or not self._result.is_file():
                raise CoacdFailed(_describe_exit(code, self._stderr.read_bytes()))
            with np.load(self._result) as data:
                count = int(data["count"])
                return [(data[f"v{i}"], data[f"f{i}"]) for i in range(count)]
        finally:
            self.cancel()

    def cancel(self) -> None:
        """Stop the child if it still runs and remove the temp folder (idempotent)."""
        if self._process.poll() is None:
            self._process.kill()
            self._process.wait()
        self._folder.cleanup()


def _describe_exit(code: int, stderr: bytes) -> str:
    if code < 0:
        try:
            name = signal.Signals(-code).name
        except ValueError:
            name = f"signal {-code}"
        return f"CoACD crashed ({name})"
    lines = [line for line in stderr.decode(errors="replace").splitlines() if line.strip()]
    return f"CoACD failed (exit {code}{': ' + lines[-1].strip()[:160] if lines else ''})"


def _die_with_parent() -> None:
    """Child side: die with the parent named in PARENT_ENV (`suctionbench.lifeline.die_with_parent`,
    loaded from its file: the child runs without the package, whose import costs 0.2 s)."""
    parent = os.environ.get(PARENT_ENV, "")
    if not parent.isdigit():
        return
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "suctionbench_lifeline", Path(__file__).resolve().parents[1] / "lifeline.py"
    )
    lifeline = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(lifeline)
    lifeline.die_with_parent(int(parent))


def _main(job: str, result: str) -> None:
    import coacd

    with np.load(job) as data:
        vertices, faces = data["vertices"], data["faces"]
        threshold, max_hulls, seed = float(data["threshold"]), int(data["max_hulls"]), int(data["seed"])
        options = json.loads(str(data["options"]))
    coacd.set_log_level("error")
    parts = coacd.run_coacd(
        coacd.Mesh(vertices, faces), threshold=threshold, max_convex_hull=max_hulls, seed=seed, **options
    )
    arrays = {"count": np.array(len(parts))}
    for i, (v, f) in enumerate(parts):
        arrays[f"v{i}"], arrays[f"f{i}"] = np.asarray(v, dtype=np.float64), np.asarray(f, dtype=np.int64)
    tmp = f"{result}.part.npz"
    np.savez(tmp, **arrays)
    os.replace(tmp, result)


if __name__ == "__main__":
    _die_with_parent()
    _main(*sys.argv[1:3])
