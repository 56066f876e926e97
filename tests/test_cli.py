"""The `suctionbench` CLI contract (DESIGN.md), exercised through typer's CliRunner on tiny meshes.

With --json the last stdout line is exactly one JSON object; exit 0 on success, 2 on bad input
(one line on stderr naming the input and the problem, nothing written), 1 on internal failure.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import trimesh
from typer.testing import CliRunner

import suctionbench
from suctionbench.cli import app

BOX_EXTENTS = (0.1, 0.08, 0.04)
"""A 10 x 8 x 4 cm box: top face at z = 0.02 m."""

TOP_GRASP = "0,0,0.02,0,0,-1"
"""Centre of the box's top face, approached straight down."""

MASS = "0.2"
"""Below the default cup's payload, so no mass warning clutters stderr."""

runner = CliRunner()


# ----------------------------------------------------------------------------------------------
# helpers


def invoke(*args: Any):
    return runner.invoke(app, [str(a) for a in args])


def stderr_of(result) -> str:
    """stderr where the runner separates it (click >= 8.2, typer's own runner); else the mix."""
    try:
        return result.stderr
    except ValueError:  # older click with mix_stderr=True
        return result.output


def last_json(result) -> dict[str, Any]:
    """The JSON object on the last non-empty stdout line (the contract says: exactly one)."""
    lines = [line for line in result.stdout.splitlines() if line.strip()]
    assert lines, f"no stdout at all; stderr: {stderr_of(result)!r}"
    payload = json.loads(lines[-1])
    assert isinstance(payload, dict)
    return payload


def squash(text: str) -> str:
    """Lower-case text without whitespace: robust to rich wrapping long lines on stderr."""
    return re.sub(r"\s+", "", text).lower()


def mentions(text: str, needle: str | tuple[str, ...]) -> bool:
    """Whether `text` mentions `needle` (a tuple: any of them), ignoring case and line wraps."""
    options = needle if isinstance(needle, tuple) else (needle,)
    return any(squash(option) in squash(text) for option in options)


def snapshot(root: Path) -> list[str]:
    """Every path under root (files and folders), to check that a failed run wrote nothing."""
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


def write_box(path: Path, extents=BOX_EXTENTS) -> Path:
    trimesh.creation.box(extents=extents).export(path)
    return path


@pytest.fixture
def box(tmp_path: Path) -> Path:
    return write_box(tmp_path / "box.stl")


# ----------------------------------------------------------------------------------------------
# 1. one grasp


def test_label_single_grasp_json(box: Path) -> None:
    result = invoke("label", box, "--grasp", TOP_GRASP, "--mass", MASS, "--json")
    assert result.exit_code == 0, stderr_of(result)
    payload = last_json(result)
    assert payload["ok"] is True
    assert {"seal", "seal_failure", "max_stretch", "wr", "rwr"} <= payload.keys()
    assert payload["seal"] is True
    assert payload["seal_failure"] is None
    assert 0.0 <= payload["rwr"] <= 1.0
    assert payload["max_stretch"] is not None and payload["max_stretch"] >= 0.0


# ----------------------------------------------------------------------------------------------
# 2. determinism and --out


def test_label_same_seed_same_json(box: Path) -> None:
    args = ("label", box, "--grasp", TOP_GRASP, "--mass", MASS, "--seed", "7", "--json")
    first, second = invoke(*args), invoke(*args)
    assert first.exit_code == second.exit_code == 0
    assert last_json(first) == last_json(second)
    assert first.stdout.splitlines()[-1] == second.stdout.splitlines()[-1]


def test_label_batch_writes_npz_atomically(tmp_path: Path, box: Path) -> None:
    out = tmp_path / "X.npz"
    result = invoke("label", box, "--grasps", "50", "--mass", MASS, "--out", out, "--json")
    assert result.exit_code == 0, stderr_of(result)
    payload = last_json(result)
    assert payload["ok"] is True and payload["grasps"] == 50 and payload["out"] == str(out)
    with np.load(out) as data:
        assert data["points"].shape == (50, 3)
        assert data["approaches"].shape == (50, 3)
        assert data["rwr"].shape == (50,)
        assert data["seal"].shape == (50,)
        assert data["max_stretch"].shape == (50,)
        assert np.all((data["rwr"] >= 0) & (data["rwr"] <= 1))
    assert snapshot(tmp_path) == ["X.npz", "box.stl"]  # no temp files left behind


