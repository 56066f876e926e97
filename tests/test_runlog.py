"""Episode logs: write a synthetic episode, read it back exactly, and fail cleanly on bad files."""

from __future__ import annotations

import json

import numpy as np
import pytest
from mcap.reader import make_reader
from scipy.spatial.transform import Rotation

from suctionbench.errors import InputError
from suctionbench.runlog import (
    EpisodeLog,
    depth_image,
    float_image,
    grasp_table,
    iter_messages,
    read_episode,
    read_run,
)

N_STATES = 30
DURATION = 3.0
N_GRASPS = 20
JOINTS = ["joint_1", "joint_2", "joint_3"]
METADATA = {
    "seed": 7,
    "policy": "planarity-centroid",
    "config": {"cup": {"radius": 0.015, "vacuum_pa": 2.5e4}, "trials": 3},
    "versions": {"suctionbench": "0.1.0", "mujoco": "3.17.0"},
}
RESULT = {
    "success": np.bool_(True),
    "q": np.float32(0.75),
    "analytic_label": np.float64(0.8125),
    "attempts": np.int64(1),
    "grasp": np.array([0.01, -0.02, 0.1]),
    "object": "basic/cube",
}
EXPECTED_RESULT = {
    "success": True,
    "q": 0.75,
    "analytic_label": 0.8125,
    "attempts": 1,
    "grasp": [0.01, -0.02, 0.1],
    "object": "basic/cube",
}

_rng = np.random.default_rng(1)
_approaches = _rng.normal(size=(N_GRASPS, 3))
GRASPS = {
    "points": _rng.uniform(-0.1, 0.1, (N_GRASPS, 3)),
    "approaches": _approaches / np.linalg.norm(_approaches, axis=1, keepdims=True),
    "q": _rng.uniform(size=N_GRASPS),
}
CHOSEN = 3


