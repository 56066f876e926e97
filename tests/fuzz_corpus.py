"""Bad inputs for every command: a corpus of malformed files, datasets, models and run directories,
built here from the library's own writers, and the command lines that feed them to the CLI.

`tests/test_fuzz.py` runs them in-process; run this file as a script for the fuzz table (each case
in a forked child under a time and memory limit, with and without --json):

    .venv/bin/python tests/fuzz_corpus.py [--timeout 20] [--only label,pick] [--cases]

Outcomes: ``clean`` exit 2, no traceback, one stderr line (and under --json a strict JSON last
line with ok false); ``messy`` exit 2 but several stderr lines or a bad JSON line; ``crash`` any
other non-zero exit or a traceback; ``wrong`` exit 0, a run past the time limit, a case whose
files were changed (data loss), or a refused case that wrote anything under the corpus directory.
"""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

N_DATA = 96
"""Datapoints of the corpus dataset (3 shards of 32)."""


@dataclass
class Case:
    """One bad command line: `argv` without --json; `keep` lists files the command must leave unchanged."""

    command: str
    argv: list[str]
    keep: list[Path] = field(default_factory=list)
    setup: Callable[[], None] | None = None

    @property
    def name(self) -> str:
        return " ".join(self.argv)


# -- corpus ----------------------------------------------------------------------------------------


