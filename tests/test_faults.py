"""Faults (issue 14): pool workers die with a killed parent, a killed eval is resumable and reported
as incomplete meanwhile, a full disk is an input error naming the path with nothing half-written."""

from __future__ import annotations

import contextlib
import errno
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import textwrap
import time
import uuid
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from suctionbench.cli import app

runner = CliRunner()
ORPHAN_GRACE_S = 5.0
"""How long a pool worker may outlive its killed parent."""


def alive(pid: int) -> bool:
    """True if `pid` runs (a zombie waiting for its reaper counts as gone)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError, IndexError):
        return False
    return state != "Z"


def wait_gone(pids: list[int], timeout: float = ORPHAN_GRACE_S) -> list[int]:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        left = [p for p in pids if alive(p)]
        if not left:
            return []
        time.sleep(0.1)
    return [p for p in pids if alive(p)]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_pool_workers_die_with_their_killed_parent():
    script = textwrap.dedent("""
        import os, sys, time
        from suctionbench.parallel import process_pool
        pool = process_pool(2)
        futures = [pool.submit(time.sleep, 120) for _ in range(2)]
        while len(pool._processes) < 2:
            time.sleep(0.05)
        time.sleep(0.5)  # the initializers have run
        print(" ".join(str(p) for p in pool._processes), flush=True)
        time.sleep(120)
    """)
    parent = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        workers = [int(p) for p in parent.stdout.readline().split()]
        assert len(workers) == 2 and all(alive(p) for p in workers)
        parent.send_signal(signal.SIGKILL)
        parent.wait()
        left = wait_gone(workers)
    finally:
        parent.kill()
    for pid in left:  # clean up before failing
        os.kill(pid, signal.SIGKILL)
    assert not left, f"workers {left} outlived their parent by {ORPHAN_GRACE_S} s"



def _threads() -> tuple[str, int]:
    import torch

    return os.environ["OMP_NUM_THREADS"], torch.get_num_threads()


def _blas_threads() -> list[int]:
    from threadpoolctl import threadpool_info

    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


def test_pool_workers_share_the_cores(monkeypatch):
    # Each of N workers gets cpu_count // N threads for torch (and OpenMP / BLAS): N full-size
    # pools on the same cores oversubscribe them. A size the user set is kept. numpy's BLAS is
    # loaded before the worker's first call can set the environment (its pool sized from every
    # core), so its pool must be limited where it runs: one thread here, not the machine's count.
    from suctionbench.parallel import THREAD_VARIABLES, process_pool

    for name in THREAD_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    with process_pool(2) as pool:
        assert pool.submit(_threads).result() == ("1", 1)
        blas = pool.submit(_blas_threads).result()
        assert blas and all(n == 1 for n in blas), blas
    monkeypatch.setenv("OMP_NUM_THREADS", "7")
    with process_pool(2) as pool:
        assert pool.submit(_threads).result()[0] == "7"

def child_pids(pid: int) -> list[int]:
    out = subprocess.run(["pgrep", "-P", str(pid)], capture_output=True, text=True).stdout
    return [int(p) for p in out.split()]


FAKE_COACD = """
import os, pathlib, time
def set_log_level(level): pass
class Mesh:
    def __init__(self, vertices, faces): pass
def run_coacd(mesh, **options):
    path = os.environ["FAKE_COACD_STARTED"]
    pathlib.Path(path + ".tmp").write_text(str(os.getpid()))
    os.replace(path + ".tmp", path)
    time.sleep(120)
"""


def start_eval_until_first_trial(cmd: list[str], staging: Path, **popen: Any):
    """Start the eval `cmd` and wait (up to 240 s) until its first trial log appears in
    `staging`/trials: returns the process, that log directory and its pool workers' pids."""
    parent = subprocess.Popen(cmd, **popen)
    logs = staging / "trials"
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline and not list(logs.glob("trial_*.mcap")):
        time.sleep(0.2)
    return parent, logs, child_pids(parent.pid)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_coacd_child_dies_with_its_killed_parent(tmp_path):
    """kill -9 of a process in the middle of a convex decomposition: its CoACD child (the real child
    script, with a stand-in coacd that computes for 120 s) is gone within ORPHAN_GRACE_S."""
    fake = tmp_path / "fake"
    fake.mkdir()
    (fake / "coacd.py").write_text(FAKE_COACD)
    started = tmp_path / "started"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(fake), os.environ.get("PYTHONPATH")])),
           "TMPDIR": str(tmp_path), "FAKE_COACD_STARTED": str(started)}
    script = textwrap.dedent("""
        import trimesh
        from suctionbench.objects.decompose import CoacdRun
        box = trimesh.creation.box()
        CoacdRun(box.vertices, box.faces, 0.05, 8).parts()
    """)
    parent = subprocess.Popen([sys.executable, "-c", script], env=env)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not started.exists() and parent.poll() is None:
            time.sleep(0.05)
        assert started.exists(), "the CoACD child did not start"
        child = int(started.read_text())
        assert child in child_pids(parent.pid) and alive(child)
        parent.send_signal(signal.SIGKILL)
        parent.wait()
        left = wait_gone([child])
    finally:
        parent.kill()
    for pid in left:  # clean up before failing
        os.kill(pid, signal.SIGKILL)
    assert not left, f"the CoACD child {left} outlived its parent by {ORPHAN_GRACE_S} s"