def _pose(angle: float, translation: tuple[float, float, float]) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    pose = np.eye(4)
    pose[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    pose[:3, 3] = translation
    return pose


@pytest.fixture(scope="module")
def episode(tmp_path_factory):
    """Path, depth image and state times of one synthetic episode."""
    rng = np.random.default_rng(0)
    path = tmp_path_factory.mktemp("run") / "episode_000.mcap"
    depth = rng.uniform(0.5, 0.8, size=(48, 64)).astype(np.float32)
    depth[0, :3] = [np.nan, np.inf, 0.0]  # invalid pixels survive too
    k = np.array([[50.0, 0.0, 32.0], [0.0, 50.0, 24.0], [0.0, 0.0, 1.0]])
    camera = np.diag([1.0, -1.0, -1.0, 1.0])  # looking straight down
    camera[:3, 3] = [0.0, 0.0, 0.7]
    times = np.linspace(0.1, DURATION, N_STATES)
    with EpisodeLog(path, METADATA) as log:
        log.log_observation(0.0, depth, k, 64, 48, camera)
        log.log_grasps(0.05, GRASPS["points"], GRASPS["approaches"], GRASPS["q"], CHOSEN)
        for i, t in enumerate(times):
            log.log_transforms(t, {"tool": _pose(0.1 * i, (0.3, 0.0, 0.2)), "object": _pose(0.0, (0.0, 0.0, 0.03))})
            log.log_joint_states(t, JOINTS, [0.01 * i, -0.02 * i, 0.5])
            log.log_suction(t, vacuum_on=i > 10, sealed=i > 12, compression=0.001 * i)
        log.log_result(DURATION, RESULT)
    return path, depth, times


def test_summary_round_trips(episode):
    path, _, _ = episode
    summary = read_episode(path)
    assert summary["metadata"] == METADATA
    assert summary["result"] == EXPECTED_RESULT
    assert summary["topics"] == {
        "/camera/calibration": 1,
        "/camera/depth": 1,
        "/grasps/candidates": 1,
        "/grasps/chosen": 1,
        "/grasps/table": 1,
        "/joint_states": N_STATES,
        "/result": 1,
        "/suction": N_STATES,
        "/tf": N_STATES + 1,  # + the camera pose of the observation
    }
    assert summary["duration"] == pytest.approx(DURATION)
    assert read_run(path.parent) == [summary]


def test_log_times_are_simulated_times(episode):
    path, _, times = episode
    stamps, messages = zip(*iter_messages(path, "/joint_states"), strict=True)
    np.testing.assert_allclose(stamps, times, rtol=0, atol=1e-9)
    assert messages[4] == {
        "timestamp": {"sec": 0, "nsec": round(times[4] * 1e9)},
        "names": JOINTS,
        "positions": [0.04, -0.08, 0.5],
    }
    assert list(iter_messages(path, "/no/such/topic")) == []


def test_depth_image_is_bit_exact(episode):
    path, depth, _ = episode
    [(t, message)] = list(iter_messages(path, "/camera/depth"))
    assert t == 0.0
    decoded = depth_image(message)
    assert decoded.dtype == np.float32
    assert np.array_equal(decoded.view(np.uint32), depth.view(np.uint32))
    [(_, calibration)] = list(iter_messages(path, "/camera/calibration"))
    assert calibration["K"] == [50.0, 0.0, 32.0, 0.0, 50.0, 24.0, 0.0, 0.0, 1.0]
    assert (calibration["width"], calibration["height"], calibration["frame_id"]) == (64, 48, "camera")


def test_grasps_and_transforms(episode):
    path, _, _ = episode
    [(_, table)] = list(iter_messages(path, "/grasps/table"))
    [(_, chosen)] = list(iter_messages(path, "/grasps/chosen"))
    grasps = grasp_table(table)
    np.testing.assert_array_equal(grasps["points"], GRASPS["points"])  # exact: JSON floats round-trip
    np.testing.assert_array_equal(grasps["approaches"], GRASPS["approaches"])
    np.testing.assert_array_equal(grasps["q"], GRASPS["q"])
    assert grasps["chosen_index"] == CHOSEN
    assert chosen == {"timestamp": table["timestamp"], "frame_id": "world"} | table["candidates"][CHOSEN]

    [(_, scene)] = list(iter_messages(path, "/grasps/candidates"))
    arrows = {e["id"]: e["arrows"] for e in scene["entities"]}
    assert len(arrows["candidates"]) == N_GRASPS and len(arrows["chosen"]) == 1
    best = int(np.argmax(grasps["q"]))
    assert arrows["candidates"][best]["color"]["g"] == pytest.approx(grasps["q"][best])
    # Each arrow ends on its grasp point and points along the approach: tail + length * R e_x == p.
    for arrow, point, approach in zip(arrows["candidates"], grasps["points"], grasps["approaches"], strict=True):
        tail = np.array([arrow["pose"]["position"][a] for a in "xyz"])
        quat = arrow["pose"]["orientation"]
        direction = Rotation.from_quat([quat[a] for a in "xyzw"]).apply([1.0, 0.0, 0.0])
        np.testing.assert_allclose(direction, approach, atol=1e-12)
        np.testing.assert_allclose(tail + (arrow["shaft_length"] + arrow["head_length"]) * direction, point)

    _, first_tf = next(iter_messages(path, "/tf"))
    [camera] = first_tf["transforms"]
    assert camera["parent_frame_id"] == "world" and camera["child_frame_id"] == "camera"
    assert camera["translation"] == {"x": 0.0, "y": 0.0, "z": 0.7}
    assert camera["rotation"] == pytest.approx({"x": 1.0, "y": 0.0, "z": 0.0, "w": 0.0})


def test_grasps_without_quality_or_choice(tmp_path):
    path = tmp_path / "e.mcap"
    with EpisodeLog(path, {}) as log:
        log.log_grasps(0.0, np.zeros((2, 3)), [[0, 0, -1.0], [0, 0, 1.0]])  # anti-parallel approaches
        log.log_grasps(0.1, np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0))
    (_, first), (_, empty) = iter_messages(path, "/grasps/table")
    assert grasp_table(first)["q"] is None and grasp_table(first)["chosen_index"] is None
    assert grasp_table(empty)["points"].shape == (0, 3)
    assert "/grasps/chosen" not in read_episode(path)["topics"]
    (_, scene), _ = iter_messages(path, "/grasps/candidates")
    assert {a["color"]["r"] for a in scene["entities"][0]["arrows"]} == {0.6}  # grey without q