def test_label_batch_same_seed_same_labels(tmp_path: Path, box: Path) -> None:
    runs = {}
    for name, seed in (("a", 3), ("b", 3), ("c", 4)):
        out = tmp_path / f"{name}.npz"
        result = invoke(
            "label", box, "--grasps", "20", "--samples", "10", "--mass", MASS, "--seed", seed, "--out", out, "--json"
        )
        assert result.exit_code == 0, stderr_of(result)
        payload = last_json(result)
        for timing_or_path in ("seconds", "grasps_per_second", "out"):
            payload.pop(timing_or_path)
        with np.load(out) as data:
            runs[name] = (payload, {k: data[k] for k in data.files})
    (pa, da), (pb, db), (_, dc) = runs["a"], runs["b"], runs["c"]
    assert pa == pb
    assert da.keys() == db.keys()
    for key in da:
        np.testing.assert_array_equal(da[key], db[key], err_msg=key)
    assert not np.array_equal(da["points"], dc["points"])  # the seed does matter


# ----------------------------------------------------------------------------------------------
# 3. + 4. bad input: exit 2, a message naming the input and the problem, nothing written

Case = Callable[[Path, Path], tuple[list[Any], list[str | tuple[str, ...]]]]


def _batch(mesh: Path, tmp_path: Path, *extra: Any) -> list[Any]:
    """A --grasps run with --out, so that 'nothing written' is meaningful."""
    return ["label", mesh, "--grasps", "3", "--samples", "5", "--mass", MASS, "--out", tmp_path / "labels.npz", *extra]


def _single(mesh: Path, grasp: str, *extra: Any) -> list[Any]:
    return ["label", mesh, "--grasp", grasp, "--mass", MASS, *extra]


def case_missing_file(tmp_path: Path, box: Path):
    missing = tmp_path / "missing.stl"
    return _batch(missing, tmp_path), [str(missing), "not found"]


def case_unsupported_extension(tmp_path: Path, box: Path):
    text = tmp_path / "mesh.txt"
    text.write_bytes(box.read_bytes())
    return _batch(text, tmp_path), [str(text), ".txt", "unsupported"]


def case_garbage_stl(tmp_path: Path, box: Path):
    garbage = tmp_path / "garbage.stl"
    garbage.write_text("this is not an STL file\njust some text\n")
    return _batch(garbage, tmp_path), [str(garbage), ("could not be read", "empty", "no triangle", "no faces")]


def case_empty_obj(tmp_path: Path, box: Path):
    empty = tmp_path / "empty.obj"
    empty.write_text("# vertices but no faces\nv 0 0 0\nv 0.05 0 0\nv 0 0.05 0\n")
    return _batch(empty, tmp_path), [str(empty), ("empty", "no faces", "no triangle")]


def case_nan_vertex_obj(tmp_path: Path, box: Path):
    cube = trimesh.creation.box(extents=BOX_EXTENTS)
    lines = ["v nan 0 0" if i == 0 else "v {:g} {:g} {:g}".format(*v) for i, v in enumerate(cube.vertices)]
    lines += ["f {} {} {}".format(*(f + 1)) for f in cube.faces]
    nan_obj = tmp_path / "nan.obj"
    nan_obj.write_text("\n".join(lines) + "\n")
    return _batch(nan_obj, tmp_path), [str(nan_obj), ("nan", "non-finite", "infinite")]


def case_flat_mesh(tmp_path: Path, box: Path):
    flat = tmp_path / "flat.obj"
    flat.write_text("v 0 0 0\nv 0.05 0 0\nv 0.05 0.05 0\nv 0 0.05 0\nf 1 2 3\nf 1 3 4\n")
    return _batch(flat, tmp_path), [str(flat), "degenerate"]


def case_scale_2m(tmp_path: Path, box: Path):
    big = write_box(tmp_path / "big.stl", (2.0, 2.0, 2.0))
    return _batch(big, tmp_path, "--units", "m"), [str(big), "absurd scale"]


def case_scale_1mm(tmp_path: Path, box: Path):
    tiny = write_box(tmp_path / "tiny.stl", (0.001, 0.001, 0.001))
    return _batch(tiny, tmp_path), [str(tiny), "absurd scale"]


def case_millimetre_obj_without_units(tmp_path: Path, box: Path):
    mm = write_box(tmp_path / "box_mm.obj", (40.0, 40.0, 40.0))  # an OBJ's units are never guessed
    return _batch(mm, tmp_path), [str(mm), "absurd scale", "fits read in cm or mm"]


def case_zero_approach(tmp_path: Path, box: Path):
    return _single(box, "0,0,0.02,0,0,0"), ["--grasp", "unit vector"]


def case_non_unit_approach(tmp_path: Path, box: Path):
    return _single(box, "0,0,0.02,0,0,-2"), ["--grasp", "unit vector"]


