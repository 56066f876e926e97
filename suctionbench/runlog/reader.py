"""Read episode logs back: summaries for results tables, and decoded messages by topic.

Every failure to read a file (missing, not MCAP, truncated, corrupt chunk, undecodable message)
becomes one `InputError` naming the file, because a run directory is user input to ``report``
and similar commands, which must exit with code 2 and a one-line reason rather than a traceback.
"""

from __future__ import annotations

import base64
import json
import os
import struct
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import zstandard
from mcap.exceptions import McapError
from mcap.reader import McapReader, make_reader
from mcap.records import Channel, Message
from mcap.summary import Summary

from suctionbench.errors import InputError
from suctionbench.runlog.writer import METADATA_NAME, METADATA_TYPES_NAME, TOPIC_RESULT

MCAP_MAGIC = b"\x89MCAP0\r\n"
"""Starts and ends every complete MCAP file."""

# What the mcap reader and its decompressors raise on malformed input (lz4 raises RuntimeError;
# json/unicode errors are ValueErrors).
_MALFORMED = (McapError, struct.error, ValueError, EOFError, KeyError, RuntimeError, zstandard.ZstdError)


def _fail(path: Path, problem: Any) -> InputError:
    text = " ".join(str(problem).split()) or type(problem).__name__
    return InputError(f"{path}: cannot read episode log: {text}")


@contextmanager
def _open(path: str | os.PathLike) -> Iterator[tuple[McapReader, Summary]]:
    """An indexed reader of a complete MCAP file; every read error inside becomes `InputError`."""
    path = Path(path)
    try:
        with open(path, "rb") as stream:
            # Check both magics first: it names the two common problems better than the mcap
            # reader's record-level errors would.
            if stream.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
                raise _fail(path, "not an MCAP file (bad magic)")
            size = stream.seek(0, os.SEEK_END)
            stream.seek(max(size - len(MCAP_MAGIC), 0))
            if size < 2 * len(MCAP_MAGIC) or stream.read() != MCAP_MAGIC:
                raise _fail(path, "truncated (no end magic: the writer did not finish)")
            stream.seek(0)
            reader = make_reader(stream, validate_crcs=True)
            summary = reader.get_summary()
            if summary is None:
                raise _fail(path, "no summary section (the writer did not finish)")
            yield reader, summary
    except FileNotFoundError:
        raise InputError(f"{path}: episode log not found") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a directory, expected an .mcap episode log") from None
    except OSError as exc:
        raise _fail(path, exc.strerror or exc) from exc
    except _MALFORMED as exc:
        if isinstance(exc, InputError):
            raise
        raise _fail(path, f"corrupt ({type(exc).__name__}: {exc})") from exc


def _decode(channel: Channel, message: Message) -> Any:
    if channel.message_encoding != "json":
        raise McapError(f"topic {channel.topic} has message encoding {channel.message_encoding!r}, expected 'json'")
    return json.loads(message.data)


def _decode_metadata_value(text: str, kind: str | None) -> Any:
    """A metadata value back to its type: "string" values are the text itself, "json" ones JSON text
    (see `EpisodeLog`). Logs before the types record (kind None) wrote every value as JSON text;
    a value that is not JSON (another writer's plain string) stays as it is."""
    if kind == "string":
        return text
    try:
        return json.loads(text)
    except ValueError:
        return text


def read_episode(path: str | os.PathLike) -> dict[str, Any]:
    """Summary of one episode log.

    Returns:
        ``{"path", "metadata", "result", "topics", "duration"}``: the decoded ``suctionbench``
        metadata record ({} if absent), the last /result message (None if the episode logged
        none), message counts per topic, and the span of log (= simulated) times in seconds.
    """
    with _open(path) as (reader, summary):
        records = {record.name: record.metadata for record in reader.iter_metadata()}
        types = records.get(METADATA_TYPES_NAME, {})
        metadata = {k: _decode_metadata_value(v, types.get(k)) for k, v in records.get(METADATA_NAME, {}).items()}
        result = None
        for _, channel, message in reader.iter_messages(topics=[TOPIC_RESULT], log_time_order=True, reverse=True):
            result = _decode(channel, message)
            break
        stats = summary.statistics
        if stats is not None:
            counts = {summary.channels[cid].topic: n for cid, n in stats.channel_message_counts.items()}
            duration = (stats.message_end_time - stats.message_start_time) / 1e9 if stats.message_count else 0.0
        else:  # another writer without statistics: count by scanning
            times = [(channel.topic, message.log_time) for _, channel, message in reader.iter_messages()]
            counts = dict(Counter(topic for topic, _ in times))
            duration = (max(t for _, t in times) - min(t for _, t in times)) / 1e9 if times else 0.0
    return {
        "path": str(path),
        "metadata": metadata,
        "result": result,
        "topics": dict(sorted(counts.items())),
        "duration": duration,
    }