def _check_foxglove_json_schema(schema: dict, where: str) -> None:
    """The subset of JSON Schema that Foxglove's parser (mcap-support parseJsonSchema) accepts: one
    type per field (or an enum as ``oneOf`` of numeric ``const``), ``properties`` on every object,
    no arrays of arrays, bytes as base64 strings."""
    assert schema.get("type") == "object" and isinstance(schema.get("properties"), dict), where
    for name, field in schema["properties"].items():
        here = f"{where}.{name}"
        if "oneOf" in field:
            assert all(isinstance(option.get("const"), int) for option in field["oneOf"]), here
            continue
        kind = field.get("type")
        assert kind in {"boolean", "string", "number", "integer", "object", "array"}, here
        if kind == "object":
            _check_foxglove_json_schema(field, here)
        if kind == "array":
            items = field["items"]
            if "oneOf" in items:
                assert all(isinstance(option.get("const"), int) for option in items["oneOf"]), here
                continue
            item_kind = items.get("type")
            assert item_kind in {"boolean", "string", "number", "integer", "object"}, here
            if item_kind == "object":
                _check_foxglove_json_schema(items, here)
        if kind == "string":
            assert field.get("contentEncoding") in {None, "base64"}, here


def _validate_every_message(path) -> dict[str, int]:
    """Validate each message of the log at `path` against its embedded JSON Schema and, for foxglove.*
    schemas, against Foxglove's published schema; returns messages checked per schema name."""
    jsonschema = pytest.importorskip("jsonschema")
    from suctionbench.runlog.writer import SCHEMA_DIR

    checked: dict[str, int] = {}
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        validators = {}
        for schema_id, schema in reader.get_summary().schemas.items():
            embedded = json.loads(schema.data)
            jsonschema.Draft202012Validator.check_schema(embedded)
            validators[schema_id] = [jsonschema.Draft202012Validator(embedded)]
            if schema.name.startswith("foxglove."):
                published = json.loads((SCHEMA_DIR / f"{schema.name}.json").read_text())
                assert embedded == published, f"{schema.name}: embedded schema is not the published one"
                assert published["required"], schema.name
                validators[schema_id].append(jsonschema.Draft202012Validator(published))
        for schema, channel, message in reader.iter_messages():
            data = json.loads(message.data)
            for validator in validators[schema.id]:
                errors = sorted(validator.iter_errors(data), key=str)
                assert not errors, f"{channel.topic} ({schema.name}) at {message.log_time}: {errors[0].message}"
            checked[schema.name] = checked.get(schema.name, 0) + 1
    return checked


def test_every_message_is_valid_against_the_published_schemas(episode):
    path, _, _ = episode
    checked = _validate_every_message(path)
    assert checked["foxglove.SceneUpdate"] == 1 and checked["foxglove.FrameTransforms"] == N_STATES + 1
    assert sum(checked.values()) == 6 + (N_STATES + 1) + 2 * N_STATES  # every message of the log


@pytest.mark.parametrize("policy", ["planarity-centroid", "fc-gqcnn"])
def test_a_real_pick_log_is_valid_against_the_published_schemas(tmp_path, policy):
    from suctionbench.sim.pick import PickRequest, PickRunner

    path = tmp_path / "pick.mcap"
    PickRunner(PickRequest("basic/box_tea", policy=policy, seed=4)).run(log=path)
    checked = _validate_every_message(path)
    for name in ("foxglove.RawImage", "foxglove.CameraCalibration", "foxglove.FrameTransforms", "foxglove.SceneUpdate"):
        assert checked.get(name, 0) >= 1, (name, checked)
    [(_, scene)] = list(iter_messages(path, "/grasps/candidates"))[:1]
    entity = scene["entities"][0]
    assert entity["arrows"] and all(entity[k] == [] for k in ("cubes", "spheres", "cylinders", "lines", "texts"))
    maps = list(iter_messages(path, "/grasps/quality_map"))
    if policy != "fc-gqcnn":  # only a dense policy has a quality map
        assert maps == []
        return
    # the dense policy's map: one q per candidate pixel, on the depth image's grid, the rest NaN
    [(_, message)] = maps
    quality = float_image(message, "quality map")
    [(_, depth)] = list(iter_messages(path, "/camera/depth"))[:1]
    assert quality.shape == depth_image(depth).shape
    [(_, table)] = list(iter_messages(path, "/grasps/table"))
    q = grasp_table(table)["q"]
    assert np.isfinite(quality).sum() == len(q)
    np.testing.assert_allclose(np.sort(quality[np.isfinite(quality)]), np.sort(q.astype(np.float32)), atol=1e-6)