@pytest.mark.slow
def test_killed_eval_no_orphans_refused_report_then_resume_equals_a_full_run(tmp_path):
    """kill -9 of an eval with 2 workers after its first trial log: no worker survives, the run is
    OUT.incomplete and report refuses it (or marks it), eval --resume finishes it, and its results
    equal those of an uninterrupted run (trials are seeded by index)."""
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "suctionbench", "eval", "--policy", "centroid", "--set", "basic", "--trials", "6",
           "--workers", "2", "--seed", "3", "--out", str(out)]
    parent, logs, workers = start_eval_until_first_trial(cmd, tmp_path / "run.incomplete",
                                                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    parent.send_signal(signal.SIGKILL)
    parent.wait()
    assert list(logs.glob("trial_*.mcap")), "no trial finished in time"
    assert workers and not wait_gone(workers), "pool workers outlived the killed eval"
    assert not out.exists()

    result = runner.invoke(app, ["report", str(out), "--out", str(tmp_path / "rep"), "--json"])
    assert result.exit_code == 2 and "incomplete" in json.loads(result.stdout.splitlines()[-1])["error"]
    assert not (tmp_path / "rep").exists()
    result = runner.invoke(app, ["eval", *cmd[4:], "--json"])
    assert result.exit_code == 2 and "--resume" in result.stderr

    resumed = runner.invoke(app, ["eval", *cmd[4:], "--resume", "--json"])
    assert resumed.exit_code == 0, resumed.stderr[-2000:]
    assert not (tmp_path / "run.incomplete").exists()
    fresh = runner.invoke(app, ["eval", *cmd[4:-1], str(tmp_path / "fresh"), "--json"])
    assert fresh.exit_code == 0, fresh.stderr[-2000:]
    a, b = (json.loads(r.stdout.splitlines()[-1]) for r in (resumed, fresh))
    keys = ("trials", "invalid", "success_rate", "ap", "outcomes", "per_object", "mean_motion_s")
    assert {k: a[k] for k in keys} == {k: b[k] for k in keys}


RAY_MARKER = "SUCTIONBENCH_RAY_FAULT_TEST"
"""Environment variable the Ray test gives its `generate`: the processes it starts inherit it."""

RAY_ORPHAN_GRACE_S = 10.0
"""How long a Ray process (GCS, raylet, agent, worker) may outlive its killed `generate`."""


def holds_file_under(pid: int, prefix: str) -> bool:
    for fd in Path(f"/proc/{pid}/fd").iterdir():
        with contextlib.suppress(OSError):
            if os.readlink(fd).startswith(prefix):
                return True
    return False


def ray_pids(token: str, ray_tmp: str, exclude: int) -> list[int]:
    """Live processes (`exclude` aside) with RAY_MARKER=token in their environment or a file under
    `ray_tmp`, the test's own Ray directory, open: only processes the test's command started. Both
    tests, since /proc may show a raylet agent's environment without the marker, and a process may
    hold no file there."""
    needle = f"{RAY_MARKER}={token}".encode()
    prefix = os.path.join(os.path.realpath(ray_tmp), "")
    pids = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit() or int(entry.name) == exclude:
            continue
        with contextlib.suppress(OSError):
            pid = int(entry.name)
            if (needle in (entry / "environ").read_bytes().split(b"\0") or holds_file_under(pid, prefix)) \
                    and alive(pid):
                pids.append(pid)
    return pids


def describe(pids: list[int]) -> str:
    out = []
    for pid in pids:
        try:
            cmdline = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
            out.append(f"{pid} {cmdline.strip()[:100]}")
        except OSError:
            out.append(f"{pid} (gone)")
    return "; ".join(out)


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_ray_generate_killed_leaves_no_orphans(tmp_path):
    """kill -9 of `generate --engine ray` while its Ray tasks run: none of the processes its local Ray
    started (GCS, raylet, its agents, workers) outlives it by RAY_ORPHAN_GRACE_S. They are found by a
    marker in their environment or by their files in a Ray directory of the test's own, so no other
    process on the machine is ever killed."""
    pytest.importorskip("ray")
    token = uuid.uuid4().hex
    # Ray's files in a fresh directory of a short path (its socket paths must fit AF_UNIX's 107
    # bytes, which pytest's tmp_path may not): no other Ray instance is found or touched.
    ray_tmp = tempfile.mkdtemp(prefix="sbray", dir="/tmp")
    env = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"}
    env.update({RAY_MARKER: token, "RAY_TMPDIR": ray_tmp, "RAY_USAGE_STATS_ENABLED": "0"})
    cmd = [sys.executable, "-m", "suctionbench", "generate", "--objects", "basic", "--datapoints", "40",
           "--engine", "ray", "--workers", "2", "--out", str(tmp_path / "ds"), "--json"]
    log = tmp_path / "generate.log"
    started: list[int] = []
    with open(log, "wb") as fh:
        parent = subprocess.Popen(cmd, env=env, stdout=fh, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        deadline = time.monotonic() + 240
        running = False
        while time.monotonic() < deadline and parent.poll() is None and not running:
            time.sleep(0.2)
            started = ray_pids(token, ray_tmp, parent.pid)
            running = "ray::generate_unit" in describe(started)
        assert running, f"no Ray task started (exit {parent.poll()}): {log.read_text()[-2000:]}"
        assert "raylet" in describe(started), describe(started)
        parent.send_signal(signal.SIGKILL)
        parent.wait()
        deadline = time.monotonic() + RAY_ORPHAN_GRACE_S
        left = ray_pids(token, ray_tmp, parent.pid)
        while left and time.monotonic() < deadline:
            time.sleep(0.2)
            left = ray_pids(token, ray_tmp, parent.pid)
        report = describe(left)
    finally:
        parent.kill()
        parent.wait()
        for pid in ray_pids(token, ray_tmp, parent.pid):  # clean up before failing
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        shutil.rmtree(ray_tmp, ignore_errors=True)
    assert not left, f"{len(left)} Ray processes outlived the killed generate by {RAY_ORPHAN_GRACE_S} s: {report}"


@contextlib.contextmanager
def small_disk(folder: Path, free: int = 0):
    """A 256 KiB tmpfs mounted on `folder` and filled up to `free` bytes left (root on Linux only;
    skipped elsewhere)."""
    folder.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", str(folder)],
                                           capture_output=True).returncode != 0:
        pytest.skip("cannot mount a small tmpfs here")
    try:
        with open(folder / "filler", "wb", buffering=0) as fh:
            try:
                while shutil.disk_usage(folder).free > free:
                    fh.write(b"\0" * 4096)
            except OSError as exc:
                assert exc.errno == errno.ENOSPC
        assert shutil.disk_usage(folder).free <= free
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)], check=False)


