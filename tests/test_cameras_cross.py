"""Your camera in the benchmark: `eval --camera PRESET|TOML` renders every trial with that camera
(checked in the run logs' calibration), worker processes find a relative TOML file, the presets are
listed with their intrinsics, and a preset's TOML template reads back to the preset."""

from __future__ import annotations

import json

import numpy as np
import pytest

from suctionbench.errors import InputError
from suctionbench.evaluation.runner import run_eval
from suctionbench.evaluation.tasks import Task
from suctionbench.runlog.reader import iter_messages
from suctionbench.sensing.camera import (
    CAMERA_PRESETS,
    REALSENSE_D435,
    camera_summary,
    intrinsics_to_toml,
    load_intrinsics_toml,
)


def _calibration(log) -> dict:
    return next(iter_messages(log, "/camera/calibration"))[1]


@pytest.mark.parametrize("name", sorted(CAMERA_PRESETS))
def test_preset_template_reads_back_and_summary_states_its_view(tmp_path, name):
    preset = CAMERA_PRESETS[name]
    path = tmp_path / f"{name}.toml"
    path.write_text(intrinsics_to_toml(preset))
    assert load_intrinsics_toml(path) == preset
    row = camera_summary(preset)
    assert (row["width"], row["height"], row["fx"]) == (preset.width, preset.height, preset.fx)
    # the horizontal field of view from the focal length: 2 atan(W / 2 fx) for a centred principal point
    assert row["hfov_deg"] == pytest.approx(np.degrees(2 * np.arctan(preset.width / (2 * preset.fx))), abs=0.05)
    assert row["default"] == (name == "primesense")


def test_eval_renders_with_the_given_camera_in_every_worker(tmp_path, monkeypatch):
    custom = tmp_path / "cams" / "my_cam.toml"
    custom.parent.mkdir()
    custom.write_text(intrinsics_to_toml(REALSENSE_D435).replace('"realsense-d435"', '"my-cam"')
                      .replace("fx = 446.8", "fx = 430.0").replace("fy = 446.8", "fy = 430.0"))
    monkeypatch.chdir(tmp_path)
    summary = run_eval(Task(name="basic", set="basic", trials=2), "centroid", tmp_path / "run", workers=2,
                       camera="cams/my_cam.toml")  # relative: workers get the absolute path
    assert summary["trials"] == 2 and summary["invalid"] == 0
    run = json.loads((tmp_path / "run" / "run.json").read_text())
    assert run["camera"] == "my-cam"
    for log in sorted((tmp_path / "run" / "trials").glob("*.mcap")):
        calibration = _calibration(log)
        assert (calibration["width"], calibration["height"]) == (848, 480)
        assert calibration["K"][0] == pytest.approx(430.0)


def test_eval_rejects_an_unknown_camera_before_writing(tmp_path):
    with pytest.raises(InputError, match="unknown"):
        run_eval(Task(name="basic", set="basic", trials=1), "centroid", tmp_path / "run", camera="kinect-9")
    bad = tmp_path / "bad.toml"
    bad.write_text("name = 'x'\nwidth = 640\n")
    with pytest.raises(InputError, match="missing key"):
        run_eval(Task(name="basic", set="basic", trials=1), "centroid", tmp_path / "run", camera=str(bad))
    assert not (tmp_path / "run").exists()


def test_cameras_command_lists_presets_and_prints_a_template(tmp_path):
    from typer.testing import CliRunner

    from suctionbench.cli import app

    listed = CliRunner().invoke(app, ["cameras", "--json"])
    assert listed.exit_code == 0
    rows = json.loads(listed.stdout.strip().splitlines()[-1])["cameras"]
    assert [r["name"] for r in rows] == list(CAMERA_PRESETS) and sum(r["default"] for r in rows) == 1
    human = CliRunner().invoke(app, ["cameras"])
    assert human.exit_code == 0 and all(name in human.stdout for name in CAMERA_PRESETS)
    assert max(len(line) for line in human.stdout.splitlines()) <= 80
    template = CliRunner().invoke(app, ["cameras", "--toml", "realsense-d435"])
    (tmp_path / "mine.toml").write_text(template.stdout)  # stdout is the TOML alone: `> mine.toml` works
    assert load_intrinsics_toml(tmp_path / "mine.toml") == REALSENSE_D435
    bad = CliRunner().invoke(app, ["cameras", "--toml", "kinect-9", "--json"])
    assert bad.exit_code == 2 and "unknown" in json.loads(bad.stdout.strip().splitlines()[-1])["error"]