def test_quality_map_round_trips_exactly(tmp_path):
    rng = np.random.default_rng(2)
    quality = rng.uniform(size=(30, 40)).astype(np.float32)
    quality[rng.uniform(size=quality.shape) < 0.5] = np.nan
    with EpisodeLog(tmp_path / "q.mcap", {}) as log:
        log.log_quality_map(0.0, quality)
        with pytest.raises(ValueError, match="quality map has shape"):
            log.log_quality_map(0.0, quality[0])
    [(_, message)] = list(iter_messages(tmp_path / "q.mcap", "/grasps/quality_map"))
    np.testing.assert_array_equal(float_image(message), quality)  # NaN where NaN, bit-exact elsewhere
    with pytest.raises(InputError, match="quality map message has encoding"):
        float_image({**message, "encoding": "mono8"}, "quality map")


def test_a_wrong_message_fails_the_published_schema():
    """The check above can fail: an entity without its empty arrays (the old logs) is rejected."""
    jsonschema = pytest.importorskip("jsonschema")
    from suctionbench.runlog.writer import SCHEMAS

    stamp = {"sec": 0, "nsec": 0}
    entity = {
        "timestamp": stamp,
        "frame_id": "world",
        "id": "x",
        "lifetime": stamp,
        "frame_locked": False,
        "metadata": [],
        "arrows": [],
    }
    validator = jsonschema.Draft202012Validator(SCHEMAS["foxglove.SceneUpdate"])
    errors = list(validator.iter_errors({"deletions": [], "entities": [entity]}))
    assert {e.message for e in errors} >= {"'cubes' is a required property", "'models' is a required property"}


def test_plain_mcap_reader_sees_foxglove_schemas(episode):
    path, _, _ = episode
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        summary = reader.get_summary()
        schemas = {c.topic: summary.schemas[c.schema_id] for c in summary.channels.values()}
        assert all(c.message_encoding == "json" for c in summary.channels.values())
        assert all(s.encoding == "jsonschema" for s in schemas.values())
        for topic, schema in schemas.items():
            _check_foxglove_json_schema(json.loads(schema.data), topic)
        names = {topic: s.name for topic, s in schemas.items()}
        assert names["/camera/depth"] == "foxglove.RawImage"
        assert names["/camera/calibration"] == "foxglove.CameraCalibration"
        assert names["/tf"] == "foxglove.FrameTransforms"
        assert names["/grasps/candidates"] == "foxglove.SceneUpdate"
        assert all(n.startswith("suctionbench.") for t, n in names.items() if not n.startswith("foxglove."))
        raw_image = json.loads(schemas["/camera/depth"].data)
        assert raw_image["properties"]["data"]["contentEncoding"] == "base64"
        records = {meta.name: meta.metadata for meta in reader.iter_metadata()}
        assert set(records) == {"suctionbench", "suctionbench.types"}
        # plain strings: a string is itself, not JSON text ("planarity-centroid", not "\"planarity-centroid\"")
        assert records["suctionbench"]["policy"] == "planarity-centroid"
        assert (
            records["suctionbench"]["seed"] == "7"
            and json.loads(records["suctionbench"]["config"]) == METADATA["config"]
        )
        assert records["suctionbench.types"] == {
            "seed": "json",
            "policy": "string",
            "config": "json",
            "versions": "json",
        }
        assert sum(1 for _ in reader.iter_messages()) == summary.statistics.message_count