@pytest.fixture
def full_disk(tmp_path):
    """A 256 KiB tmpfs filled up."""
    with small_disk(tmp_path / "small") as mount:
        yield mount


@pytest.fixture
def nearly_full_disk(tmp_path):
    """A 256 KiB tmpfs with 64 KiB left: room to start a file, not to finish an episode log."""
    with small_disk(tmp_path / "nearly_full", free=64 * 1024) as mount:
        yield mount


@pytest.fixture
def read_only_dir(tmp_path):
    """An empty directory nothing can be written in: a read-only tmpfs (root, Linux), else mode 0555
    (which root ignores); skipped where neither holds."""
    folder = tmp_path / "read_only"
    folder.mkdir()
    mounted = os.geteuid() == 0 and subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", str(folder)], capture_output=True).returncode == 0
    if not mounted:
        folder.chmod(0o555)
    try:
        if os.access(folder, os.W_OK):
            pytest.skip("cannot make a read-only directory here")
        yield folder
    finally:
        if mounted:
            subprocess.run(["umount", "-l", str(folder)], check=False)
        else:
            folder.chmod(0o755)


@pytest.fixture
def box_mesh(tmp_path) -> Path:
    import trimesh

    path = tmp_path / "box.stl"
    trimesh.creation.box(extents=(0.06, 0.04, 0.02)).export(path)
    return path


