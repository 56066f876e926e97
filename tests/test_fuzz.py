"""The CLI contract under bad input (issue 14): every bad option value or malformed file exits 2
with one stderr line naming the input, no traceback, a strict JSON error line under --json, nothing
written, and nothing of the user's written over or deleted.

Two sources of bad input: Hypothesis draws values that break each numeric option's rule
(`suctionbench.validate.OPTION_RULES`) for every command, and `fuzz_corpus` builds malformed meshes,
camera and task TOMLs, datasets, models and run directories. Good inputs from the same corpus
must pass, so the checks cannot pass by refusing everything.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import typer
from fuzz_corpus import build_corpus, cases, classify, remove_new, tree
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from suctionbench.cli import app
from suctionbench.cli.common import emit, numeric_type
from suctionbench.validate import OPTION_RULES, Rule

runner = CliRunner()

HEAVY = {"pick", "bench agreement", "bench label", "bench plan", "bench episode", "bench generate",
         "objects generate", "objects build", "objects stats", "objects import"}
"""Commands whose corpus cases load the simulator or build objects: run under `slow` only."""

STUBS = {  # required arguments: parsing stops at the bad option before any of these is used
    "label": ["mesh.stl"], "pick": ["--object", "basic/box_tea"],
    "generate": ["--objects", "basic", "--datapoints", "1", "--out", "o"],
    "dataset show": ["d"], "train": ["--dataset", "d", "--out", "o"], "model show": ["m"],
    "model score": ["m", "--dataset", "d"],
    "eval": ["--policy", "centroid", "--set", "basic", "--out", "o"], "report": ["r", "--out", "o"],
    "objects show": ["basic/x"], "objects import": ["m.stl"], "plan": ["--depth", "d.npy"],
}


def strict_json(text: str) -> dict:
    """The last line of `text` parsed as strict JSON (NaN / Infinity refused, as JavaScript does)."""
    def refuse(constant: str):
        raise ValueError(f"non-standard JSON constant {constant}")

    return json.loads(text.strip().splitlines()[-1], parse_constant=refuse)


def numeric_options() -> list[tuple[str, str, type]]:
    """(command path, option flag, int or float) for every numeric option of every command."""
    found = []

    def walk(command, path: list[str]) -> None:
        for param in command.params:
            kind = numeric_type(param)
            if kind is not None and param.opts and param.opts[0].startswith("--"):
                found.append((" ".join(path), param.opts[0], kind))
        for name, sub in sorted(getattr(command, "commands", {}).items()):
            walk(sub, [*path, name])

    walk(typer.main.get_command(app), [])
    return found


OPTIONS = numeric_options()


def test_every_numeric_option_has_a_rule():
    """A new numeric option must say what its valid values are (suctionbench/validate.py OPTION_RULES)."""
    assert len(OPTIONS) > 30
    missing = sorted({flag for _, flag, _ in OPTIONS if flag[2:].replace("-", "_") not in OPTION_RULES})
    assert not missing, f"add a Rule to suctionbench.validate.OPTION_RULES for {missing}"


def bad_values(rule: Rule, kind: type) -> st.SearchStrategy[str]:
    """Command-line strings that break `rule` for an option of type `kind`."""
    options = [st.sampled_from(["abc", "", "1,2", "--", "0x10"] + (["nan", "inf", "-inf"] if kind is float else
                                                                      ["1.5", "1e3"]))]
    if rule.low is not None:
        below = st.integers(max_value=math.ceil(rule.low) - 1) if kind is int else \
            st.floats(max_value=rule.low, exclude_max=not rule.low_open, allow_nan=False, allow_infinity=False)
        options.append(below.map(str))
    if rule.high is not None:
        above = st.integers(min_value=math.floor(rule.high) + 1) if kind is int else \
            st.floats(min_value=rule.high, exclude_min=True, allow_nan=False, allow_infinity=False)
        options.append(above.map(str))
    return st.one_of(*options)


def option_and_bad_value() -> st.SearchStrategy[tuple[str, str, str]]:
    def pick(option: tuple[str, str, type]) -> st.SearchStrategy[tuple[str, str, str]]:
        command, flag, kind = option
        rule = OPTION_RULES.get(flag[2:].replace("-", "_"), Rule())
        return bad_values(rule, kind).map(lambda value: (command, flag, value))

    return st.sampled_from(OPTIONS).flatmap(pick)


def assert_clean_exit_2(result, *, as_json: bool, needle: str | None = None) -> str:
    stderr = result.stderr
    assert result.exit_code == 2, (result.exit_code, result.stdout[-500:], stderr[-2000:])
    assert "Traceback" not in stderr
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1, lines
    if needle is not None:
        assert needle in lines[0], lines[0]
    if as_json:
        reply = strict_json(result.stdout)
        assert reply["ok"] is False and reply["error"]
    return lines[0]


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(option_and_bad_value(), st.booleans())
def test_bad_numeric_option_exits_2_with_one_line(case, as_json):
    command, flag, value = case
    argv = [*command.split(), *STUBS.get(command, []), f"{flag}={value}", *(["--json"] if as_json else [])]
    result = runner.invoke(app, argv)
    assert_clean_exit_2(result, as_json=as_json, needle=flag)


@pytest.mark.slow
@settings(max_examples=600, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(option_and_bad_value(), st.booleans())
def test_bad_numeric_option_exits_2_many(case, as_json):
    test_bad_numeric_option_exits_2_with_one_line.hypothesis.inner_test(case, as_json)


@pytest.mark.parametrize("argv", [
    ["label", "no-such-mesh.stl", "--grasps", "1", "--seed", "0", "--top", "0", "--mass", "0.001"],
    ["label", "no-such-mesh.stl", "--grasps", "1", "--seed", "4294967295", "--samples", "1"],
    ["eval", "--policy", "centroid", "--set", "nope", "--workers", "0", "--trials", "1", "--out", "o"],
])
def test_rules_accept_their_bounds(argv):
    """The rules do not refuse valid values: bounds themselves pass parsing, and the command fails
    later, on the missing mesh or unknown set."""
    result = runner.invoke(app, argv)
    assert result.exit_code == 2 and ("no-such-mesh" in result.stderr or "'nope'" in result.stderr), result.stderr


def test_usage_errors_are_one_line():
    for argv in (["label", "m.stl", "--bogus"], ["nope"], ["eval", "--policy"], ["label", "m.stl", "--grasps", "x"]):
        for as_json in (False, True):
            assert_clean_exit_2(runner.invoke(app, argv + (["--json"] if as_json else [])), as_json=as_json)


def test_messages_are_plain_text_not_markup():
    """'[ray]' in a message is printed as written (rich would read it as a style tag and drop it)."""
    result = runner.invoke(app, ["eval", "--policy", "centroid", "--set", "[ray]", "--out", "o"])
    assert "[ray]" in assert_clean_exit_2(result, as_json=False)


MARKUP = "[red]x[/]"
"""A user string that rich would read as markup: a style, and a closing tag ('[/]' alone is a
MarkupError: nothing to close)."""


def test_tables_print_user_strings_literally(capsys):
    """Titles, headers and cells of the human tables hold names, paths and policies as written."""
    from suctionbench.cli.common import print_kv, print_rows

    print_rows(f"objects in {MARKUP}", [{"key": f"user/{MARKUP}", "[bold]policy": "[/]", "path": "a[/]b"}])
    print_kv(f"pick {MARKUP}", {"policy": MARKUP, "[/]": "[bold]"})
    out = capsys.readouterr().out
    for text in (f"objects in {MARKUP}", f"user/{MARKUP}", "[bold]policy", "a[/]b", f"pick {MARKUP}", "[bold]"):
        assert text in out, text


def test_label_prints_a_mesh_path_with_brackets_literally(tmp_path):
    import trimesh

    folder = tmp_path / "a[" / "]b[red]"  # the path reads '.../a[/]b[red]/box.stl'
    folder.mkdir(parents=True)
    mesh = folder / "box.stl"
    trimesh.creation.box(extents=(0.06, 0.04, 0.02)).export(mesh)
    result = runner.invoke(app, ["label", str(mesh), "--grasps", "4", "--samples", "2", "--top", "2",
                                 "--mass", "0.1"])
    assert result.exit_code == 0, result.stderr[-2000:]
    assert f"labelsfor{mesh}" in "".join(result.stdout.split())  # the title wraps to the table's width


def test_json_output_is_strict(capsys):
    emit({"q": float("-inf"), "a": np.float32("nan"), "v": np.array([1.0, np.inf]), "n": {"x": (float("nan"),)}},
         True)
    reply = strict_json(capsys.readouterr().out)
    assert reply == {"q": None, "a": None, "v": [1.0, None], "n": {"x": [None]}}


# -- the corpus ------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    return build_corpus(tmp_path_factory.mktemp("fuzz") / "corpus")


def _case_params():
    """One pytest param per corpus case; paths are resolved against the real corpus in the test."""
    import tempfile

    root = Path(tempfile.gettempdir()) / "suctionbench-fuzz-ids"
    placeholder = {name: root / name for name in CORPUS_NAMES}
    placeholder["root"] = root
    params = []
    for i, case in enumerate(cases(placeholder)):
        marks = [pytest.mark.slow] if case.command in HEAVY else []
        params.append(pytest.param(i, id=f"{i:03d}-{case.command.replace(' ', '-')}", marks=marks))
    return params


CORPUS_NAMES = [
    "box", "mesh_empty.obj", "mesh_garbage.stl", "mesh_truncated.obj", "mesh_words.ply", "file.txt", "a_dir",
    "cam_huge.toml", "cam_1px.toml", "cam_tiny_f.toml", "cam_far.toml", "cam_nan.toml", "cam_types.toml",
    "cam_binary.toml", "task_types.toml", "task_binary.toml", "task_zero.toml", "task_negseed.toml",
    "task_poses.toml", "task_metrics.toml", "task_placement.toml", "task_unknown_key.toml", "task_huge.toml",
    "task_set.toml", "ds_good", "ds_no_shard", "ds_truncated", "ds_no_manifest", "ds_bad_manifest", "ds_no_tensors",
    "ds_empty_card", "ds_bad_card", "ds_no_card", "ds_no_splits", "ds_nan", "model_good", "model_nan",
    "model_truncated", "model_bad_card", "model_no_weights", "model_empty", "run_good", "run_killed", "run_killed0",
    "run_extra", "run_truncated_json", "run_list_json", "run_empty_json", "run_no_trials", "run_bad_log",
    "depth_flat.npy", "depth_nan.npy", "depth_rgb.npy", "depth_pickle.npy", "depth_mm_float.npy", "mask_small.npy",
    "pose_3x3.npy", "pose_nan.npy", "garbage.npy", "user_model", "user_objects",
]


def test_corpus_names_are_complete(corpus):
    assert set(corpus) == {*CORPUS_NAMES, "root"}


@pytest.mark.parametrize("index", _case_params())
@pytest.mark.parametrize("as_json", [False, True], ids=["plain", "json"])
def test_corpus_case_exits_2_and_keeps_files(corpus, index, as_json):
    case = cases(corpus)[index]
    if case.setup:
        case.setup()
    before, files = [p.read_bytes() for p in case.keep], tree(corpus["root"])
    result = runner.invoke(app, case.argv + (["--json"] if as_json else []))
    changed = [p.read_bytes() if p.is_file() else None for p in case.keep] != before
    written = remove_new(corpus["root"], files)  # a refused command writes nothing
    outcome = classify(result.exit_code, result.stdout, result.stderr, as_json, changed or bool(written))
    assert outcome == "clean", (outcome, result.exit_code, case.name, written[:3], result.stderr[-1500:])


@pytest.mark.parametrize("argv", [
    ["dataset", "show", "{ds_good}"],
    ["model", "show", "{model_good}"],
    ["report", "{run_good}", "--out", "{root}/report_good"],
    ["report", "{run_killed}", "--out", "{root}/report_killed", "--allow-incomplete"],
])
def test_good_corpus_inputs_pass(corpus, argv):
    """Positive controls: the checks that refuse the damaged copies accept the originals."""
    result = runner.invoke(app, [a.format(**corpus) for a in argv] + ["--json"])
    assert result.exit_code == 0, result.stderr[-1500:]
    reply = strict_json(result.stdout)
    assert reply["ok"] is True
    if "--allow-incomplete" in argv:
        assert reply["incomplete"][0]["found_trials"] == 1 and "incomplete 1/3" in reply["rows"][0]["policy"]
    elif argv[0] == "report":
        assert reply["incomplete"] == [] and reply["rows"][0]["trials"] == 3


def test_overwrite_replaces_only_a_dataset(corpus, tmp_path):
    import shutil

    from suctionbench.dataset.verify import remove_dataset

    mine = tmp_path / "mine"
    shutil.copytree(corpus["ds_good"], mine)
    remove_dataset(mine)
    assert not any(mine.iterdir())
    theirs = tmp_path / "theirs"
    shutil.copytree(corpus["ds_good"], theirs)
    (theirs / "splits" / "notes.txt").write_text("mine")
    with pytest.raises(Exception, match="notes.txt"):
        remove_dataset(theirs)
    assert (theirs / "splits" / "notes.txt").is_file() and (theirs / "config.json").is_file()


def test_train_never_replaces_files_it_did_not_write(corpus, tmp_path):
    """A model card of someone else's in --out: train refuses, with or without --overwrite, and the
    file is unchanged; a run of its own in the same place is resumed or replaced as before."""
    theirs = tmp_path / "theirs"
    theirs.mkdir()
    (theirs / "model.json").write_text('{"my": "card"}')
    (theirs / "precision_recall.png").write_bytes(b"my plot")
    base = ["train", "--dataset", str(corpus["ds_good"]), "--arch", "compact", "--epochs", "1", "--json"]
    for extra in ([], ["--overwrite"]):
        result = runner.invoke(app, [*base, "--out", str(theirs), *extra])
        line = assert_clean_exit_2(result, as_json=True, needle="'model.json', which suctionbench did not write")
        assert str(theirs) in line
    assert (theirs / "model.json").read_text() == '{"my": "card"}'
    (theirs / "model.json").unlink()
    assert_clean_exit_2(runner.invoke(app, [*base, "--out", str(theirs)]), as_json=True,
                        needle="'precision_recall.png', which suctionbench did not write")
    ours = tmp_path / "ours"
    assert runner.invoke(app, [*base, "--out", str(ours)]).exit_code == 0
    again = runner.invoke(app, [*base, "--out", str(ours), "--overwrite", "--seed", "1"])
    assert again.exit_code == 0, again.stderr[-1500:]


def test_train_refuses_sizes_the_machine_cannot_hold(corpus, tmp_path, monkeypatch):
    """The batch's memory and the checkpoints' disk are estimated before training."""
    base = ["train", "--dataset", str(corpus["ds_good"]), "--arch", "dn3", "--epochs", "1", "--out",
            str(tmp_path / "m"), "--json"]
    monkeypatch.setattr("suctionbench.validate.available_memory", lambda: 50 * 2**20)
    assert_clean_exit_2(runner.invoke(app, base), as_json=True, needle="--batch-size 64 (--arch dn3): needs about")
    monkeypatch.setattr("shutil.disk_usage", lambda _p: shutil_usage(total=2**30, used=2**30 - 2**20, free=2**20))
    monkeypatch.setattr("suctionbench.validate.available_memory", lambda: 2**40)
    assert_clean_exit_2(runner.invoke(app, base), as_json=True, needle="--arch dn3 checkpoints: needs about")
    assert not (tmp_path / "m").exists()


def shutil_usage(**kw):
    import shutil

    return shutil._ntuple_diskusage(kw["total"], kw["used"], kw["free"])


def test_a_nan_training_checkpoint_is_refused(tmp_path):
    import torch

    from suctionbench.errors import InputError
    from suctionbench.learning.checkpoint import STATE_FORMAT, load_train_state, save_train_state

    save_train_state(tmp_path, {"model": {"w": torch.tensor([1.0, float("nan")])}})
    with pytest.raises(InputError, match="train_state.pt'.*NaN or infinite"):
        load_train_state(tmp_path)
    save_train_state(tmp_path, {"model": {"w": torch.tensor([1.0, 2.0])}})
    assert load_train_state(tmp_path)["format"] == STATE_FORMAT


def test_objects_never_replace_a_directory_holding_user_files(corpus, tmp_path):
    """objects build --out and objects import --overwrite replace object directories: one holding a
    file suctionbench did not write (or no object at all) is refused before any work, untouched."""
    from suctionbench.objects.ownership import foreign_object_entry
    from suctionbench.objects.registry import assets_root, eval_specs

    root = corpus["user_objects"]
    result = runner.invoke(app, ["objects", "build", "--set", "basic", "--out", str(root), "--json"])
    assert_clean_exit_2(result, as_json=True, needle="basic/box_tea': holds no object.toml of suctionbench")
    result = runner.invoke(app, ["objects", "import", str(corpus["box"]), "--root", str(root), "--overwrite", "--json"])
    assert_clean_exit_2(result, as_json=True, needle="custom/box': holds no object.toml of suctionbench")
    assert (root / "basic" / "box_tea" / "notes.txt").is_file() and (root / "custom" / "box" / "notes.txt").is_file()
    mine = tmp_path / "objects"  # an object suctionbench imported, then a note of the user's put into it
    imported = ["objects", "import", str(corpus["box"]), "--root", str(mine), "--json"]
    assert runner.invoke(app, imported).exit_code == 0
    (mine / "custom" / "box" / "notes.txt").write_text("mine")
    result = runner.invoke(app, [*imported, "--overwrite"])
    assert_clean_exit_2(result, as_json=True, needle="custom/box': holds 'notes.txt', which suctionbench did not write")
    (mine / "custom" / "box" / "notes.txt").unlink()
    assert runner.invoke(app, [*imported, "--overwrite"]).exit_code == 0  # its own object: replaced
    # positive controls: every shipped object is one suctionbench wrote (objects build may replace it),
    # also once its record is of another version (a field gone, one added: a rebuild after the format changed)
    assert [s.name for g in eval_specs().values() for s in g if foreign_object_entry(assets_root() / s.set / s.name)] \
        == []
    import shutil
    import tomllib

    import tomli_w

    old = tmp_path / "old" / "box_tea"
    shutil.copytree(assets_root() / "basic" / "box_tea", old)
    record = tomllib.loads((old / "object.toml").read_text())
    record.pop("mass_model", None)
    (old / "object.toml").write_text(tomli_w.dumps({**record, "retired_field": 1}))
    assert foreign_object_entry(old) is None


def _user_folder(path: Path) -> Path:
    path.mkdir(parents=True)
    (path / "notes.txt").write_text("my notes\n")
    return path


def test_build_object_never_replaces_a_folder_holding_user_files(tmp_path, monkeypatch):
    """The objects layer itself refuses (not only the CLI): build_object, the function every object
    build, import and corpus generation ends in, refuses a folder holding a file it did not write
    before any work, and again if such a file appears while it works; the folder is untouched and
    no temporary is left beside it. An empty folder, or one of its own objects, it replaces."""
    import trimesh

    from suctionbench.errors import InputError
    from suctionbench.objects import build
    from suctionbench.objects.spec import ObjectSpec

    box = trimesh.creation.box(extents=(0.06, 0.04, 0.02))
    spec = ObjectSpec(name="box", set="custom", generator="import", density=500.0)
    target = _user_folder(tmp_path / "custom" / "box")
    with pytest.raises(InputError, match=f"object directory '{target}': holds no object.toml of suctionbench"):
        build.build_object(box, spec, target, decompose=False)
    assert sorted(p.name for p in target.iterdir()) == ["notes.txt"]
    assert sorted(p.name for p in target.parent.iterdir()) == ["box"]
    (target / "notes.txt").unlink()  # empty: nothing to lose
    build.build_object(box, spec, target, decompose=False)
    assert sorted(p.name for p in target.iterdir()) == ["mesh.stl", "object.toml"]
    real = build.stable_poses

    def user_writes_meanwhile(*args):  # a file of the user's appears while the object is built
        (target / "notes.txt").write_text("written while the build ran\n")
        return real(*args)

    monkeypatch.setattr(build, "stable_poses", user_writes_meanwhile)
    with pytest.raises(InputError, match=f"'{target}': holds 'notes.txt', which suctionbench did not write"):
        build.build_object(box, spec, target, decompose=False)
    assert sorted(p.name for p in target.iterdir()) == ["mesh.stl", "notes.txt", "object.toml"]
    assert sorted(p.name for p in target.parent.iterdir()) == ["box"]


def test_objects_generate_never_replaces_a_corpus_folder_holding_user_files(tmp_path):
    """objects generate rebuilds out/train/NAME where no cached object of its spec is there: a user's
    folder of that name is refused before anything is built, and kept."""
    from suctionbench.objects.corpus import corpus_specs

    spec = corpus_specs(2, 0)[1]
    folder = _user_folder(tmp_path / "corpus" / spec.set / spec.name)
    result = runner.invoke(app, ["objects", "generate", "--count", "2", "--workers", "1", "--out",
                                 str(tmp_path / "corpus"), "--json"])
    assert_clean_exit_2(result, as_json=True, needle=f"object directory '{folder}': holds no object.toml")
    written = sorted(str(p.relative_to(tmp_path / "corpus")) for p in tree(tmp_path / "corpus"))
    assert written == [spec.set, f"{spec.set}/{spec.name}", f"{spec.set}/{spec.name}/notes.txt"], written


def test_dataset_show_thumbnails_of_a_small_dataset(tmp_path):
    """Fewer than 16 datapoints: the sheet shows them all (it sampled 16 without replacement)."""
    from fuzz_corpus import write_dataset

    dataset = write_dataset(tmp_path / "ds", n=5, per_shard=5)
    result = runner.invoke(app, ["dataset", "show", str(dataset), "--thumbnails", str(tmp_path / "t.png"), "--json"])
    assert result.exit_code == 0, result.stderr[-1500:]
    assert (tmp_path / "t.png").stat().st_size > 0


def test_library_warnings_do_not_break_the_one_line(capsys):
    """A library's warning during a refused command is held back (one error line); during a success
    it is printed after the work, once."""
    import warnings

    from suctionbench.cli.common import run_command
    from suctionbench.errors import InputError

    def refused():
        warnings.warn("invalid value encountered in cast", RuntimeWarning, stacklevel=1)
        raise InputError("mesh 'm.stl': degenerate")

    def succeeds():
        for _ in range(3):
            warnings.warn("invalid value encountered in cast", RuntimeWarning, stacklevel=1)
        return {"done": 1}

    with pytest.raises(typer.Exit):
        run_command(False, refused)
    assert capsys.readouterr().err.strip().splitlines() == ["error: mesh 'm.stl': degenerate"]
    run_command(True, succeeds)
    captured = capsys.readouterr()
    assert strict_json(captured.out) == {"ok": True, "done": 1}
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("warning: RuntimeWarning: invalid value encountered in cast")


TORCH_ALLOCATION_FAILURE = ("[enforce fail at alloc_cpu.cpp:127] DefaultCPUAllocator: can't allocate memory: you "
                            "tried to allocate 3435921408 bytes. Error code 12 (Cannot allocate memory)")


@pytest.mark.parametrize("error", [MemoryError(), RuntimeError(TORCH_ALLOCATION_FAILURE)])
def test_out_of_memory_names_the_sizes(error, box_mesh_path, monkeypatch):
    """Memory exhausted despite the estimates (numpy's MemoryError, torch's failed allocation): exit 2,
    one line naming the command's size options and their values."""
    def exhausted(*_a, **_k):
        raise error

    monkeypatch.setattr("suctionbench.geometry.sampling.sample_surface_grasps", exhausted)
    result = runner.invoke(app, ["label", str(box_mesh_path), "--grasps", "7", "--mass", "0.1", "--json"])
    assert_clean_exit_2(result, as_json=True, needle="out of memory with --grasps 7 --samples 50")