def test_exception_in_block_leaves_no_file(tmp_path):
    path = tmp_path / "broken.mcap"
    with pytest.raises(RuntimeError, match="simulation blew up"), EpisodeLog(path, {"seed": 1}) as log:
        log.log_suction(0.0, True, False, 0.0)
        raise RuntimeError("simulation blew up")
    assert list(tmp_path.iterdir()) == []


def test_file_appears_only_on_close(tmp_path):
    path = tmp_path / "sub" / "episode.mcap"
    log = EpisodeLog(path, {})
    log.log_result(1.0, {"success": False})
    assert not path.exists() and len(list(path.parent.iterdir())) == 1
    assert read_run(path.parent) == []  # the .part file is not an episode
    log.close()
    assert [p.name for p in path.parent.iterdir()] == ["episode.mcap"]
    assert read_episode(path)["result"] == {"success": False}
    with pytest.raises(RuntimeError, match="closed"):
        log.log_result(2.0, {})


def test_bad_inputs_to_the_writer(tmp_path):
    with pytest.raises(TypeError, match="object"):
        EpisodeLog(tmp_path / "x.mcap", {"bad": object()})
    assert list(tmp_path.iterdir()) == []
    with EpisodeLog(tmp_path / "y.mcap", {}) as log:
        with pytest.raises(ValueError, match="non-negative"):
            log.log_suction(-1.0, True, True, 0.0)
        with pytest.raises(ValueError, match="shape"):
            log.log_observation(0.0, np.zeros((4, 4), np.float32), np.eye(3), 5, 4, np.eye(4))
        log.log_result(0.0, {"q": float("nan")})
    assert read_episode(tmp_path / "y.mcap")["result"] == {"q": None}  # JSON has no NaN


@pytest.mark.parametrize(
    ("damage", "message"),
    [
        (lambda data: data[: len(data) // 2], "truncated"),
        (lambda data: b"PK\x03\x04 not an mcap at all" + data[30:], "not an MCAP file"),
        (lambda data: data[:200] + bytes(b ^ 0xFF for b in data[200:-200]) + data[-200:], "corrupt"),
        (lambda data: b"", "not an MCAP file"),
    ],
    ids=["truncated", "foreign", "flipped", "empty"],
)
def test_damaged_files_raise_input_error(episode, tmp_path, damage, message):
    path, _, _ = episode
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(damage(path.read_bytes()))
    for read in (read_episode, lambda p: list(iter_messages(p, "/camera/depth")), read_run):
        with pytest.raises(InputError, match=message) as info:
            read(bad if read is not read_run else tmp_path)
        assert str(bad) in str(info.value) and "\n" not in str(info.value)


def test_missing_paths_raise_input_error(tmp_path):
    with pytest.raises(InputError, match="not found"):
        read_episode(tmp_path / "nope.mcap")
    with pytest.raises(InputError, match="not found"):
        iter_messages(tmp_path / "nope.mcap", "/tf")
    with pytest.raises(InputError, match="not found"):
        read_run(tmp_path / "nope")
    with pytest.raises(InputError, match="is a directory"):
        read_episode(tmp_path)


def test_logs_with_json_text_metadata_still_read(tmp_path):
    """Logs written before the plain-string metadata (every value JSON text, no types record)."""
    from mcap.writer import Writer

    path = tmp_path / "old.mcap"
    with open(path, "wb") as f:
        writer = Writer(f)
        writer.start(profile="", library="suctionbench 0.1.0")
        writer.add_metadata(
            "suctionbench", {"suctionbench_version": '"0.1.0"', "seed": "3", "cup": '{"radius": 0.015}'}
        )
        writer.finish()
    assert read_episode(path)["metadata"] == {"suctionbench_version": "0.1.0", "seed": 3, "cup": {"radius": 0.015}}
    new = tmp_path / "new.mcap"
    with EpisodeLog(new, {"suctionbench_version": "0.1.0", "seed": 3, "cup": {"radius": 0.015}, "tag": "7"}):
        pass
    assert read_episode(new)["metadata"] == {
        "suctionbench_version": "0.1.0",
        "seed": 3,
        "cup": {"radius": 0.015},
        "tag": "7",
    }  # a string that looks like JSON stays a string