def write_dataset(directory: Path, n: int = N_DATA, per_shard: int = 32, *, nan_labels: bool = False) -> Path:
    """A small, valid dataset written with the library's writer (optionally NaN labels, hashes updated)."""
    from suctionbench.dataset.storage import (
        FIELDS,
        DatasetWriter,
        _npz_bytes,  # noqa: PLC2701 (byte-exact rewrite below)
        manifest_name,
        shard_file_name,
        write_splits,
    )

    rng = np.random.default_rng(0)
    metric = rng.uniform(0, 1, n).astype(np.float32)
    writer = DatasetWriter(directory, per_shard)
    for start in range(0, n, per_shard):
        k = min(per_shard, n - start)
        writer.write_shard(start // per_shard, {
            "depth_ims_tf_table": rng.uniform(0.55, 0.6, (k, 32, 32, 1)).astype(np.float32),
            "context_ims_tf_table": rng.uniform(0.55, 0.6, (k, 32, 32, 1)).astype(np.float32),
            "object_context": rng.uniform(0.0, 0.1, (k, 6)).astype(np.float32),
            "hand_poses": np.column_stack([rng.uniform(0, 300, (k, 2)), rng.uniform(0.5, 0.6, k),
                                           rng.uniform(0, 0.6, k), np.zeros((k, 2)), np.ones(k)]).astype(np.float32),
            "robust_suction_wrench_resistance": metric[start:start + k],
            "object_labels": (np.arange(start, start + k) // 16).astype(np.int32),
            "pose_labels": np.zeros(k, np.int32), "image_labels": np.arange(start, start + k, dtype=np.int32),
            "grasp_labels": np.zeros(k, np.int32), "seal_flags": np.ones(k, np.uint8),
            "wrench_resistance": (metric[start:start + k] > 0.2).astype(np.uint8),
        })
    writer.write_card({"config": {"label_threshold": 0.2, "label": {"cup": {"name": "default"}}},
                       "camera": {"name": "primesense"}, "objects": [f"o{i}" for i in range(n // 16)],
                       "fingerprint": "fuzz", "datapoints": n, "shards": -(-n // per_shard), "status": "complete",
                       "positive_rate": float((metric > 0.2).mean())})
    write_splits(directory, np.arange(n), np.arange(n) // 16, seed=0)
    if nan_labels:  # labels of shard 0 become NaN, its manifest updated: hashes alone cannot tell
        name = shard_file_name("robust_suction_wrench_resistance", 0)
        data = _npz_bytes(np.full(per_shard, np.nan, np.float32))
        (directory / "tensors" / name).write_bytes(data)
        manifest_path = directory / "tensors" / manifest_name(0)
        manifest = json.loads(manifest_path.read_text())
        import hashlib

        manifest["files"][name] = {"sha256": hashlib.sha256(data).hexdigest(), "bytes": len(data)}
        manifest_path.write_text(json.dumps(manifest))
    assert set(FIELDS)
    return directory


def write_model(directory: Path, *, nan_weights: bool = False) -> Path:
    """A compact GQ-CNN with seeded weights; `nan_weights`: then one weight set to NaN in the file and the
    card's sha256 updated to match (a hash check alone cannot tell)."""
    import torch
    from safetensors.torch import load_file, save_file

    from suctionbench.io import file_digest
    from suctionbench.learning.checkpoint import CARD_NAME, WEIGHTS_NAME, GQCNNModel, save_model
    from suctionbench.learning.data import NormStats
    from suctionbench.learning.models import build_model

    network = build_model("compact", torch.Generator().manual_seed(0))
    stats = NormStats(0.58, 0.01, (0.58, 0.3), (0.01, 0.2), count=10)
    save_model(directory, GQCNNModel(network, stats, {"arch": "compact"}))
    if nan_weights:
        weights = directory / WEIGHTS_NAME
        tensors = load_file(str(weights))
        first = next(iter(tensors))
        tensors[first].view(-1)[0] = float("nan")
        save_file(tensors, str(weights))
        card = json.loads((directory / CARD_NAME).read_text())
        card["weights_sha256"] = file_digest(weights)[0]
        (directory / CARD_NAME).write_text(json.dumps(card))
    return directory


def write_run(directory: Path, trials: int = 3, done: int | None = None, *, part: bool = False,
              extra: bool = False) -> Path:
    """A run directory as `eval` writes it: run.json for `trials`, `done` finished logs, optionally a
    `.part` log of a killed writer and a stray extra trial log."""
    from suctionbench.runlog.writer import EpisodeLog

    done = trials if done is None else done
    (directory / "trials").mkdir(parents=True)
    task = {"name": "smoke", "set": "basic", "trials": trials, "placement": "drop", "seed": 0, "stable_poses": 1,
            "metrics": [], "description": ""}
    (directory / "run.json").write_text(json.dumps({
        "task": task, "policy": "centroid", "policy_spec": "centroid", "model": None, "metric": "rwr",
        "cup": "default", "camera": "primesense", "trials": trials, "seed": 0}))
    indices = list(range(done)) + ([trials + 5] if extra else [])
    for i in indices:
        record = {"object": "basic/box_tea", "valid": True, "success": True, "failure": None, "policy_q": 0.8,
                  "label_rwr": 0.9, "sim_time": 4.0, "plan_time": 0.1, "sensing_time": 0.0, "trial": i}
        with EpisodeLog(directory / "trials" / f"trial_{i:05d}.mcap", {"policy": "centroid"}) as log:
            log.log_result(1.0, record)
    if part:
        (directory / "trials" / f".trial_{done:05d}.mcap.1234abcd.part").write_bytes(b"\x89MCAP0\r\n partial")
    return directory


def build_corpus(root: Path) -> dict[str, Path]:
    """Every malformed input the cases refer to, under `root`."""
    import trimesh

    root.mkdir(parents=True, exist_ok=True)
    p: dict[str, Path] = {"root": root}

    def text(name: str, content: str | bytes) -> Path:
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
        p[name] = path
        return path

    box = trimesh.creation.box(extents=(0.06, 0.04, 0.02))
    p["box"] = root / "box.stl"
    box.export(p["box"])
    obj = box.export(file_type="obj")
    text("mesh_empty.obj", "")
    text("mesh_garbage.stl", bytes(range(256)) * 8)
    text("mesh_truncated.obj", obj[: len(obj) // 3].rsplit("\n", 1)[0] + "\nf 1 2 999\n")
    text("mesh_words.ply", "this is not a mesh\n")
    text("file.txt", "a plain file\n")
    (root / "a_dir").mkdir(exist_ok=True)
    p["a_dir"] = root / "a_dir"

    cam = "name = 'c'\nwidth = {w}\nheight = {h}\nfx = {fx}\nfy = {fx}\ncx = {cx}\ncy = {cy}\n" \
          "min_depth = 0.2\nmax_depth = {maxd}\n"
    text("cam_huge.toml", cam.format(w=20000, h=20000, fx=500.0, cx=10000.0, cy=10000.0, maxd=2.0))
    text("cam_1px.toml", cam.format(w=1, h=1, fx=500.0, cx=0.5, cy=0.5, maxd=2.0))
    text("cam_tiny_f.toml", cam.format(w=640, h=480, fx=1e-9, cx=320.0, cy=240.0, maxd=2.0))
    text("cam_far.toml", cam.format(w=640, h=480, fx=500.0, cx=320.0, cy=240.0, maxd=1e9))
    text("cam_nan.toml", cam.format(w=640, h=480, fx="nan", cx=320.0, cy=240.0, maxd=2.0))
    text("cam_types.toml", cam.format(w="'wide'", h=480, fx=500.0, cx=320.0, cy=240.0, maxd=2.0))
    text("cam_binary.toml", b"\x00\xff\xfe" * 50)

    task = "set = 'basic'\ntrials = {trials}\nplacement = '{placement}'\nseed = {seed}\n{extra}"
    text("task_types.toml", task.format(trials="'many'", placement="drop", seed=0, extra=""))
    text("task_binary.toml", b"\x00\x01\x02\xff" * 40)
    text("task_zero.toml", task.format(trials=0, placement="drop", seed=0, extra=""))
    text("task_negseed.toml", task.format(trials=2, placement="drop", seed=-3, extra=""))
    text("task_poses.toml", task.format(trials=2, placement="stable", seed=0, extra="stable_poses = 0\n"))
    text("task_metrics.toml", task.format(trials=2, placement="drop", seed=0, extra="metrics = 'rwr'\n"))
    text("task_placement.toml", task.format(trials=2, placement="hover", seed=0, extra=""))
    text("task_unknown_key.toml", task.format(trials=2, placement="drop", seed=0, extra="colour = 'red'\n"))
    text("task_huge.toml", task.format(trials=10**8, placement="drop", seed=0, extra=""))
    text("task_set.toml", "set = 3\ntrials = 2\n")

    # datasets: one valid, then each damaged in one way
    good = write_dataset(root / "ds_good")
    p["ds_good"] = good
    for name in ("ds_no_shard", "ds_truncated", "ds_no_manifest", "ds_bad_manifest", "ds_no_tensors",
                 "ds_empty_card", "ds_bad_card", "ds_no_card", "ds_no_splits"):
        shutil.copytree(good, root / name)
        p[name] = root / name
    (p["ds_no_shard"] / "tensors" / "hand_poses_00001.npz").unlink()
    victim = p["ds_truncated"] / "tensors" / "depth_ims_tf_table_00002.npz"
    victim.write_bytes(victim.read_bytes()[:100])
    (p["ds_no_manifest"] / "tensors" / "shard_00001.json").unlink()
    (p["ds_bad_manifest"] / "tensors" / "shard_00000.json").write_text("{garbled")
    shutil.rmtree(p["ds_no_tensors"] / "tensors")
    (p["ds_empty_card"] / "config.json").write_text("{}")
    (p["ds_bad_card"] / "config.json").write_text("[1, 2")
    (p["ds_no_card"] / "config.json").unlink()
    shutil.rmtree(p["ds_no_splits"] / "splits")
    p["ds_nan"] = write_dataset(root / "ds_nan", nan_labels=True)

    # models
    p["model_good"] = write_model(root / "model_good")
    p["model_nan"] = write_model(root / "model_nan", nan_weights=True)
    for name in ("model_truncated", "model_bad_card", "model_no_weights"):
        shutil.copytree(p["model_good"], root / name)
        p[name] = root / name
    w = p["model_truncated"] / "model.safetensors"
    w.write_bytes(w.read_bytes()[:500])
    (p["model_bad_card"] / "model.json").write_text('{"format": 1')
    (p["model_no_weights"] / "model.safetensors").unlink()
    (root / "model_empty").mkdir()
    p["model_empty"] = root / "model_empty"

    # runs
    p["run_good"] = write_run(root / "run_good")
    p["run_killed"] = write_run(root / "run_killed", done=1, part=True)
    p["run_killed0"] = write_run(root / "run_killed0", done=0, part=True)
    p["run_extra"] = write_run(root / "run_extra", extra=True)
    for name, content in (("run_truncated_json", '{"task": {"name": "smoke", "se'), ("run_list_json", "[]"),
                          ("run_empty_json", "{}")):
        shutil.copytree(p["run_good"], root / name)
        (root / name / "run.json").write_text(content)
        p[name] = root / name
    p["run_no_trials"] = write_run(root / "run_no_trials")
    shutil.rmtree(p["run_no_trials"] / "trials")
    p["run_bad_log"] = write_run(root / "run_bad_log")
    log = p["run_bad_log"] / "trials" / "trial_00001.mcap"
    log.write_bytes(log.read_bytes()[:-40])

    # depth images, masks and camera poses (plan)
    def array(name: str, value: np.ndarray, **kw) -> None:
        p[name] = root / name
        np.save(p[name], value, **kw)

    array("depth_flat.npy", np.full((480, 640), 0.6, np.float32))
    array("depth_nan.npy", np.full((480, 640), np.nan, np.float32))
    array("depth_rgb.npy", np.full((8, 8, 3), 0.6, np.float32))
    array("depth_pickle.npy", np.array([{"a": 1}], dtype=object), allow_pickle=True)
    array("depth_mm_float.npy", np.full((480, 640), 600.0, np.float32))
    array("mask_small.npy", np.ones((10, 10), bool))
    array("pose_3x3.npy", np.eye(3))
    array("pose_nan.npy", np.full((4, 4), np.nan))
    text("garbage.npy", b"\x93NUMPY garbage" * 10)

    # directories holding a user's files where a command writes: nothing of theirs may go
    (root / "user_model").mkdir()
    p["user_model"] = root / "user_model"
    (p["user_model"] / "model.json").write_text('{"my": "own model card"}\n')
    p["user_objects"] = root / "user_objects_root"
    (p["user_objects"] / "basic" / "box_tea").mkdir(parents=True)
    (p["user_objects"] / "basic" / "box_tea" / "notes.txt").write_text("my notes\n")
    (p["user_objects"] / "custom" / "box").mkdir(parents=True)
    (p["user_objects"] / "custom" / "box" / "notes.txt").write_text("my notes\n")
    return p


# -- cases -----------------------------------------------------------------------------------------


def _notes_dir(path: Path) -> Callable[[], None]:
    """A user's directory (notes, a LaTeX file) that --overwrite must not delete."""
    def setup() -> None:
        shutil.rmtree(path, ignore_errors=True)
        path.mkdir(parents=True)
        (path / "notes.txt").write_text("my notes\n")
        (path / "paper.tex").write_text("\\documentclass{article}\n")
    return setup


def cases(p: dict[str, Path]) -> list[Case]:
    """The bad command lines, grouped by command (about 250)."""
    r = p["root"]
    out: list[Case] = []

    def add(command: str, *argv: object, keep: list[Path] | None = None, setup=None) -> None:
        out.append(Case(command, [str(a) for a in argv], keep or [], setup))

    box = p["box"]
    # label
    for opt, values in (("--grasps", ["-1", "0", "1000000000000", "1e3", "nan", ""]),
                        ("--samples", ["0", "-5", "100000000", "inf"]),
                        ("--mass", ["-1", "0", "nan", "inf", "abc"]),
                        ("--seed", ["-1", "-99999999999"]),
                        ("--top", ["-1"])):
        for v in values:
            add("label", "label", box, *([] if opt == "--grasps" else ["--grasps", "4"]), opt, v)
    for com in ("nan,0,0", "17,0,0", "1,2"):
        add("label", "label", box, "--grasps", "4", "--com", com)
    for grasp in ("nan,0,0,0,0,1", "0,0,0.01,0,0,2", "8,0,0,0,0,-1", "1,2,3"):
        add("label", "label", box, "--grasp", grasp)
    for name in ("mesh_empty.obj", "mesh_garbage.stl", "mesh_truncated.obj", "mesh_words.ply"):
        add("label", "label", p[name], "--grasps", "4")
    add("label", "label", r / "missing.obj", "--grasps", "4")
    add("label", "label", p["a_dir"], "--grasps", "4")
    add("label", "label", box, "--grasps", "4", "--units", "parsec")
    add("label", "label", box, "--grasps", "4", "--cup", "huge")
    add("label", "label", box, "--grasps", "4", "--out", p["file.txt"] / "labels.npz")
    add("label", "label", box, "--grasps", "4", "--out", p["file.txt"], keep=[p["file.txt"]])
    add("label", "label", box)

    # pick
    for argv in (["--seed", "-1"], ["--object", "nope/x"], ["--object", "basic"], ["--grasp", "8.6,0,0,0,0,-1"],
                 ["--grasp", "0,0,0,0,0,0"], ["--placement", "hover"], ["--metric", "xyz"], ["--policy", "nope"],
                 ["--cup", "huge"], ["--log", p["file.txt"] / "x.mcap"], ["--log", r / "ep.txt"],
                 ["--render", p["file.txt"] / "x.png"], ["--model", p["model_nan"], "--policy", "gqcnn"],
                 ["--model", p["model_truncated"], "--policy", "gqcnn"]):
        argv = list(argv)
        if "--object" not in argv:
            argv = ["--object", "basic/box_tea", *argv]
        add("pick", "pick", *argv)
    for name in ("cam_huge.toml", "cam_1px.toml", "cam_tiny_f.toml", "cam_far.toml", "cam_nan.toml",
                 "cam_types.toml", "cam_binary.toml"):
        add("pick", "pick", "--object", "basic/box_tea", "--camera", p[name])

    # generate
    g = ["generate", "--objects", "basic"]
    for opt, v in (("--datapoints", "0"), ("--datapoints", "-1"), ("--datapoints", "100000000000"),
                   ("--grasps-per-object", "0"), ("--grasps-per-object", "100000000"), ("--seed", "-1"),
                   ("--workers", "-1"), ("--engine", "spark"), ("--load", "dynamic"), ("--noise", "kinect"),
                   ("--thumbnail-sampling", "median"), ("--thumbnail-crop", "8"), ("--thumbnail-crop", "x"),
                   ("--thumbnail-crop", "200"), ("--max-images-per-object", "0"),
                   ("--max-images-per-object", "100001")):
        base = {"--datapoints": "4"}
        base[opt] = v
        add("generate", *g, *[x for kv in base.items() for x in kv], "--out", r / f"gen_{opt[2:]}_{v}")
    add("generate", *g, "--datapoints", "4", "--out", p["file.txt"])
    add("generate", *g, "--datapoints", "4", "--out", p["file.txt"] / "ds")
    add("generate", "generate", "--objects", "nope", "--datapoints", "4", "--out", r / "gen_nope")
    for name in ("ds_no_splits", "ds_empty_card", "ds_bad_card", "ds_no_card", "file.txt", "a_dir", "model_good",
                 "model_bad_card"):
        add("generate", *g, "--datapoints", "4", "--holdout-like", p[name], "--out", r / f"gen_holdout_{name}")
    for name in ("cam_huge.toml", "cam_1px.toml", "cam_tiny_f.toml", "cam_far.toml", "cam_binary.toml"):
        add("generate", *g, "--datapoints", "4", "--camera", p[name], "--out", r / f"gen_{name}")
    notes = r / "user_notes"
    add("generate", *g, "--datapoints", "4", "--workers", "1", "--out", notes, "--overwrite",
        keep=[notes / "notes.txt", notes / "paper.tex"], setup=_notes_dir(notes))

    # dataset show
    for name in ("ds_no_shard", "ds_truncated", "ds_no_manifest", "ds_bad_manifest", "ds_no_tensors",
                 "ds_empty_card", "ds_bad_card", "ds_no_card", "ds_nan"):
        add("dataset show", "dataset", "show", p[name])
    add("dataset show", "dataset", "show", r / "missing_ds")
    add("dataset show", "dataset", "show", p["file.txt"])
    add("dataset show", "dataset", "show", p["ds_good"], "--seed", "-1")
    add("dataset show", "dataset", "show", p["ds_good"], "--thumbnails", p["file.txt"] / "t.png")

    # train
    t = ["train", "--arch", "compact", "--epochs", "1"]
    for name in ("ds_nan", "ds_no_shard", "ds_truncated", "ds_no_tensors", "ds_empty_card", "ds_no_splits"):
        add("train", *t, "--dataset", p[name], "--out", r / f"train_{name}")
    for opt, v in (("--epochs", "0"), ("--epochs", "-1"), ("--batch-size", "0"), ("--max-datapoints", "0"),
                   ("--max-datapoints", "-5"), ("--seed", "-1"), ("--device", "tpu"), ("--arch", "huge"),
                   ("--split", "random"), ("--batch-size", "1000000000000"), ("--learning-rate", "0"),
                   ("--learning-rate", "inf"), ("--max-objects", "0"), ("--max-objects", "-2"),
                   ("--train-objects", "*household*"), ("--train-objects", "")):
        add("train", *t, "--dataset", p["ds_good"], opt, v, "--out", r / f"train_{opt[2:]}_{v}")
    add("train", *t, "--dataset", p["ds_good"], "--out", p["file.txt"])

    # model show
    for name in ("model_nan", "model_truncated", "model_bad_card", "model_no_weights", "model_empty", "file.txt"):
        add("model show", "model", "show", p[name])
    add("model show", "model", "show", r / "missing_model")

    # model score
    for name in ("model_nan", "model_truncated", "model_bad_card", "file.txt"):
        add("model score", "model", "score", p[name], "--dataset", p["ds_good"])
    for opt, v in (("--split", "random"), ("--part", "test"), ("--max-datapoints", "0"), ("--seed", "-1")):
        add("model score", "model", "score", p["model_good"], "--dataset", p["ds_good"], opt, v)
    add("model score", "model", "score", p["model_good"], "--dataset", r / "missing_dataset")

    # eval
    e = ["eval", "--policy", "centroid", "--workers", "1"]
    for opt, v in (("--trials", "0"), ("--trials", "-1"), ("--trials", "100000000"), ("--workers", "-1"),
                   ("--seed", "-1"), ("--engine", "spark"), ("--metric", "xyz"), ("--cup", "huge"),
                   ("--set", "nope"), ("--model", p["model_nan"])):
        argv = [*e, "--set", "basic", "--trials", "2", opt, v] if opt != "--set" else [*e, "--set", v]
        if opt == "--model":
            argv[2] = "gqcnn"
        add("eval", *argv, "--out", r / f"eval_{opt[2:]}_{Path(str(v)).name}")
    for name in ("task_types.toml", "task_binary.toml", "task_zero.toml", "task_negseed.toml", "task_poses.toml",
                 "task_metrics.toml", "task_placement.toml", "task_unknown_key.toml", "task_huge.toml",
                 "task_set.toml"):
        add("eval", *e, "--task", p[name], "--out", r / f"eval_{name}")
    add("eval", *e, "--task", r / "missing.toml", "--out", r / "eval_missing")
    add("eval", *e, "--out", r / "eval_neither")
    add("eval", *e, "--set", "basic", "--trials", "2", "--out", p["file.txt"])
    add("eval", "eval", "--policy", "nope", "--set", "basic", "--trials", "2", "--out", r / "eval_badpolicy")

    # report
    for name in ("run_killed", "run_killed0", "run_extra", "run_truncated_json", "run_list_json",
                 "run_empty_json", "run_no_trials", "run_bad_log"):
        add("report", "report", p[name], "--out", r / f"report_{name}")
    add("report", "report", r / "missing_run", "--out", r / "report_missing")
    add("report", "report", p["a_dir"], "--out", r / "report_empty_dir")
    add("report", "report", p["run_good"], "--out", p["file.txt"])

    # bench
    for argv in (["--threshold", "nan"], ["--threshold", "inf"], ["--threshold", "-1"], ["--threshold", "2"],
                 ["--trials", "0"], ["--trials", "-1"], ["--workers", "-1"], ["--sets", ",,,"],
                 ["--sets", "nope"], ["--seed", "-1"]):
        add("bench agreement", "bench", "agreement", "--trials", "3", "--workers", "1", *argv)
    for argv in (["--grasps", "0"], ["--grasps", "-1"], ["--reference-grasps", "-1"], ["--samples", "0"],
                 ["--memory-grasps", "-1"], ["--cores", "-1"], ["--mass", "nan"], ["--seed", "-1"],
                 ["--mesh", p["mesh_garbage.stl"]], ["--grasps", "1000000000000"]):
        add("bench label", "bench", "label", "--grasps", "10", "--reference-grasps", "1", "--memory-grasps", "10",
            *argv)
    for argv in (["--policies", ",,,"], ["--policies", "nope"], ["--scenes", "0"], ["--cores", "-1"],
                 ["--seed", "-1"], ["--model", p["model_nan"]]):
        add("bench plan", "bench", "plan", "--policies", "centroid", "--scenes", "1", *argv)
    for argv in (["--episodes", "0"], ["--episodes", "-1"], ["--cores", "-1"], ["--object", "nope/x"],
                 ["--seed", "-1"]):
        add("bench episode", "bench", "episode", "--episodes", "1", *argv)
    for argv in (["--datapoints", "0"], ["--datapoints", "-1"], ["--workers", "-1"], ["--objects", "nope"],
                 ["--seed", "-1"]):
        add("bench generate", "bench", "generate", "--datapoints", "4", "--workers", "1", *argv)
    for argv in (["--datapoints", "0"], ["--datapoints", "-1"], ["--reference-datapoints", "5000"],
                 ["--archs", ",,,"], ["--archs", "nope"], ["--device", "tpu"], ["--device", "cuda:x"],
                 ["--batch-size", "0"], ["--cores", "-1"], ["--seed", "-1"]):
        add("bench train", "bench", "train", "--device", "cpu", "--datapoints", "1000",
            "--reference-datapoints", "1000", *argv)
    for argv in (["--scale", "nan"], ["--scale", "-1"], ["--cores", "-1"], ["--units", "ft"]):
        add("bench import", "bench", "import", p["mesh_garbage.stl"], *argv)
    add("bench import", "bench", "import", p["mesh_garbage.stl"])

    # objects
    for argv in (["--count", "0"], ["--count", "-1"], ["--seed", "-1"], ["--workers", "-1"],
                 ["--count", "100000000000"], ["--masses", "feathers"]):
        add("objects generate", "objects", "generate", "--count", "1", "--workers", "1", *argv,
            "--out", r / f"corpus_{'_'.join(argv)}")
    add("objects generate", "objects", "generate", "--count", "1", "--out", p["file.txt"])
    add("objects build", "objects", "build", "--set", "nope", "--out", r / "build_nope")
    add("objects build", "objects", "build", "--set", "basic", "--workers", "-1", "--out", r / "build_w")
    for argv in (["--grasps", "0"], ["--grasps", "-1"], ["--seed", "-1"], ["--set", "nope"]):
        add("objects stats", "objects", "stats", "--set", "basic", "--grasps", "2", *argv)
    for argv in ([p["mesh_garbage.stl"]], [p["mesh_empty.obj"]], [r / "missing.stl"], [box, "--units", "parsec"],
                 [box, "--mass", "-1"], [box, "--mass", "nan"], [box, "--name", "BAD NAME"],
                 [box, "--set", "../../etc"]):
        add("objects import", "objects", "import", *argv, "--root", r / "user_objects")
    for key in ("nope/x", "../../etc", "basic"):
        add("objects show", "objects", "show", key)
    add("objects build", "objects", "build", "--set", "basic", "--workers", "1", "--out", p["user_objects"],
        keep=[p["user_objects"] / "basic" / "box_tea" / "notes.txt"])
    add("objects import", "objects", "import", box, "--root", p["user_objects"], "--overwrite",
        keep=[p["user_objects"] / "custom" / "box" / "notes.txt"])
    add("objects stats", "objects", "stats", "--set", "basic", "--grasps", "1000000000")
    add("objects generate", "objects", "generate", "--count", "1000000000", "--workers", "1",
        "--out", r / "corpus_huge")
    add("bench label", "bench", "label", "--grasps", "10", "--reference-grasps", "1", "--memory-grasps", "1000000000")
    add("bench agreement", "bench", "agreement", "--trials", "1000000000", "--workers", "1")
    add("bench plan", "bench", "plan", "--policies", "centroid", "--scenes", "1000")

    # train into a directory holding a model card it did not write, with and without --overwrite
    for extra in ([], ["--overwrite"]):
        add("train", *t, "--dataset", p["ds_good"], "--out", p["user_model"], *extra,
            keep=[p["user_model"] / "model.json"])

    # plan: depth images, masks, camera poses, cameras and outputs
    d = ["plan", "--camera", "primesense", "--policy", "centroid", "--depth"]
    for name in ("depth_nan.npy", "depth_rgb.npy", "depth_pickle.npy", "depth_mm_float.npy", "garbage.npy",
                 "file.txt", "mesh_empty.obj"):
        add("plan", *d, p[name])
    add("plan", *d, r / "missing.npy")
    for argv in (["--mask", p["mask_small.npy"]], ["--mask", r / "missing.npy"], ["--camera-pose", p["pose_3x3.npy"]],
                 ["--camera-pose", p["pose_nan.npy"]], ["--camera-pose", p["file.txt"]], ["--policy", "nope"],
                 ["--policy-arg", "junk"], ["--out", p["file.txt"] / "x.png"], ["--out", p["a_dir"]],
                 ["--camera", p["cam_huge.toml"]], ["--camera", p["cam_binary.toml"]], ["--camera", "nope"],
                 ["--model", p["model_nan"], "--policy", "gqcnn"], ["--depth-scale", "0"]):
        add("plan", *d, p["depth_flat.npy"], *argv)

    # cameras
    for spec in ("nope", p["cam_binary.toml"], p["cam_nan.toml"], p["cam_huge.toml"], p["cam_types.toml"],
                 r / "missing.toml"):
        add("cameras", "cameras", "--toml", spec)
    return out


# -- the table -------------------------------------------------------------------------------------


def classify(code: int, stdout: str, stderr: str, as_json: bool, changed: bool) -> str:
    """clean / messy / crash / wrong (see the module docstring)."""
    if changed or code in (0, -9):  # -9: still running at the time limit
        return "wrong"
    if code != 2 or "Traceback" in stderr:
        return "crash"
    lines = [line for line in stderr.splitlines() if line.strip()]
    if len(lines) != 1:
        return "messy"
    if as_json:
        last = stdout.strip().splitlines()[-1] if stdout.strip() else ""
        try:
            obj = json.loads(last, parse_constant=lambda c: (_ for _ in ()).throw(ValueError(c)))
        except ValueError:
            return "messy"
        if not isinstance(obj, dict) or obj.get("ok") is not False:
            return "messy"
    return "clean"


def clear_outputs(case: Case, paths: dict[str, Path]) -> None:
    """Remove what an earlier run of `case` wrote to its --out (never a corpus input), so runs are independent."""
    inputs = set(paths.values())
    root = paths["root"]
    for flag, value in zip(case.argv, case.argv[1:], strict=False):
        target = Path(value)
        if flag == "--out" and target not in inputs and root in target.parents and not case.setup:
            for stale in (target, target.with_name(target.name + ".incomplete")):
                if stale.is_dir():
                    shutil.rmtree(stale)
                elif stale.exists():
                    stale.unlink()


def _snapshot(paths: list[Path]) -> list[bytes | None]:
    return [path.read_bytes() if path.is_file() else None for path in paths]


def tree(root: Path) -> set[Path]:
    """Every path under `root` (to find what a refused command wrote)."""
    return set(root.rglob("*"))


def remove_new(root: Path, before: set[Path]) -> list[Path]:
    """Delete what appeared under `root` since `before` (so cases stay independent); returns it."""
    new = sorted(tree(root) - before, key=lambda path: len(path.parts))
    for path in reversed(new):
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        else:
            path.unlink(missing_ok=True)
    return new


def run_forked(argv: list[str], timeout: float, mem_bytes: int) -> tuple[int, str, str]:
    """Run the CLI in a forked child (imports already done) with its own session, time and memory
    limit; returns (exit code, stdout, stderr); code -9 after the time limit."""
    import resource
    import signal
    import tempfile
    import time

    with tempfile.TemporaryFile() as fo, tempfile.TemporaryFile() as fe:
        pid = os.fork()
        if pid == 0:  # child
            code = 1
            try:
                os.setsid()
                resource.setrlimit(resource.RLIMIT_AS, (mem_bytes, mem_bytes))
                os.dup2(fo.fileno(), 1)
                os.dup2(fe.fileno(), 2)
                import sys

                sys.argv = ["suctionbench", *argv]
                from suctionbench.cli import main

                main()
                code = 0
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
            except BaseException:  # noqa: BLE001 (anything escaping main is a crash)
                import traceback

                traceback.print_exc()
                code = 1
            finally:
                import sys

                sys.stdout.flush()
                sys.stderr.flush()
                os._exit(code)
        deadline = time.monotonic() + timeout
        status = None
        while time.monotonic() < deadline:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                break
            time.sleep(0.05)
        else:
            with contextlib_suppress():
                os.killpg(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            status = None
        code = -9 if status is None else (os.waitstatus_to_exitcode(status))
        fo.seek(0)
        fe.seek(0)
        return code, fo.read().decode(errors="replace"), fe.read().decode(errors="replace")


def contextlib_suppress():
    import contextlib

    return contextlib.suppress(ProcessLookupError)


def main() -> None:
    import argparse
    import tempfile
    import time

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timeout", type=float, default=20.0)
    parser.add_argument("--only", default="", help="comma-separated commands")
    parser.add_argument("--cases", action="store_true", help="print each case's outcome")
    parser.add_argument("--no-json", action="store_true", help="only the plain runs")
    args = parser.parse_args()
    import torch  # noqa: F401

    import suctionbench.cli  # noqa: F401  (import once, before forking)

    root = Path(tempfile.mkdtemp(prefix="sb_fuzz_"))
    start = time.perf_counter()
    paths = build_corpus(root / "corpus")
    print(f"corpus built in {time.perf_counter() - start:.1f} s under {root}", flush=True)
    only = {c.strip() for c in args.only.split(",") if c.strip()}
    table: dict[str, dict[str, int]] = {}
    for case in cases(paths):
        if only and case.command not in only:
            continue
        for as_json in (False,) if args.no_json else (False, True):
            clear_outputs(case, paths)
            if case.setup:
                case.setup()
            before, files = _snapshot(case.keep), tree(paths["root"])
            t0 = time.perf_counter()
            code, stdout, stderr = run_forked(case.argv + (["--json"] if as_json else []), args.timeout,
                                              6 * 2**30)
            changed = _snapshot(case.keep) != before
            written = remove_new(paths["root"], files)
            changed = changed or (bool(written) and code != 0)  # a refused command writes nothing
            outcome = classify(code, stdout, stderr, as_json, changed)
            row = table.setdefault(case.command, {"cases": 0, "clean": 0, "messy": 0, "crash": 0, "wrong": 0})
            row["cases"] += 1
            row[outcome] += 1
            if args.cases:
                last = (stderr.strip().splitlines() or [""])[-1][:150]
                print(f"{outcome:6s} rc={code:3d} {time.perf_counter() - t0:5.1f}s {'J ' if as_json else '  '}"
                      f"{case.name[:140]} | {last}", flush=True)
    shutil.rmtree(root, ignore_errors=True)
    print("\n| command | runs | clean exit 2 | exit 2, not one line | crash | wrong success |")
    print("|---|---|---|---|---|---|")
    total = {"cases": 0, "clean": 0, "messy": 0, "crash": 0, "wrong": 0}
    for command, row in table.items():
        print(f"| {command} | {row['cases']} | {row['clean']} | {row['messy']} | {row['crash']} | {row['wrong']} |")
        for k in total:
            total[k] += row[k]
    print(f"| **all** | {total['cases']} | {total['clean']} | {total['messy']} | {total['crash']} | {total['wrong']} |")


if __name__ == "__main__":
    main()