@pytest.fixture
def box_mesh_path(tmp_path):
    import trimesh

    path = tmp_path / "box.stl"
    trimesh.creation.box(extents=(0.06, 0.04, 0.02)).export(path)
    return path


def test_generate_resume_needs_only_the_disk_it_has_not_written(tmp_path, monkeypatch):
    """A resumed run keeps (or rewrites in place) what --out holds, so its disk estimate counts only
    the rest: with no free disk at all a fresh run is refused and a finished one still resumes."""
    base = ["generate", "--objects", "basic", "--datapoints", "4", "--grasps-per-object", "20", "--workers", "1",
            "--json"]
    done = tmp_path / "done"
    first = runner.invoke(app, [*base, "--out", str(done)])
    assert first.exit_code == 0, first.stderr[-1500:]
    monkeypatch.setattr("shutil.disk_usage", lambda _p: shutil_usage(total=2**30, used=2**30, free=0))
    assert_clean_exit_2(runner.invoke(app, [*base, "--out", str(tmp_path / "fresh")]), as_json=True,
                        needle="--datapoints 4: needs about")
    assert not (tmp_path / "fresh").exists()
    again = runner.invoke(app, [*base, "--out", str(done), "--resume"])
    assert again.exit_code == 0, again.stderr[-1500:]