def read_run(directory: str | os.PathLike) -> list[dict[str, Any]]:
    """`read_episode` of every ``*.mcap`` in `directory` (not recursive), sorted by file name.

    Temp files of episodes still being written (``.NAME.part``) are not ``*.mcap`` and so skipped.
    """
    directory = Path(directory)
    if not directory.is_dir():
        reason = "not found" if not directory.exists() else "is not a directory"
        raise InputError(f"{directory}: run directory {reason}")
    return [read_episode(p) for p in sorted(directory.glob("*.mcap")) if p.is_file()]


def iter_messages(path: str | os.PathLike, topic: str) -> Iterator[tuple[float, dict[str, Any]]]:
    """``(log_time_seconds, message)`` for every message on `topic`, in log-time order.

    The file is opened and checked at call time (so a bad path fails here, not at the first
    ``next``); a topic the episode never logged yields nothing. Decode a /camera/depth message
    with `depth_image`.
    """
    with _open(path):  # validate eagerly; the generator below reopens lazily
        pass

    def messages() -> Iterator[tuple[float, dict[str, Any]]]:
        with _open(path) as (reader, _):
            for _, channel, message in reader.iter_messages(topics=[topic], log_time_order=True):
                yield message.log_time / 1e9, _decode(channel, message)

    return messages()


def frame_pose(path: str | os.PathLike, frame: str) -> np.ndarray:
    """World-from-`frame` transform (4, 4) at the log's first /tf message that holds `frame` (the
    camera's, or the object's placement before the cup moves it). InputError if none does."""
    for _, message in iter_messages(path, "/tf"):
        for tf in message.get("transforms", []):
            if tf.get("child_frame_id") == frame:
                from scipy.spatial.transform import Rotation

                t, q = tf["translation"], tf["rotation"]
                pose = np.eye(4)
                pose[:3, :3] = Rotation.from_quat([q["x"], q["y"], q["z"], q["w"]]).as_matrix()
                pose[:3, 3] = [t["x"], t["y"], t["z"]]
                return pose
    raise _fail(Path(path), f"no {frame} transform")


def float_image(message: dict[str, Any], what: str = "image") -> np.ndarray:
    """The float32 (height, width) image of a 32FC1 RawImage message: /camera/depth (metres) or
    /grasps/quality_map (q, NaN where unscored); `what` names it in errors."""
    if message.get("encoding") != "32FC1":
        raise InputError(f"{what} message has encoding {message.get('encoding')!r}, expected '32FC1'")
    height, width, step = message["height"], message["width"], message["step"]
    raw = np.frombuffer(base64.b64decode(message["data"]), dtype="<f4")
    if step != 4 * width or raw.size != height * width:
        raise InputError(f"{what} message: {raw.size * 4} bytes do not match {height}x{width} 32FC1 (step {step})")
    return raw.reshape(height, width).astype(np.float32)


def depth_image(message: dict[str, Any]) -> np.ndarray:
    """The float32 (height, width) depth image in metres of a /camera/depth (RawImage) message."""
    return float_image(message, "depth")


def grasp_table(message: dict[str, Any]) -> dict[str, Any]:
    """Arrays of a /grasps/table message: points (N, 3), approaches (N, 3), q (N,) or None, chosen_index.

    q is None when the candidates were logged without qualities; a non-finite q was logged as
    null and comes back as NaN.
    """
    candidates = message["candidates"]

    def vectors(key: str) -> np.ndarray:
        return np.array([[c[key][a] for a in "xyz"] for c in candidates], dtype=float).reshape(-1, 3)

    has_q = bool(candidates) and all("q" in c for c in candidates)
    return {
        "points": vectors("point"),
        "approaches": vectors("approach"),
        "q": np.array([np.nan if c["q"] is None else c["q"] for c in candidates]) if has_q else None,
        "chosen_index": message.get("chosen_index"),
    }