def test_full_disk_is_an_input_error_naming_the_path(full_disk, box_mesh, monkeypatch):
    """The labels do not fit: refused before labelling (the size estimate); and where the estimate
    is passed (here switched off), the write itself fails with one line naming the file."""
    out = full_disk / "labels.npz"
    argv = ["label", str(box_mesh), "--grasps", "20", "--samples", "5", "--mass", "0.1", "--out", str(out), "--json"]
    result = runner.invoke(app, argv)
    assert result.exit_code == 2, result.stderr
    error = json.loads(result.stdout.splitlines()[-1])["error"]
    assert error.startswith("--grasps 20 --out: needs about") and f"of disk under '{out}', 0 B free" in error, error
    monkeypatch.setattr("suctionbench.cli.label.require_disk", lambda *a: None)
    result = runner.invoke(app, argv)
    assert result.exit_code == 2, result.stderr
    error = json.loads(result.stdout.splitlines()[-1])["error"]
    assert str(out) in error and "No space left" in error and "Traceback" not in result.stderr
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler"]  # no temporary file left


def test_bench_generate_checks_the_disk_before_writing(full_disk, monkeypatch):
    """bench generate writes two datasets in the temporary directory: a disk without room for them
    is refused up front (exit 2, the path named), before any object is loaded or file written."""
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", str(full_disk))
    result = runner.invoke(app, ["bench", "generate", "--objects", "basic", "--datapoints", "10", "--workers", "1",
                                 "--json"])
    assert result.exit_code == 2, result.stderr
    error = json.loads(result.stdout.splitlines()[-1])["error"]
    assert "--datapoints 10" in error and f"of disk under '{full_disk}'" in error, error
    assert len(result.stderr.strip().splitlines()) == 1 and "Traceback" not in result.stderr
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler"]


def test_report_on_a_full_disk_writes_nothing(full_disk, tmp_path):
    from fuzz_corpus import write_run

    run = write_run(tmp_path / "run")
    result = runner.invoke(app, ["report", str(run), "--out", str(full_disk / "report"), "--json"])
    assert result.exit_code == 2, result.stderr
    assert "No space left" in json.loads(result.stdout.splitlines()[-1])["error"]
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler"]  # all or nothing: no half report


@pytest.mark.parametrize("name", ["episode.mcap", "runs/episode.mcap"])
def test_pick_log_into_a_read_only_directory(read_only_dir, name):
    """Refused before the episode runs: exit 2, one line naming --log and its path, nothing written."""
    log = read_only_dir / name
    result = runner.invoke(app, ["pick", "--object", "basic/box_tea", "--log", str(log), "--json"])
    assert result.exit_code == 2, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and "Traceback" not in result.stderr
    error = json.loads(result.stdout.splitlines()[-1])["error"]
    assert error.startswith(f"--log '{log}': cannot write in '{read_only_dir}'"), error
    assert list(read_only_dir.iterdir()) == []


def test_episode_log_errors_name_the_log_not_its_temporary_file(read_only_dir):
    """The library's own error (a caller without the CLI's check) names the log's path."""
    from suctionbench.runlog.writer import EpisodeLog

    log = read_only_dir / "episode.mcap"
    with pytest.raises(OSError) as info:
        EpisodeLog(log, {"seed": 0})
    assert info.value.filename == str(log) and info.value.errno in (errno.EROFS, errno.EACCES)
    assert list(read_only_dir.iterdir()) == []


# -- a full disk in the middle of an episode log ---------------------------------------------------


def test_episode_log_on_a_full_disk_names_the_log_and_leaves_nothing(full_disk, nearly_full_disk):
    """The library's writer: on a disk without room for the header, or with room for the first
    messages only (the disk fills mid-episode), the error is an OSError naming the log, not its
    hidden .part file, and the .part file is gone."""
    import numpy as np

    from suctionbench.runlog.writer import EpisodeLog

    for disk in (full_disk, nearly_full_disk):
        log = disk / "episode.mcap"
        with pytest.raises(OSError) as info, EpisodeLog(log, {"seed": 0}) as episode:
            names = [f"joint_{i}" for i in range(2048)]
            for step in range(100):  # ~4 MB of joint states: far more than is left
                episode.log_joint_states(step * 0.01, names, np.random.default_rng(step).random(2048).tolist())
        assert info.value.errno == errno.ENOSPC and info.value.filename == str(log)
        assert sorted(p.name for p in disk.iterdir()) == ["filler"]


def test_pick_log_on_a_disk_that_fills_mid_episode(nearly_full_disk, monkeypatch):
    """pick --log: refused before the episode when the log cannot fit (the size estimate); with the
    estimate switched off, the disk fills while the episode is logged: exit 2, one line naming the
    log, no .part left."""
    log = nearly_full_disk / "episode.mcap"
    argv = ["pick", "--object", "basic/box_tea", "--log", str(log), "--json"]
    result = runner.invoke(app, argv)
    assert result.exit_code == 2, result.stderr
    assert json.loads(result.stdout.splitlines()[-1])["error"].startswith("--log: needs about")
    monkeypatch.setattr("suctionbench.cli.pick.require_disk", lambda *a: None)
    result = runner.invoke(app, argv)
    assert result.exit_code == 2, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and "Traceback" not in result.stderr
    error = json.loads(result.stdout.splitlines()[-1])["error"]
    assert error.startswith(f"'{log}': No space left on device"), error
    assert sorted(p.name for p in nearly_full_disk.iterdir()) == ["filler"]


