"""`EpisodeLog`: write one pick episode to an MCAP file (see the package docstring for the format).

All ``log_*`` methods take ``t`` in seconds of *simulated* time and store it as the message's
log time in nanoseconds. Channels and schemas are registered on first use, so a log holds only
the topics an episode actually produced.
"""

from __future__ import annotations

import base64
import contextlib
import dataclasses
import json
import math
import os
import uuid
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import IO, Any

import numpy as np
from mcap.writer import Writer
from scipy.spatial.transform import Rotation

from suctionbench import __version__
from suctionbench.geometry.frames import approach_frames
from suctionbench.io import remove_stale_temporaries, writer_tag

METADATA_NAME = "suctionbench"
"""Name of the MCAP metadata record holding the run metadata."""

METADATA_TYPES_NAME = "suctionbench.types"
"""Name of the metadata record that says, per key of METADATA_NAME, how its value is written:
"string" (the text itself) or "json" (numbers, booleans, null, lists and tables as JSON text)."""

WORLD_FRAME = "world"
"""Root frame of every transform on /tf."""

# Topic names: the contract between this writer, the reader and Foxglove layouts.
TOPIC_DEPTH = "/camera/depth"
TOPIC_CALIBRATION = "/camera/calibration"
TOPIC_TF = "/tf"
TOPIC_JOINTS = "/joint_states"
TOPIC_GRASP_SCENE = "/grasps/candidates"
TOPIC_GRASP_TABLE = "/grasps/table"
TOPIC_GRASP_CHOSEN = "/grasps/chosen"
TOPIC_QUALITY_MAP = "/grasps/quality_map"
TOPIC_SUCTION = "/suction"
TOPIC_RESULT = "/result"

# Display-only sizes of the grasp arrows in the 3D panel (metres). The arrow's tip sits on the
# grasp point and it points along the approach direction, like the cup coming in.
ARROW_SHAFT_LENGTH = 0.03
ARROW_SHAFT_DIAMETER = 0.002
ARROW_HEAD_LENGTH = 0.01
ARROW_HEAD_DIAMETER = 0.005
CHOSEN_ARROW_SCALE = 2.0
"""The chosen grasp is drawn this many times thicker than the other candidates."""
NO_QUALITY_COLOR = {"r": 0.6, "g": 0.6, "b": 0.6, "a": 1.0}
SCENE_PRIMITIVES = ("arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models")
"""The primitive arrays of a foxglove.SceneEntity (all required by the published schema)."""
"""Colour of candidates without a quality (q is None or NaN)."""


# --------------------------------------------------------------------------------------------
# JSON Schemas. Foxglove identifies well-known types by the schema *name* and checks messages
# against its published JSON Schemas, whose `required` lists every field (a SceneEntity must carry
# all its primitive arrays, even empty). The foxglove.* schemas are those published schemas,
# vendored unchanged from the `@foxglove/schemas` npm package (see schemas/README.md), and every
# message below is written to satisfy them (tests/test_runlog.py validates each message of a real
# pick log with jsonschema). Our own records are suctionbench.* schemas in the same style: one type
# per field, "properties" on every object, `required` for what is always there.
# --------------------------------------------------------------------------------------------

SCHEMA_DIR = Path(__file__).parent / "schemas"
"""The vendored Foxglove JSON Schemas (foxglove.NAME.json)."""

FOXGLOVE_SCHEMAS_VERSION = "@foxglove/schemas 2.1.0"
"""Where the vendored foxglove.* schemas come from."""

FOXGLOVE_SCHEMAS = (
    "foxglove.RawImage",
    "foxglove.CameraCalibration",
    "foxglove.FrameTransforms",
    "foxglove.SceneUpdate",
)
"""The well-known Foxglove types a log uses."""


def _foxglove(name: str) -> dict:
    return json.loads((SCHEMA_DIR / f"{name}.json").read_text())


def _obj(required: bool = True, **properties: dict) -> dict:
    schema = {"type": "object", "properties": properties}
    if required:
        schema["required"] = list(properties)
    return schema