def case_wrong_count(tmp_path: Path, box: Path):
    return _single(box, "0,0,0.02,0,0"), ["--grasp", "0,0,0.02,0,0", "6"]


def case_non_numeric(tmp_path: Path, box: Path):
    return _single(box, "a,b,c,d,e,f"), ["--grasp", "a,b,c,d,e,f"]


def case_point_off_surface(tmp_path: Path, box: Path):
    return _single(box, "0,0,0.07,0,0,-1"), ["--grasp", "surface"]


def case_negative_mass(tmp_path: Path, box: Path):
    args = _batch(box, tmp_path)
    args[args.index("--mass") : args.index("--mass") + 2] = ["--mass=-0.2"]
    return args, ["mass", "-0.2"]


def case_nan_mass(tmp_path: Path, box: Path):
    args = _batch(box, tmp_path)
    args[args.index("--mass") + 1] = "nan"
    return args, ["mass", "nan"]


def case_unknown_cup(tmp_path: Path, box: Path):
    return _batch(box, tmp_path, "--cup", "foo"), ["cup", "foo"]


def case_unknown_units(tmp_path: Path, box: Path):
    return _batch(box, tmp_path, "--units", "km"), ["units", "km"]


def case_both_grasp_and_grasps(tmp_path: Path, box: Path):
    return _batch(box, tmp_path, "--grasp", TOP_GRASP), ["--grasp", "--grasps"]


def case_neither_grasp_nor_grasps(tmp_path: Path, box: Path):
    return ["label", box, "--mass", MASS], ["--grasp", "--grasps"]


def case_zero_grasps(tmp_path: Path, box: Path):
    args = _batch(box, tmp_path)
    args[args.index("--grasps") + 1] = "0"
    return args, ["--grasps", "0"]


def case_unwritable_out(tmp_path: Path, box: Path):
    blocker = tmp_path / "file.txt"
    blocker.write_text("a regular file, not a folder")
    out = blocker / "x.npz"
    args = _batch(box, tmp_path)
    args[args.index("--out") + 1] = out
    return args, [str(out), ("cannot write", "not a directory", "exists")]


def case_bad_typer_option(tmp_path: Path, box: Path):
    args = _batch(box, tmp_path)
    args[args.index("--samples") + 1] = "abc"
    return args, ["--samples"]


BAD_INPUTS = [
    pytest.param(case_missing_file, id="missing-file"),
    pytest.param(case_unsupported_extension, id="txt-extension"),
    pytest.param(case_garbage_stl, id="garbage-stl"),
    pytest.param(case_empty_obj, id="empty-obj"),
    pytest.param(case_nan_vertex_obj, id="nan-vertex-obj"),
    pytest.param(case_flat_mesh, id="flat-mesh"),
    pytest.param(case_scale_2m, id="scale-2m"),
    pytest.param(case_scale_1mm, id="scale-1mm"),
    pytest.param(case_millimetre_obj_without_units, id="mm-file-no-units"),
    pytest.param(case_zero_approach, id="zero-approach"),
    pytest.param(case_non_unit_approach, id="non-unit-approach"),
    pytest.param(case_wrong_count, id="grasp-5-numbers"),
    pytest.param(case_non_numeric, id="grasp-non-numeric"),
    pytest.param(case_point_off_surface, id="grasp-5cm-off-surface"),
    pytest.param(case_negative_mass, id="negative-mass"),
    pytest.param(case_nan_mass, id="nan-mass"),
    pytest.param(case_unknown_cup, id="unknown-cup"),
    pytest.param(case_unknown_units, id="unknown-units"),
    pytest.param(case_both_grasp_and_grasps, id="grasp-and-grasps"),
    pytest.param(case_neither_grasp_nor_grasps, id="neither-grasp-nor-grasps"),
    pytest.param(case_zero_grasps, id="grasps-0"),
    pytest.param(case_unwritable_out, id="unwritable-out"),
    pytest.param(case_bad_typer_option, id="samples-abc-usage-error"),
]


@pytest.mark.parametrize("case", BAD_INPUTS)
def test_bad_input_exits_2(case: Case, tmp_path: Path, box: Path) -> None:
    args, needles = case(tmp_path, box)
    before = snapshot(tmp_path)
    result = invoke(*args)
    stderr = stderr_of(result)
    assert result.exit_code == 2, (result.exit_code, result.stdout, stderr)
    assert "Traceback" not in stderr and "internal" not in stderr.lower()
    for needle in needles:
        assert mentions(stderr, needle), f"stderr does not mention {needle!r}: {stderr!r}"
    assert snapshot(tmp_path) == before  # nothing written, no temp file left


