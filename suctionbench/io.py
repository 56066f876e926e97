"""Atomic writes: a reader never sees a half-written file or directory, an interrupted run leaves
none in place of the output (files: temp file + rename; directories: temp sibling + rename).

Every temporary sibling names its output and its writer: ``.NAME.PID-HOST.XXXXXXXX.tmp`` (a
file; ``.part``: an episode log, suctionbench.runlog.writer), ``.NAME.PID-HOST.XXXXXXXX.partial``
(a directory being written), ``.NAME.replaced-PID-HOST`` (the old output, while the new one takes
its place); HOST is a short hash of the host's name. A process killed with SIGKILL cannot delete
its own; the next write of the same output does (`remove_stale_temporaries`): only those of that
output, and only where their writer is a process of this host that no longer exists.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import math
import os
import re
import shutil
import socket
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.errors import InputError


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside `path`; on success rename it over `path`, else delete it."""
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        remove_stale_temporaries(path)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.{writer_tag()}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        raise InputError(f"output '{path}': cannot write there ({os_error_reason(exc)})") from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        try:
            yield tmp_path
        except OSError as exc:
            if exc.errno not in WRITE_ERRNOS:
                raise
            raise InputError(f"output '{path}': cannot write there ({os_error_reason(exc)})") from None
        try:
            os.chmod(tmp_path, 0o666 & ~_umask())  # mkstemp makes 0600 files; use the usual mode
            os.replace(tmp_path, path)
        except OSError as exc:
            raise InputError(f"output '{path}': cannot write there ({os_error_reason(exc)})") from None
    finally:
        tmp_path.unlink(missing_ok=True)


_HOST = hashlib.sha256(socket.gethostname().encode()).hexdigest()[:6]


def bytes_under(directory: str | Path) -> int:
    """Bytes of the files under `directory` (0 if it is not a directory)."""
    directory = Path(directory)
    if not directory.is_dir():
        return 0
    return sum(path.stat().st_size for path in directory.rglob("*") if path.is_file())


def writer_tag() -> str:
    """'PID-HOST': this process and (a hash of) its host, written into the names of its temporaries."""
    return f"{os.getpid()}-{_HOST}"


def _temporary_pattern(name: str) -> re.Pattern[str]:
    """The names of the temporaries of output `name` (see the module's doc), with their writer."""
    writer = r"(?P<{0}pid>[1-9]\d{{0,6}})-(?P<{0}host>[0-9a-f]{{6}})"  # pids have at most 7 digits (pid_max)
    temporary = rf"{writer.format('')}\.[a-z0-9_]+\.(?P<kind>tmp|part|partial)"  # a random part
    return re.compile(rf"\.{re.escape(name)}\.(?:{temporary}|replaced-{writer.format('old_')})")


def _writer_gone(pid: int, host: str) -> bool:
    """True if the writer `pid` on `host` has certainly ended: a process of this host that is not
    running (a process of another host, or of another user, is never judged)."""
    if host != _HOST or pid == os.getpid():
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except (OSError, OverflowError):  # PermissionError: it runs, as another user
        return False
    return False


def remove_stale_temporaries(out: str | Path) -> list[Path]:
    """Delete the temporaries of output `out` that a killed writer left beside it (a .tmp or .part
    file, a .partial directory, a replaced-... old output), and return them. Only names of this output's
    temporaries are touched, only plain files and directories (never a symbolic link), and only
    where their writer, a process of this host, no longer exists. An old output whose writer died
    before the new one took its place (`out` is missing) is put back as `out` instead of deleted."""
    out = Path(out)
    pattern = _temporary_pattern(out.name)
    prefix = f".{out.name}."
    removed = []
    try:
        with os.scandir(out.parent) as scan:
            entries = sorted((e for e in scan if e.name.startswith(prefix)), key=lambda e: e.name)
    except OSError:
        return removed
    for entry in entries:
        match = pattern.fullmatch(entry.name)
        if match is None or entry.is_symlink():
            continue
        kind = match["kind"] or "replaced"
        pid, host = (match["pid"], match["host"]) if match["kind"] else (match["old_pid"], match["old_host"])
        if not _writer_gone(int(pid), host):
            continue
        path = Path(entry.path)
        try:  # best effort: a temporary that cannot be removed (another process did, no permission) stays
            if kind in ("tmp", "part") and entry.is_file():
                path.unlink()
            elif kind == "partial" and entry.is_dir():
                shutil.rmtree(path)
            elif kind == "replaced" and not out.exists() and not out.is_symlink():
                os.replace(path, out)  # killed between the two renames of publish_dir: the old output back
                continue
            elif kind == "replaced":
                shutil.rmtree(path) if entry.is_dir() else path.unlink()
            else:
                continue
        except OSError:
            continue
        removed.append(path)
    return removed