def _array(items: dict) -> dict:
    return {"type": "array", "items": items}


_NUM = {"type": "number"}
_INT = {"type": "integer"}
_STR = {"type": "string"}
_BOOL = {"type": "boolean"}
_TIME = _obj(sec={"type": "integer", "minimum": 0}, nsec={"type": "integer", "minimum": 0, "maximum": 999_999_999})
_VEC3 = _obj(x=_NUM, y=_NUM, z=_NUM)

# Optional fields ("q" without qualities, "chosen_index" without a choice) are left out rather
# than null, because Foxglove's JSON Schema parser accepts only one type per field.
_GRASP_CANDIDATE = _obj(index=_INT, point=_VEC3, approach=_VEC3, q=_NUM) | {"required": ["index", "point", "approach"]}

SCHEMAS: dict[str, dict] = {
    **{
        name: _foxglove(name)
        for name in (
            "foxglove.RawImage",
            "foxglove.CameraCalibration",
            "foxglove.FrameTransforms",
            "foxglove.SceneUpdate",
        )
    },
    "suctionbench.JointStates": _obj(timestamp=_TIME, names=_array(_STR), positions=_array(_NUM)),
    "suctionbench.GraspTable": _obj(
        timestamp=_TIME, frame_id=_STR, chosen_index=_INT, candidates=_array(_GRASP_CANDIDATE)
    )
    | {"required": ["timestamp", "frame_id", "candidates"]},
    "suctionbench.ChosenGrasp": _obj(timestamp=_TIME, frame_id=_STR, **_GRASP_CANDIDATE["properties"])
    | {"required": ["timestamp", "frame_id", "index", "point", "approach"]},
    "suctionbench.Suction": _obj(timestamp=_TIME, vacuum_on=_BOOL, sealed=_BOOL, compression=_NUM),
    # Free-form record: Foxglove needs "properties" on every object, even an open one.
    "suctionbench.EpisodeResult": {"type": "object", "properties": {}, "description": "The episode's outcome."},
}

TOPIC_SCHEMAS: dict[str, str] = {
    TOPIC_DEPTH: "foxglove.RawImage",
    TOPIC_CALIBRATION: "foxglove.CameraCalibration",
    TOPIC_TF: "foxglove.FrameTransforms",
    TOPIC_JOINTS: "suctionbench.JointStates",
    TOPIC_GRASP_SCENE: "foxglove.SceneUpdate",
    TOPIC_GRASP_TABLE: "suctionbench.GraspTable",
    TOPIC_GRASP_CHOSEN: "suctionbench.ChosenGrasp",
    TOPIC_QUALITY_MAP: "foxglove.RawImage",
    TOPIC_SUCTION: "suctionbench.Suction",
    TOPIC_RESULT: "suctionbench.EpisodeResult",
}


# --------------------------------------------------------------------------------------------
# Value conversion
# --------------------------------------------------------------------------------------------


def jsonable(value: Any) -> Any:
    """`value` as plain JSON types: numpy scalars/arrays, tuples, paths and dataclasses converted.

    Non-finite floats become ``None`` because JSON has no NaN/Infinity and Foxglove (a browser
    ``JSON.parse``) rejects them; ``None`` is what JavaScript itself writes for them.
    """
    if value is None or isinstance(value, bool | int | str):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, np.ndarray | np.generic):
        return jsonable(value.tolist())
    if isinstance(value, Mapping):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple | set | frozenset):
        return [jsonable(v) for v in value]
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return jsonable(dataclasses.asdict(value))
    raise TypeError(f"cannot log a value of type {type(value).__name__} as JSON: {value!r:.80}")


def metadata_record(metadata: Mapping[str, Any]) -> tuple[dict[str, str], dict[str, str]]:
    """MCAP metadata (string -> string) for `metadata`, and the record of each value's encoding."""
    record, types = {}, {}
    for key, value in metadata.items():
        value = jsonable(value)
        plain = isinstance(value, str)
        record[str(key)] = value if plain else json.dumps(value, allow_nan=False)
        types[str(key)] = "string" if plain else "json"
    return record, types


