"""The files in examples/ run as the README says: the policy plug-in plans on rendered scenes and
runs in `suctionbench eval` (worker processes, --policy-arg), and the gymnasium loop runs as a script."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from suctionbench.policies.base import make_policy

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
PLUGIN = f"{EXAMPLES / 'policy_plugin.py'}:make_policy"


def _module(name: str):
    spec = importlib.util.spec_from_file_location(f"example_{name}", EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def rendered():
    from suctionbench.sim.pick import PickRequest, PickRunner

    runner = PickRunner(PickRequest("basic/box_tea", seed=1))
    runner.reset()
    return runner.observe()


def test_policy_plugin_is_short_and_grasps_the_top_of_the_object(rendered):
    assert len((EXAMPLES / "policy_plugin.py").read_text().splitlines()) <= 40
    policy = make_policy(PLUGIN, band=0.005)
    action = policy.plan(rendered, np.random.default_rng(0))
    u, v = (int(x) for x in action.pixel)
    assert rendered.mask[v, u] and 0.0 < action.q <= 1.0
    heights = rendered.intrinsics.deproject(rendered.depth)[rendered.mask] @ rendered.camera_pose[2, :3]
    height = action.point @ rendered.camera_pose[2, :3]
    assert height >= np.percentile(heights, 90) - 0.005  # on the top band, not a side
    assert action.approach_world[2] < -0.9  # from above


def test_policy_plugin_runs_in_eval_with_an_option(tmp_path):
    out = tmp_path / "run"  # the README's command, as a user types it (relative spec, from the checkout)
    command = [sys.executable, "-m", "suctionbench", "eval", "--policy", "examples/policy_plugin.py:make_policy",
               "--policy-arg", "band=0.02", "--set", "basic", "--trials", "2", "--workers", "2", "--out", str(out),
               "--json"]
    result = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300,
                            env={**os.environ, "MUJOCO_GL": "egl"})
    assert result.returncode == 0, result.stderr[-2000:]
    summary = json.loads(result.stdout.strip().splitlines()[-1])
    assert summary["ok"] and summary["trials"] == 2 and summary["invalid"] == 0
    assert summary["label"] == "examples/policy_plugin.py:make_policy(band=0.02)"
    run = json.loads((out / "run.json").read_text())
    assert run["policy_spec"] == PLUGIN and run["policy_args"] == {"band": 0.02}
    assert run["command"].startswith("suctionbench eval --policy examples/policy_plugin.py:make_policy")


def test_gym_loop_policy_aims_at_the_object_straight_down():
    import gymnasium

    loop = _module("gym_loop")
    env = gymnasium.make("suctionbench/SuctionPick-v4", object_set="basic")
    try:
        observation, _ = env.reset(seed=5)
        action = loop.middle_straight_down(observation)
        assert env.action_space.contains(action)
        pose = observation["camera_pose"].astype(float)
        k = observation["intrinsics"]
        u, v = (k @ (action[:3] / action[2]))[:2]
        assert observation["mask"][int(round(v)), int(round(u))]
        np.testing.assert_allclose(pose[:3, :3] @ action[3:], [0, 0, -1], atol=1e-5)
        _, reward, terminated, _, info = env.step(action)
        assert reward in (0.0, 1.0) and terminated and info["grasp_world"] is not None
        np.testing.assert_allclose(info["grasp_world"][:3], pose[:3, :3] @ action[:3] + pose[:3, 3], atol=1e-4)
        assert np.all(loop.middle_straight_down({**observation, "mask": np.zeros_like(observation["mask"])}) == 0)
    finally:
        env.close()


def test_gym_loop_runs_as_a_script():
    result = subprocess.run([sys.executable, "examples/gym_loop.py", "--episodes", "2", "--seed", "4"], cwd=ROOT,
                            capture_output=True, text=True, timeout=300, env={**os.environ, "MUJOCO_GL": "egl"})
    assert result.returncode == 0, result.stderr[-2000:]
    lines = result.stdout.strip().splitlines()
    assert [line.split(":")[0] for line in lines[:2]] == ["episode 0", "episode 1"]
    assert lines[-1].startswith("success rate") and lines[-1].endswith("over 2 episodes")


def test_render_depth_writes_an_image_plan_reads(tmp_path):
    from suctionbench.planning import plan_grasp, read_depth

    out = tmp_path / "scene.png"
    result = subprocess.run([sys.executable, "examples/render_depth.py", "--object", "basic/box_tea", "--seed", "1",
                             "--out", str(out)], cwd=ROOT, capture_output=True, text=True, timeout=300,
                            env={**os.environ, "MUJOCO_GL": "egl"})
    assert result.returncode == 0, result.stderr[-2000:]
    depth = read_depth(out)
    assert depth.shape == (480, 640) and 0.3 < float(np.median(depth[depth > 0])) < 1.0
    grasp = plan_grasp(depth, "primesense", policy="planarity-centroid", seed=0)
    assert grasp.observation.mask[int(grasp.action.pixel[1]), int(grasp.action.pixel[0])]


def test_shipped_depth_example_is_the_scene_render_depth_makes():
    from PIL import Image

    from suctionbench.planning import plan_grasp, read_depth

    depth = read_depth(EXAMPLES / "scene_mug.png")  # examples/render_depth.py's defaults
    assert Image.open(EXAMPLES / "scene_mug.png").mode.startswith("I") and depth.shape == (480, 640)
    result = plan_grasp(depth, "primesense", policy="planarity-centroid", seed=0)
    assert 5000 < result.observation.mask.sum() < 8000  # the mug, not the bin or the robot
    assert result.plane.inlier_fraction > 0.7 and result.action.approach_world[2] < -0.8


def test_bin_loop_clears_part_of_a_smoke_bin(capsys):
    cleared = _module("bin_loop").main(task="bin-smoke", seed=0)
    assert 0.0 <= cleared <= 1.0
    out = capsys.readouterr().out
    attempts = [line for line in out.splitlines() if line.startswith("attempt ")]
    assert attempts  # it made at least one grasp attempt
    # the summary it prints counts the rewards it received: removed / in the bin is what it returned
    removed, total = (int(x) for x in out.split("removed ")[-1].split(" objects")[0].split(" of "))
    assert removed / total == pytest.approx(cleared)
    assert removed == sum(int(line.split("reward ")[1].split()[0]) for line in attempts)


def test_policy_plugin_runs_unchanged_on_a_bin(tmp_path):
    # A plug-in gets the whole bin as its observation's mask (no per-region planning) and plans as it likes.
    from typer.testing import CliRunner

    from suctionbench.cli import app

    result = CliRunner().invoke(app, ["eval", "--policy", PLUGIN, "--task", "bin-smoke", "--workers", "1",
                                      "--out", str(tmp_path / "run"), "--json"])
    assert result.exit_code == 0, result.output
    run = json.loads((tmp_path / "run" / "run.json").read_text())
    attempts = run["bins"][0]["attempts"]
    assert attempts and all(a["region"] is None for a in attempts if a["grasp_world"] is not None)