def test_eval_disk_full_mid_trial_log_is_resumable(nearly_full_disk, monkeypatch):
    """eval whose disk fills while a trial is logged (the estimate passed: something else filled
    the disk): exit 2, one line naming the trial log, no .part file, the run kept in OUT.incomplete,
    which a rerun points to (--resume)."""
    monkeypatch.setattr("suctionbench.evaluation.runner.BYTES_PER_TRIAL_LOG", 1)
    out = nearly_full_disk / "run"
    argv = ["eval", "--policy", "centroid", "--set", "basic", "--trials", "2", "--workers", "1", "--out", str(out),
            "--json"]
    result = runner.invoke(app, argv)
    assert result.exit_code == 2, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and "Traceback" not in result.stderr
    error = json.loads(result.stdout.splitlines()[-1])["error"]
    log = nearly_full_disk / "run.incomplete" / "trials" / "trial_00000.mcap"
    assert error.startswith(f"'{log}': No space left on device"), error
    assert not out.exists() and not list(nearly_full_disk.rglob("*.part"))
    assert sorted(p.name for p in (nearly_full_disk / "run.incomplete").iterdir()) == ["run.json", "trials"]
    again = runner.invoke(app, argv)
    assert again.exit_code == 2 and "--resume" in json.loads(again.stdout.splitlines()[-1])["error"]


def test_eval_resume_with_nothing_to_resume_says_so(tmp_path):
    """eval --resume where no interrupted run is (a job rerun with the same command until it is
    done): the run starts afresh, with one 'note:' line on stderr saying so and "resumed": false in
    the JSON; where an interrupted run is, "resumed": true and the trial logs it kept."""
    out = tmp_path / "run"
    argv = ["eval", "--policy", "centroid", "--set", "basic", "--trials", "2", "--workers", "1", "--out", str(out),
            "--resume", "--json"]
    result = runner.invoke(app, argv)
    assert result.exit_code == 0, result.stderr[-2000:]
    assert result.stderr.strip().splitlines() == [
        f"note: --resume: nothing to resume: no '{tmp_path / 'run.incomplete'}'; running all 2 trials"]
    reply = json.loads(result.stdout.splitlines()[-1])
    assert reply["resumed"] is False and reply["trials_reused"] == 0 and reply["trials"] == 2
    out.rename(tmp_path / "run.incomplete")  # as if killed after its first trial
    (tmp_path / "run.incomplete" / "trials" / "trial_00001.mcap").unlink()
    result = runner.invoke(app, argv)
    assert result.exit_code == 0 and result.stderr.strip() == "", result.stderr[-2000:]
    reply = json.loads(result.stdout.splitlines()[-1])
    assert reply["resumed"] is True and reply["trials_reused"] == 1 and reply["trials"] == 2
    help_text = runner.invoke(app, ["eval", "--help"], env={"COLUMNS": "200"}).stdout
    assert "With none there, the run starts afresh and says so" in " ".join(help_text.replace("│", " ").split())


def test_save_model_on_a_full_disk_names_the_weights(full_disk):
    """safetensors' own writer fails on a full disk with an error of its own type and no path; the
    weights are serialised in memory and written by Python instead: InputError naming the file."""
    import torch

    from suctionbench.errors import InputError
    from suctionbench.learning.checkpoint import GQCNNModel, save_model
    from suctionbench.learning.data import NormStats
    from suctionbench.learning.models import build_model

    model = GQCNNModel(build_model("compact", torch.Generator().manual_seed(0)),
                       NormStats(0.58, 0.01, (0.58, 0.3), (0.01, 0.2), count=10), {"arch": "compact"})
    with pytest.raises(InputError, match=f"output '{full_disk / 'm' / 'model.safetensors'}'.*No space left"):
        save_model(full_disk / "m", model)
    assert not list((full_disk / "m").iterdir())


@pytest.fixture
def disk_16k_free(tmp_path):
    """A 256 KiB tmpfs with 16 KiB left: room for a folder, not for an object's mesh."""
    with small_disk(tmp_path / "16k_free", free=16 * 1024) as mount:
        yield mount