def seconds_to_ns(t: float) -> int:
    """Simulated time in seconds -> MCAP time in integer nanoseconds (rounded, must be >= 0)."""
    if not math.isfinite(t) or t < 0:
        raise ValueError(f"log time must be a finite, non-negative number of seconds, got {t!r}")
    return round(t * 1e9)


def _timestamp(ns: int) -> dict[str, int]:
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def _float_image(stamp: dict[str, int], frame_id: str, image: np.ndarray) -> dict[str, Any]:
    """A foxglove.RawImage message of a float32 (H, W) image: 32FC1, little-endian, base64."""
    image = np.ascontiguousarray(image, dtype="<f4")
    height, width = image.shape
    return {"timestamp": stamp, "frame_id": frame_id, "width": width, "height": height, "encoding": "32FC1",
            "step": width * 4, "data": base64.b64encode(image.tobytes()).decode("ascii")}


def _xyz(v: np.ndarray) -> dict[str, float]:
    return {"x": float(v[0]), "y": float(v[1]), "z": float(v[2])}


def _quaternions(rotations: np.ndarray) -> list[dict[str, float]]:
    """Foxglove quaternions of rotation matrices (..., 3, 3)."""
    quats = Rotation.from_matrix(np.reshape(rotations, (-1, 3, 3))).as_quat()  # (x, y, z, w)
    return [{"x": float(x), "y": float(y), "z": float(z), "w": float(w)} for x, y, z, w in quats]


def _as_array(name: str, value: Any, shape: tuple[int | None, ...]) -> np.ndarray:
    """`value` as a float array of `shape` (None = any length); ValueError naming it otherwise."""
    arr = np.asarray(value, dtype=float)
    if arr.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, arr.shape, strict=True)):
        want = "x".join("N" if s is None else str(s) for s in shape)
        raise ValueError(f"{name} must have shape ({want}), got {arr.shape}")
    return arr


# --------------------------------------------------------------------------------------------
# The writer
# --------------------------------------------------------------------------------------------