@pytest.mark.parametrize("case", BAD_INPUTS)
def test_bad_input_json_reports_error(case: Case, tmp_path: Path, box: Path) -> None:
    args, needles = case(tmp_path, box)
    before = snapshot(tmp_path)
    result = invoke(*args, "--json")
    assert result.exit_code == 2, (result.exit_code, result.stdout, stderr_of(result))
    payload = last_json(result)
    assert payload["ok"] is False
    assert isinstance(payload["error"], str) and "\n" not in payload["error"]
    for needle in needles:
        assert mentions(payload["error"], needle), f"error does not mention {needle!r}: {payload['error']!r}"
    assert snapshot(tmp_path) == before


def test_bad_input_message_is_one_stderr_line(tmp_path: Path) -> None:
    missing = tmp_path / ("a" * 120 + ".stl")
    result = invoke("label", missing, "--grasps", "3")
    assert result.exit_code == 2
    lines = [line for line in stderr_of(result).splitlines() if line.strip()]
    assert len(lines) == 1, lines
    assert str(missing) in lines[0]


def test_short_bad_input_message_is_one_stderr_line(box: Path) -> None:
    result = invoke("label", box, "--grasps", "3", "--cup", "foo")
    assert result.exit_code == 2
    lines = [line for line in stderr_of(result).splitlines() if line.strip()]
    assert lines == ["error: cup preset 'foo' is unknown (known: default, paper)"]


def test_out_is_existing_directory_is_bad_input(tmp_path: Path, box: Path) -> None:
    folder = tmp_path / "labels.npz"
    folder.mkdir()
    result = invoke("label", box, "--grasps", "3", "--samples", "5", "--mass", MASS, "--out", folder, "--json")
    assert result.exit_code == 2, (result.exit_code, result.stdout)
    assert str(folder) in last_json(result)["error"]


# ----------------------------------------------------------------------------------------------
# absurd-scale boundaries that must pass


def test_one_metre_box_in_metres_is_ok(tmp_path: Path) -> None:
    big = write_box(tmp_path / "metre.stl", (1.0, 1.0, 1.0))
    result = invoke("label", big, "--grasp", "0,0,0.5,0,0,-1", "--units", "m", "--mass", MASS, "--json")
    assert result.exit_code == 0, stderr_of(result)
    assert last_json(result)["ok"] is True


def test_millimetre_file_with_units_mm_is_ok(tmp_path: Path) -> None:
    mm = write_box(tmp_path / "box_mm.stl", (40.0, 40.0, 40.0))
    result = invoke("label", mm, "--grasp", TOP_GRASP, "--units", "mm", "--mass", MASS, "--json")
    assert result.exit_code == 0, stderr_of(result)
    payload = last_json(result)
    assert payload["ok"] is True and payload["seal"] is True
    assert payload["contact_point"][2] == pytest.approx(0.02, abs=1e-6)  # metres, not mm


def test_millimetre_stl_without_units_is_read_in_millimetres(tmp_path: Path) -> None:
    # 40 units is no plausible size in metres and a plausible one in millimetres (AUTO_UNITS)
    mm = write_box(tmp_path / "box_mm.stl", (40.0, 40.0, 40.0))
    result = invoke("label", mm, "--grasp", TOP_GRASP, "--mass", MASS, "--json")
    assert result.exit_code == 0, stderr_of(result)
    assert last_json(result)["contact_point"][2] == pytest.approx(0.02, abs=1e-6)


# ----------------------------------------------------------------------------------------------
# 5. non-watertight mesh: labels, with a warning


def test_non_watertight_mesh_labels_with_warning(tmp_path: Path) -> None:
    mesh = trimesh.creation.box(extents=BOX_EXTENTS)
    mesh.update_faces(np.arange(len(mesh.faces)) != 0)  # face 0 lies on the x = -0.05 side
    assert not mesh.is_watertight
    path = tmp_path / "open_box.stl"
    mesh.export(path)
    result = invoke("label", path, "--grasp", TOP_GRASP, "--mass", MASS, "--json")
    assert result.exit_code == 0, stderr_of(result)
    payload = last_json(result)
    assert payload["ok"] is True
    assert any("not watertight" in w for w in payload["warnings"]), payload["warnings"]
    assert mentions(stderr_of(result), "not watertight")


# ----------------------------------------------------------------------------------------------
# 6. version


def test_version_json() -> None:
    result = invoke("version", "--json")
    assert result.exit_code == 0
    assert last_json(result) == {"ok": True, "version": suctionbench.__version__}


def test_version_plain() -> None:
    result = invoke("version")
    assert result.exit_code == 0
    assert result.stdout.strip() == suctionbench.__version__