WRITE_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES, errno.EPERM, errno.EFBIG})
"""Errors of the place being written to (full, read-only, not permitted), not of the program."""

_HINTS = {
    errno.ENOSPC: "disk full: free space or write elsewhere",
    errno.EDQUOT: "disk quota exceeded: free space or write elsewhere",
    errno.EROFS: "read-only file system: write elsewhere",
    errno.EACCES: "no permission: write elsewhere or fix the permissions",
    errno.EPERM: "not permitted: write elsewhere or fix the permissions",
    errno.ENOTDIR: "a file stands where a directory must be",
}


def os_error_reason(exc: OSError) -> str:
    """The reason of a file-system error with what to do about it ('No space left on device (disk full: ...)')."""
    reason = exc.strerror or type(exc).__name__
    hint = _HINTS.get(exc.errno or 0)
    return f"{reason} ({hint})" if hint else reason


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def file_digest(path: str | Path) -> tuple[str, int]:
    """sha256 hex digest and size of a file, read in 1 MiB chunks (never the whole file in memory)."""
    h = hashlib.sha256()
    size = 0
    with open(path, "rb") as fh:
        while chunk := fh.read(1 << 20):
            h.update(chunk)
            size += len(chunk)
    return h.hexdigest(), size


def save_npz(path: str | Path, **arrays: np.ndarray) -> None:
    """np.savez_compressed, atomically."""
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(fh, **arrays)


def publish_dir(staging: str | Path, out: str | Path) -> None:
    """Move the finished directory `staging` to `out` (a sibling): one rename when `out` is absent,
    else the old `out` is renamed aside first and deleted after; never a mix of old and new."""
    staging, out = Path(staging), Path(out)
    remove_stale_temporaries(out)
    if out.is_dir() and not any(out.iterdir()):
        out.rmdir()
    if not out.exists():
        os.replace(staging, out)
        return
    trash = out.with_name(f".{out.name}.replaced-{writer_tag()}")
    shutil.rmtree(trash, ignore_errors=True)
    os.replace(out, trash)
    os.replace(staging, out)
    shutil.rmtree(trash, ignore_errors=True)


@contextlib.contextmanager
def atomic_dir(out: str | Path, refuse: Callable[[Path], str | None]) -> Iterator[Path]:
    """Yield an empty temporary sibling of directory `out` to write into; on success it replaces
    `out` (`publish_dir`), on failure it is deleted and `out` is untouched.

    `refuse(out)` is asked first when `out` exists and is not empty: a reason (the directory holds
    files this program did not write) raises InputError, so nothing of the user's is replaced.
    """
    out = Path(out)
    remove_stale_temporaries(out)  # first: an old output a killed writer had moved aside is back
    if out.exists() and not out.is_dir():
        raise InputError(f"output '{out}': exists and is not a directory")
    if out.is_dir() and any(out.iterdir()):
        reason = refuse(out)
        if reason:
            raise InputError(f"output '{out}': {reason}; nothing replaced (choose another directory)")
    staging = staging_dir(out)
    try:
        try:
            yield staging
            publish_dir(staging, out)
        except InputError as exc:  # name the output, not its hidden staging directory
            raise InputError(str(exc).replace(str(staging), str(out))) from None
        except OSError as exc:
            if exc.errno not in WRITE_ERRNOS:
                raise
            raise InputError(f"output '{out}': cannot write there ({os_error_reason(exc)})") from None
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def staging_dir(out: str | Path) -> Path:
    """A new, empty temporary sibling of directory `out` (``.NAME.PID-HOST.XXXXXXXX.partial``, the
    usual mode) to write `out` into, its parents created; InputError naming `out` if it cannot be."""
    out = Path(out)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.{writer_tag()}.", suffix=".partial", dir=out.parent))
        os.chmod(staging, 0o777 & ~_umask())  # mkdtemp makes 0700 directories; use the usual mode
    except OSError as exc:
        raise InputError(f"output '{out}': cannot write there ({os_error_reason(exc)})") from None
    return staging


def json_safe(value: Any) -> Any:
    """`value` ready for strict JSON: NaN / infinities become None (strict parsers reject them),
    numpy scalars and arrays become Python numbers and lists, tuples become lists, keys strings."""
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_safe(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def read_json(path: str | Path, what: str, missing: str, malformed: str = "") -> Any:
    """The JSON value in `path`, or an InputError "`what` 'path': ..." saying it is missing (with the
    hint `missing`), unreadable, or malformed (line and message, then `malformed`)."""
    try:
        text = Path(path).read_text()
    except FileNotFoundError:
        raise InputError(f"{what} '{path}': missing ({missing})") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{what} '{path}': unreadable ({exc})") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{what} '{path}': malformed JSON (line {exc.lineno}: {exc.msg}{malformed})") from None