class EpisodeLog:
    """An MCAP log of one pick episode, written atomically.

    Messages go to a hidden temp file next to `path` (``.NAME.PID-HOST.XXXXXXXX.part``, see
    `suctionbench.io`: the next log of `path` removes one whose writer was killed); `close` finishes
    the MCAP summary, fsyncs and renames it onto `path`, so `path` is either absent or a complete,
    indexed file — never a half-written log that a later ``read_run`` would trip over. Used as a
    context manager, an exception inside the block discards the temp file instead (`abort`).

    Args:
        path: destination ``.mcap`` file; its parent directories are created; an existing file
            is replaced on close.
        metadata: run metadata (config, versions, seed, ...); stored as the MCAP metadata record
            ``"suctionbench"`` with plain string values: a string as itself, anything else as
            JSON text (``7``, ``true``, ``{"radius": 0.015}``), and a second record
            ``"suctionbench.types"`` naming which is which so the reader restores the types.
            (The writing suctionbench version is also in the MCAP header's ``library`` field.)
    """

    def __init__(self, path: str | os.PathLike, metadata: Mapping[str, Any]):
        self.path = Path(path)
        # Serialise before touching the disk, so bad metadata leaves nothing behind.
        record, types = metadata_record(metadata)
        self._tmp_path = self.path.with_name(f".{self.path.name}.{writer_tag()}.{uuid.uuid4().hex[:8]}.part")
        self._schema_ids: dict[str, int] = {}
        self._channel_ids: dict[str, int] = {}
        self._sequence: dict[str, int] = {}
        self._file: IO[bytes] | None = None
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            remove_stale_temporaries(self.path)
            self._file = open(self._tmp_path, "xb")  # noqa: SIM115 (closed in close/abort)
        except OSError as exc:
            raise self._named(exc) from None
        try:
            self._writer = Writer(self._file)
            self._writer.start(profile="", library=f"suctionbench {__version__}")
            self._writer.add_metadata(METADATA_NAME, record)
            self._writer.add_metadata(METADATA_TYPES_NAME, types)
        except OSError as exc:  # a full disk while the header is flushed
            self.abort()
            raise self._named(exc) from None
        except BaseException:
            self.abort()
            raise

    # -- lifecycle ---------------------------------------------------------------------------

    def __enter__(self) -> EpisodeLog:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()

    @property
    def closed(self) -> bool:
        return self._file is None

    def close(self) -> None:
        """Finish the file (summary, indexes) and move it onto `path`. Idempotent."""
        if self._file is None:
            return
        try:
            self._writer.finish()
            self._file.flush()
            os.fsync(self._file.fileno())
        except OSError as exc:
            self.abort()
            raise self._named(exc) from None
        except BaseException:
            self.abort()
            raise
        self._file.close()
        self._file = None
        try:
            os.replace(self._tmp_path, self.path)
        except OSError as exc:
            self._tmp_path.unlink(missing_ok=True)
            raise self._named(exc) from None

    def _named(self, exc: OSError) -> OSError:
        """`exc` about the log's own path, not its hidden temp file (what the user named)."""
        return type(exc)(exc.errno, exc.strerror, str(self.path)) if exc.errno else exc

    def abort(self) -> None:
        """Discard the episode: close and delete the temp file; `path` is left untouched.

        Closing flushes what is buffered, which fails on a full disk: the temp file is deleted all
        the same (the error that led here is the one worth reporting)."""
        if self._file is None:
            return
        file, self._file = self._file, None
        with contextlib.suppress(OSError):
            file.close()
        self._tmp_path.unlink(missing_ok=True)

    # -- low level ---------------------------------------------------------------------------

    def _channel(self, topic: str) -> int:
        """Channel id of `topic`, registering it (and its schema) on first use."""
        channel_id = self._channel_ids.get(topic)
        if channel_id is None:
            schema_name = TOPIC_SCHEMAS[topic]
            schema_id = self._schema_ids.get(schema_name)
            if schema_id is None:
                schema = {"title": schema_name, **SCHEMAS[schema_name]}
                schema_id = self._writer.register_schema(
                    name=schema_name, encoding="jsonschema", data=json.dumps(schema).encode()
                )
                self._schema_ids[schema_name] = schema_id
            channel_id = self._writer.register_channel(topic=topic, message_encoding="json", schema_id=schema_id)
            self._channel_ids[topic] = channel_id
        return channel_id

    def _write(self, topic: str, ns: int, message: Mapping[str, Any]) -> None:
        """Append `message` (converted with `jsonable`) to `topic` at log time `ns` nanoseconds."""
        if self._file is None:
            raise RuntimeError(f"episode log {self.path} is already closed")
        data = json.dumps(jsonable(message), allow_nan=False, separators=(",", ":")).encode()
        try:
            channel_id = self._channel(topic)
            sequence = self._sequence.get(topic, 0)
            self._writer.add_message(channel_id, log_time=ns, data=data, publish_time=ns, sequence=sequence)
        except OSError as exc:  # a full disk while a chunk is flushed
            raise self._named(exc) from None
        self._sequence[topic] = sequence + 1

    @staticmethod
    def _frame_transform(ns: int, child: str, world_from_child: Any) -> dict[str, Any]:
        pose = _as_array(f"transform of {child!r}", world_from_child, (4, 4))
        return {
            "timestamp": _timestamp(ns),
            "parent_frame_id": WORLD_FRAME,
            "child_frame_id": child,
            "translation": _xyz(pose[:3, 3]),
            "rotation": _quaternions(pose[:3, :3])[0],
        }

    # -- episode content ---------------------------------------------------------------------

    def log_observation(
        self,
        t: float,
        depth: np.ndarray,
        intrinsics_matrix: Any,
        width: int,
        height: int,
        camera_pose_world: Any,
        frame_id: str = "camera",
    ) -> None:
        """A depth image (metres, float32 (H, W)) with its calibration and camera pose.

        The pose is world-from-camera in the OpenCV optical frame (x right, y down, z forward),
        which is also Foxglove's camera convention, so it goes on /tf unchanged.
        """
        ns = seconds_to_ns(t)
        depth = np.ascontiguousarray(depth, dtype="<f4")  # 32FC1 is little-endian float32
        if depth.shape != (height, width):
            raise ValueError(f"depth image has shape {depth.shape}, expected (height, width) = ({height}, {width})")
        k = _as_array("intrinsics_matrix", intrinsics_matrix, (3, 3))
        stamp = _timestamp(ns)
        self._write(TOPIC_DEPTH, ns, _float_image(stamp, frame_id, depth))
        self._write(
            TOPIC_CALIBRATION,
            ns,
            {
                "timestamp": stamp,
                "frame_id": frame_id,
                "width": width,
                "height": height,
                "distortion_model": "plumb_bob",  # rendered depth: an ideal pinhole, all D zero
                "D": [0.0] * 5,
                "K": k.ravel(),
                "R": np.eye(3).ravel(),
                "P": np.hstack([k, np.zeros((3, 1))]).ravel(),
            },
        )
        self._write(TOPIC_TF, ns, {"transforms": [self._frame_transform(ns, frame_id, camera_pose_world)]})

    def log_quality_map(self, t: float, quality: np.ndarray, frame_id: str = "camera") -> None:
        """A dense policy's quality map: q of the grasp at each pixel of the depth image it planned
        on (float32 (H, W), NaN where no grasp was scored), as a 32FC1 image in the camera's frame,
        so Foxglove shows it beside /camera/depth and `reader.float_image` reads it back."""
        quality = np.asarray(quality, dtype="<f4")
        if quality.ndim != 2:
            raise ValueError(f"quality map has shape {quality.shape}, expected (height, width)")
        ns = seconds_to_ns(t)
        self._write(TOPIC_QUALITY_MAP, ns, _float_image(_timestamp(ns), frame_id, quality))

    def log_transforms(self, t: float, transforms: Mapping[str, Any]) -> None:
        """Poses of named frames, each a 4x4 world-from-child matrix, as one /tf message."""
        ns = seconds_to_ns(t)
        self._write(TOPIC_TF, ns, {"transforms": [self._frame_transform(ns, c, m) for c, m in transforms.items()]})

    def log_joint_states(self, t: float, names: Sequence[str], positions: Sequence[float]) -> None:
        """Joint positions (radians or metres) by joint name."""
        if len(names) != len(positions):
            raise ValueError(f"{len(names)} joint names but {len(positions)} positions")
        ns = seconds_to_ns(t)
        self._write(TOPIC_JOINTS, ns, {"timestamp": _timestamp(ns), "names": list(names), "positions": positions})

    def log_grasps(
        self,
        t: float,
        points: Any,
        approaches: Any,
        q: Any = None,
        chosen_index: int | None = None,
        frame_id: str = WORLD_FRAME,
    ) -> None:
        """Grasp candidates: arrows in the 3D scene, the raw numbers, and the chosen grasp.

        Arrows are coloured by q from red (0) to green (1), grey without q; the chosen one is
        drawn thicker. /grasps/table lists every candidate as ``{index, point: {x, y, z},
        approach: {x, y, z}, q}`` (q left out when None; ``reader.grasp_table`` turns it back
        into arrays); /grasps/chosen repeats the chosen candidate's record.
        """
        ns = seconds_to_ns(t)
        points = _as_array("points", points, (None, 3))
        approaches = _as_array("approaches", approaches, (len(points), 3))
        if q is not None:
            q = _as_array("q", q, (len(points),))
        if chosen_index is not None and not 0 <= chosen_index < len(points):
            raise ValueError(f"chosen_index {chosen_index} out of range for {len(points)} candidates")
        stamp = _timestamp(ns)

        arrows = _grasp_arrows(points, approaches, q)
        entities = [_entity(stamp, frame_id, "candidates", arrows)]
        if chosen_index is not None:
            chosen = dict(arrows[chosen_index])
            for key in ("shaft_diameter", "head_diameter"):
                chosen[key] *= CHOSEN_ARROW_SCALE
            entities.append(_entity(stamp, frame_id, "chosen", [chosen]))
        # Delete-all first, so a "chosen" arrow from an earlier update does not linger.
        deletions = [{"timestamp": stamp, "type": 1, "id": ""}]
        self._write(TOPIC_GRASP_SCENE, ns, {"deletions": deletions, "entities": entities})
        candidates = [
            {"index": i, "point": _xyz(p), "approach": _xyz(v)} | ({} if q is None else {"q": q[i]})
            for i, (p, v) in enumerate(zip(points, approaches, strict=True))
        ]
        table = {"timestamp": stamp, "frame_id": frame_id, "candidates": candidates}
        if chosen_index is not None:
            table["chosen_index"] = chosen_index
        self._write(TOPIC_GRASP_TABLE, ns, table)
        if chosen_index is not None:
            self._write(TOPIC_GRASP_CHOSEN, ns, {"timestamp": stamp, "frame_id": frame_id} | candidates[chosen_index])

    def log_suction(self, t: float, vacuum_on: bool, sealed: bool, compression: float) -> None:
        """State of the suction cup: vacuum command, seal test, bellow compression (metres)."""
        ns = seconds_to_ns(t)
        self._write(
            TOPIC_SUCTION,
            ns,
            {
                "timestamp": _timestamp(ns),
                "vacuum_on": bool(vacuum_on),
                "sealed": bool(sealed),
                "compression": float(compression),
            },
        )

    def log_result(self, t: float, result: Mapping[str, Any]) -> None:
        """The episode's outcome record, stored as given (numpy values converted by `jsonable`)."""
        self._write(TOPIC_RESULT, seconds_to_ns(t), result)