def fine_box():
    """A 6 x 4 x 2 cm box of 768 faces: a 38 KB STL."""
    import trimesh

    return trimesh.creation.box(extents=(0.06, 0.04, 0.02)).subdivide().subdivide().subdivide()


def test_build_object_on_a_disk_that_fills_names_the_file_and_leaves_nothing(disk_16k_free):
    """The disk fills while an object is written (its mesh does not fit in what is left): an
    InputError naming the object's file that could not be written, not its folder or the root;
    nothing left, neither the temporary folder nor the parent folders the build created."""
    from suctionbench.errors import InputError
    from suctionbench.objects.build import build_object
    from suctionbench.objects.spec import ObjectSpec

    spec = ObjectSpec(name="box", set="custom", generator="import", density=500.0)
    target = disk_16k_free / "user" / "custom" / "box"
    with pytest.raises(InputError) as info:
        build_object(fine_box(), spec, target, decompose=False)
    assert str(info.value).startswith(f"output '{target / 'mesh.stl'}': cannot write there (No space left"), info.value
    assert sorted(p.name for p in disk_16k_free.iterdir()) == ["filler"]


def test_objects_import_on_a_disk_that_fills_names_the_file(disk_16k_free, monkeypatch, tmp_path):
    """objects import past its size estimate (switched off here: something else filled the disk):
    exit 2, one line naming the file that could not be written, nothing left under --root."""
    mesh = tmp_path / "box.stl"
    fine_box().export(mesh)
    monkeypatch.setattr("suctionbench.cli.objects.require_disk", lambda *a: None)
    root = disk_16k_free / "user"
    result = runner.invoke(app, ["objects", "import", str(mesh), "--root", str(root), "--json"])
    assert result.exit_code == 2, result.stderr[-2000:]
    assert len(result.stderr.strip().splitlines()) == 1 and "Traceback" not in result.stderr
    error = json.loads(result.stdout.splitlines()[-1])["error"]
    assert error.startswith(f"output '{root / 'custom' / 'box' / 'mesh.stl'}': cannot write there (No space left"), \
        error
    assert sorted(p.name for p in disk_16k_free.iterdir()) == ["filler"]


# -- temporaries a killed writer left beside its output ---------------------------------------------


def dead_pid() -> int:
    """The id of a process that has ended."""
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    assert not alive(child.pid)
    return child.pid


def test_a_rerun_removes_only_stale_temporaries_of_its_own_output(tmp_path):
    """Before writing OUT, its temporaries (.OUT.PID-HOST.*.tmp / .part / .partial, .OUT.replaced-PID-HOST)
    whose writer is a process of this host that no longer exists are removed; nothing else: not
    those of a running writer, of another host, of another output, of the old unnamed format, a
    symbolic link, nor the user's files."""
    from suctionbench.io import atomic_dir, atomic_path, remove_stale_temporaries, writer_tag
    from suctionbench.runlog.writer import EpisodeLog

    dead, host = dead_pid(), writer_tag().split("-")[1]
    live = os.getppid()
    stale = [f".l.npz.{dead}-{host}.ab12_x9z.tmp", f".rep.{dead}-{host}.q0w9e8r7.partial/index.html",
             f".rep.replaced-{dead}-{host}/index.html", f".e.mcap.{dead}-{host}.0a1b2c3d.part"]
    kept = [f".l.npz.{live}-{host}.ab12_x9z.tmp", f".l.npz.{dead}-000000.ab12_x9z.tmp",
            f".m.npz.{dead}-{host}.ab12_x9z.tmp", ".l.npz.ab12_x9z.tmp", f".rep.{live}-{host}.q0w9e8r7.partial/a",
            "notes.txt", "rep/index.html", f"l.npz.{dead}-{host}.ab12_x9z.tmp"]
    for name in stale + kept:
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text("x")
    (tmp_path / f".l.npz.{dead}-{host}.zz_link.tmp").symlink_to(tmp_path / "notes.txt")
    kept.append(f".l.npz.{dead}-{host}.zz_link.tmp")
    with atomic_path(tmp_path / "l.npz") as tmp:
        tmp.write_text("labels")
    with atomic_dir(tmp_path / "rep", lambda out: None) as out:
        (out / "index.html").write_text("new")
    with EpisodeLog(tmp_path / "e.mcap", {"seed": 0}):
        pass
    assert (tmp_path / "l.npz").read_text() == "labels" and (tmp_path / "rep" / "index.html").read_text() == "new"
    left = {str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*") if p.is_file() or p.is_symlink()}
    assert left == {*kept, "l.npz", "e.mcap"}, left ^ {*kept, "l.npz", "e.mcap"}
    assert remove_stale_temporaries(tmp_path / "l.npz") == []


def test_an_old_output_moved_aside_by_a_killed_writer_is_put_back(tmp_path):
    """Killed between publish_dir's two renames (OUT moved aside, the new one not yet in place): the
    next write of OUT puts the old one back before judging OUT, instead of deleting it."""
    from suctionbench.io import remove_stale_temporaries, writer_tag

    dead, host = dead_pid(), writer_tag().split("-")[1]
    aside = tmp_path / f".rep.replaced-{dead}-{host}"
    aside.mkdir()
    (aside / "index.html").write_text("old report")
    assert remove_stale_temporaries(tmp_path / "rep") == []
    assert (tmp_path / "rep" / "index.html").read_text() == "old report" and not aside.exists()


KILL_AT = {  # command, and the moment its process kills itself (SIGKILL: no cleanup can run)
    "report .partial": ("report", "suctionbench.evaluation.report._write_report", "after"),
    "report .replaced": ("report", "os.replace", "replaced"),
    "label --out .tmp": ("label", "os.replace", "npz"),
}
KILLER = textwrap.dedent("""
    import importlib, os, signal, sys
    target, when = sys.argv[1], sys.argv[2]
    module, name = target.rsplit(".", 1)
    owner = importlib.import_module(module)
    real = getattr(owner, name)

    def killed(*args, **kwargs):
        if when == "npz" and str(args[1]).endswith(".npz"):
            os.kill(os.getpid(), signal.SIGKILL)  # the labels are written, not yet renamed into place
        result = real(*args, **kwargs)
        if when == "after" or (when == "replaced" and ".replaced-" in str(args[1])):
            os.kill(os.getpid(), signal.SIGKILL)
        return result

    setattr(owner, name, killed)
    from suctionbench.cli import app
    sys.argv = ["suctionbench", *sys.argv[3:]]
    app()
""")


@pytest.mark.parametrize("case", [pytest.param(c, marks=[pytest.mark.slow] if c.startswith("report") else [])
                                  for c in KILL_AT])
def test_kill_9_leaves_temporaries_a_rerun_removes(case, tmp_path, box_mesh):
    """kill -9 of report (while its report is written; between its two renames) and of label --out
    (its labels written, not renamed): the hidden temporary stays beside the output; the same
    command run again removes it and writes the output. Nothing else in the folder is touched."""
    from fuzz_corpus import write_run

    command, target, when = KILL_AT[case]
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    (out_dir / "notes.txt").write_text("mine")
    if command == "report":
        run = write_run(tmp_path / "run")
        argv = ["report", str(run), "--out", str(out_dir / "rep")]
        if when == "replaced":
            assert runner.invoke(app, argv).exit_code == 0  # an old report for the killed one to replace
    else:
        argv = ["label", str(box_mesh), "--grasps", "20", "--samples", "2", "--mass", "0.1",
                "--out", str(out_dir / "l.npz")]
    killed = subprocess.run([sys.executable, "-c", KILLER, target, when, *argv], capture_output=True, text=True)
    assert killed.returncode == -signal.SIGKILL, killed.stderr[-2000:]
    hidden = sorted(p.name for p in out_dir.iterdir() if p.name.startswith("."))
    assert len(hidden) == (2 if when == "replaced" else 1) and all(f"{killed_pid(hidden[0])}-" in h for h in hidden)
    result = runner.invoke(app, [*argv, "--json"])
    assert result.exit_code == 0, result.stderr[-2000:]
    assert sorted(p.name for p in out_dir.iterdir()) == sorted(["notes.txt", "rep" if command == "report" else "l.npz"])


def killed_pid(name: str) -> str:
    """The writer's pid in a temporary's name ('.rep.replaced-123-abcdef', '.l.npz.123-abcdef.x.tmp')."""
    tag = name.rsplit("replaced-", 1)[1] if "replaced-" in name else name.split(".")[-3]
    return tag.split("-")[0]


# -- every output on a full disk and on a read-only file system ------------------------------------


OUTPUTS = {  # command line writing to {d} (a directory on the small file system), inputs from the corpus
    "label --out": ["label", "{box}", "--grasps", "50", "--samples", "2", "--mass", "0.1", "--out", "{d}/l.npz"],
    "generate": ["generate", "--objects", "basic", "--datapoints", "4", "--workers", "1", "--out", "{d}/ds"],
    "eval": ["eval", "--policy", "centroid", "--set", "basic", "--trials", "1", "--workers", "1", "--out", "{d}/run"],
    "train": ["train", "--dataset", "{ds_good}", "--out", "{d}/model", "--arch", "compact", "--epochs", "1"],
    "report": ["report", "{run_good}", "--out", "{d}/report"],
    "objects build": ["objects", "build", "--set", "adversarial", "--workers", "1", "--out", "{d}/objects"],
    "objects import": ["objects", "import", "{box}", "--root", "{d}/user"],
    "objects generate": ["objects", "generate", "--count", "2", "--workers", "1", "--out", "{d}/corpus"],
    "dataset show --thumbnails": ["dataset", "show", "{ds_good}", "--thumbnails", "{d}/t.png"],
    "pick --log": ["pick", "--object", "basic/box_tea", "--log", "{d}/e.mcap"],
    "plan --out": ["plan", "--depth", "{depth}", "--camera", "primesense", "--policy", "centroid",
                   "--out", "{d}/p.png"],
}


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    from fuzz_corpus import build_corpus

    return build_corpus(tmp_path_factory.mktemp("faults") / "corpus")


@pytest.mark.parametrize("kind", ["full", "read-only"])
@pytest.mark.parametrize("name", list(OUTPUTS))
def test_every_output_on_a_full_or_read_only_disk(name, kind, corpus, tmp_path, request):
    """Each command that writes, pointed at a full or a read-only file system, is refused before its
    work (the size estimate, the write check) with one line naming the path, and writes nothing
    there: no partial output, no temporary file, no empty directory."""
    disk = request.getfixturevalue("full_disk" if kind == "full" else "read_only_dir")
    argv = [a.format(d=disk, depth=corpus["depth_flat.npy"], **corpus) for a in OUTPUTS[name]]
    start = time.monotonic()
    result = runner.invoke(app, [*argv, "--json"])
    assert result.exit_code == 2, (result.exit_code, result.stderr[-2000:])
    assert len(result.stderr.strip().splitlines()) == 1 and "Traceback" not in result.stderr, result.stderr
    error = json.loads(result.stdout.splitlines()[-1])["error"]
    assert str(disk) in error, error
    assert sorted(p.name for p in disk.iterdir()) == (["filler"] if kind == "full" else []), error
    assert time.monotonic() - start < 20  # refused up front, not after the work (objects build: minutes)


# -- interrupted runs and failing tasks ------------------------------------------------------------


def test_a_failing_task_cancels_the_queue():
    """A pool left by an exception cancels the tasks not yet started: the error arrives after the
    running tasks end, not after the whole queue (here 20 x 1 s on 2 workers)."""
    from suctionbench.parallel import map_ordered

    start = time.monotonic()
    with pytest.raises(ValueError, match="non-negative"):
        list(map_ordered(time.sleep, [(-1,)] + [(1,)] * 20, workers=2))
    assert time.monotonic() - start < 8


def test_interrupt_is_one_line_and_a_json_line(capsys):
    """Ctrl-C in a command: exit 130 with one stderr line and, under --json, the JSON line."""
    import typer

    from suctionbench.cli.common import run_command

    def body():
        raise KeyboardInterrupt

    with pytest.raises(typer.Exit) as info:
        run_command(True, body)
    assert info.value.exit_code == 130
    captured = capsys.readouterr()
    assert json.loads(captured.out.splitlines()[-1]) == {"ok": False, "error": "interrupted"}
    assert len(captured.err.strip().splitlines()) == 1 and "interrupted" in captured.err


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_interrupted_eval_stops_at_once_and_resumes(tmp_path):
    """SIGINT to an eval parent (its workers untouched, unlike a terminal's Ctrl-C): it stops after
    the running trials instead of running the whole queue, exits 130 with one line and the JSON
    line, leaves no worker, and --resume finishes the run."""
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "suctionbench", "eval", "--policy", "centroid", "--set", "basic", "--trials", "40",
           "--workers", "2", "--seed", "1", "--out", str(out), "--json"]
    parent, logs, workers = start_eval_until_first_trial(cmd, tmp_path / "run.incomplete",
                                                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    parent.send_signal(signal.SIGINT)
    try:
        stdout, stderr = parent.communicate(timeout=30)
    finally:
        parent.kill()
    assert parent.returncode == 130, stderr[-2000:]
    assert [line for line in stderr.splitlines() if line.strip()] == ["error: interrupted (Ctrl-C)"]
    assert json.loads(stdout.splitlines()[-1]) == {"ok": False, "error": "interrupted"}
    assert not wait_gone(workers)
    assert len(list(logs.glob("trial_*.mcap"))) < 20 and not list(logs.glob(".*.part"))
    resumed = runner.invoke(app, ["eval", *cmd[4:-1], "--resume", "--json"])
    assert resumed.exit_code == 0, resumed.stderr[-2000:]
    assert json.loads(resumed.stdout.splitlines()[-1])["trials"] == 40