def _quality_colors(q: np.ndarray | None, n: int) -> list[dict[str, float]]:
    """Red (q = 0) to green (q = 1) per candidate; grey where q is missing or NaN."""
    if q is None:
        return [NO_QUALITY_COLOR] * n
    return [
        {"r": 1.0 - float(v), "g": float(v), "b": 0.0, "a": 1.0} if math.isfinite(v) else NO_QUALITY_COLOR
        for v in np.clip(q, 0.0, 1.0)
    ]


def _grasp_arrows(points: np.ndarray, approaches: np.ndarray, q: np.ndarray | None) -> list[dict[str, Any]]:
    """Foxglove ArrowPrimitives ending on each grasp point, pointing along its approach."""
    if len(points) == 0:
        return []
    frames = approach_frames(approaches)  # columns (x, y, z = approach)
    # An identity-oriented arrow points along +x: use the right-handed frame (approach, x, y).
    orientations = _quaternions(frames[:, :, [2, 0, 1]])
    tails = points - (ARROW_SHAFT_LENGTH + ARROW_HEAD_LENGTH) * frames[:, :, 2]
    return [
        {
            "pose": {"position": _xyz(tail), "orientation": orientation},
            "shaft_length": ARROW_SHAFT_LENGTH,
            "shaft_diameter": ARROW_SHAFT_DIAMETER,
            "head_length": ARROW_HEAD_LENGTH,
            "head_diameter": ARROW_HEAD_DIAMETER,
            "color": color,
        }
        for tail, orientation, color in zip(tails, orientations, _quality_colors(q, len(points)), strict=True)
    ]


def _entity(stamp: dict[str, int], frame_id: str, entity_id: str, arrows: list[dict]) -> dict[str, Any]:
    """A SceneEntity that persists until the next update (zero lifetime) and is fixed in the world.

    It holds only arrows, but the published schema requires every primitive array, so the others
    are there, empty."""
    return {
        "timestamp": stamp,
        "frame_id": frame_id,
        "id": entity_id,
        "lifetime": {"sec": 0, "nsec": 0},
        "frame_locked": False,
        "metadata": [],
        "arrows": arrows,
        **{kind: [] for kind in SCENE_PRIMITIVES if kind != "arrows"},
    }
