"""Bin picking in clutter (suctionbench.clutter): bin tasks, depth segmentation, the cup's path
check, filling the bin, the bin benchmark from the CLI, and the SuctionBin-v5 environment."""

from __future__ import annotations

import json
import math

import gymnasium
import mujoco
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from typer.testing import CliRunner

import suctionbench  # noqa: F401  (registers the environments)
from suctionbench.cli import app
from suctionbench.clutter.planning import path_is_clear
from suctionbench.clutter.tasks import BinTask, load_bin_task
from suctionbench.config import to_dict
from suctionbench.errors import InputError
from suctionbench.evaluation.tasks import is_bin_task
from suctionbench.policies.gqcnn import DEFAULT_MODEL
from suctionbench.policies.plugins import load_policy
from suctionbench.sensing.camera import CameraIntrinsics
from suctionbench.sensing.segmentation import SegmentationConfig, convex, segment_regions

SHIPPED = ("bin-smoke", "bin-basic", "bin-typical", "bin-mixed")


# -- tasks ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_bin_tasks_load(name):
    task = load_bin_task(name)
    assert is_bin_task(name)
    assert 1 <= task.objects[0] <= task.objects[1] <= 15
    assert task.max_failures >= 1


def test_single_object_tasks_are_not_bin_tasks():
    assert not is_bin_task("basic") and not is_bin_task("smoke")


def test_bin_draw_is_seeded_and_in_range():
    task = BinTask(name="t", sets=("basic",), objects=(5, 8), trials=3)
    available = [f"basic/o{i}" for i in range(30)]
    draws = [task.draw(i, available) for i in range(20)]
    assert draws == [task.draw(i, available) for i in range(20)]  # the same bins for every policy
    assert all(5 <= len(d) <= 8 and len(set(d)) == len(d) for d in draws)  # distinct objects
    assert len({tuple(d) for d in draws}) > 1


@pytest.mark.parametrize("text, problem", [
    ('scene = "bin"\nsets = ["basic"]\nobjects = [5, 3]\ntrials = 1\n', "objects"),
    ('scene = "bin"\nsets = []\nobjects = [1, 3]\ntrials = 1\n', "sets"),
    ('scene = "bin"\nsets = ["basic"]\nobjects = [1, 3]\ntrials = 1\nbogus = 2\n', "bogus"),
    ('scene = "bin"\nsets = ["basic"]\nobjects = [1, 3]\n', "trials"),
    ('sets = ["basic"]\nobjects = [1, 3]\ntrials = 1\n', "not a bin task"),
])
def test_malformed_bin_tasks_are_named(tmp_path, text, problem):
    path = tmp_path / "t.toml"
    path.write_text(text)
    with pytest.raises(InputError, match=problem):
        load_bin_task(str(path))


# -- segmentation -----------------------------------------------------------------------------------
CAMERA = CameraIntrinsics(name="test", fx=500.0, fy=500.0, cx=80.0, cy=60.0, width=160, height=120,
                          min_depth=0.2, max_depth=2.0)


def _scene_depth(blocks):
    """Depth image (camera looking straight down from 0.6 m onto a floor) of axis-aligned blocks
    given as (x0, x1, y0, y1, height, tilt): a top face at `height` above the floor over
    [x0, x1] x [y0, y1] (camera-frame metres), tilted about the camera's y axis by `tilt` rad
    through its centre. Each pixel's ray meets the first top face or the floor."""
    v, u = np.mgrid[0:CAMERA.height, 0:CAMERA.width].astype(float)
    rx, ry = (u - CAMERA.cx) / CAMERA.fx, (v - CAMERA.cy) / CAMERA.fy
    depth = np.full(u.shape, 0.6)
    for x0, x1, y0, y1, height, tilt in blocks:
        xc = 0.5 * (x0 + x1)
        # the plane z = (0.6 - height) - tan(tilt) (x - xc), met by the ray (rx z, ry z, z)
        z = (0.6 - height + math.tan(tilt) * xc) / (1.0 + math.tan(tilt) * rx)
        x, y = rx * z, ry * z
        inside = (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1) & (z < depth)
        depth[inside] = z[inside]
    return depth.astype(np.float32)


def test_segmentation_separates_stacked_and_side_by_side_objects():
    # Three objects: two side by side at the same height whose top faces, tilted 30 deg each way,
    # meet in a valley at x = 0 (a concave crease of 60 deg, no depth step: each face descends
    # towards the other, depth 0.536 m at its outer edge and 0.564 m where they meet), and one on its
    # own 2 cm higher (a depth step of 2 cm > the 8 mm jump threshold).
    blocks = [
        (-0.05, 0.0, -0.03, 0.03, 0.05, math.radians(-30)),
        (0.0, 0.05, -0.03, 0.03, 0.05, math.radians(30)),
        (-0.03, 0.03, 0.035, 0.05, 0.07, 0.0),
    ]
    depth = _scene_depth(blocks)
    workspace = depth < 0.6 - 0.005  # above the floor
    regions = segment_regions(depth, CAMERA, workspace)
    assert len(regions) == 3
    assert not np.any(np.sum(regions, axis=0) > 1)  # disjoint


def test_segmentation_keeps_an_object_whole_across_its_own_convex_edge():
    # A roof-shaped top: the same two 30 deg faces meeting in a ridge instead (each rises towards
    # the other, depth 0.564 m at its outer edge and 0.536 m at x = 0), as the top and the side of
    # one object do: a convex crease, not a boundary. (Two objects leaning together into a ridge
    # look the same and merge: the segmentation's documented limit.) Cutting convex creases too,
    # the segmentation before 2026-11-28, splits it in two.
    roof = [(-0.05, 0.0, -0.03, 0.03, 0.05, math.radians(30)), (0.0, 0.05, -0.03, 0.03, 0.05, math.radians(-30))]
    depth = _scene_depth(roof)
    workspace = depth < 0.6 - 0.005
    regions = segment_regions(depth, CAMERA, workspace)
    assert len(regions) == 1
    assert regions[0].sum() > 0.9 * workspace.sum()
    assert len(segment_regions(depth, CAMERA, workspace, SegmentationConfig(cut_convex_creases=True))) == 2


def test_convexity_criterion_on_a_box_edge_and_a_valley():
    # The derivations in `convex`'s docstring: a box's top (n = z at (0, 0, 1)) and side (n = x at
    # (1, 0, 0.5)) bend away: (n1 - n2) . (p1 - p2) = 1.5 > 0; two faces of a V, n = (+-1, 0, 1) / sqrt 2
    # at (-+1, 0, 1): -2 sqrt 2 < 0. Swapping the two points swaps both differences: the same sign.
    z, x = np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])
    assert convex(z, x, np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.5]))
    assert convex(x, z, np.array([1.0, 0.0, 0.5]), np.array([0.0, 0.0, 1.0]))
    left, right = np.array([1.0, 0.0, 1.0]) / np.sqrt(2), np.array([-1.0, 0.0, 1.0]) / np.sqrt(2)
    assert not convex(left, right, np.array([-1.0, 0.0, 1.0]), np.array([1.0, 0.0, 1.0]))


def test_segmentation_keeps_one_flat_face_whole_under_noise():
    depth = _scene_depth([(-0.05, 0.05, -0.04, 0.04, 0.05, 0.0)])
    noisy = depth + np.random.default_rng(0).normal(0.0, 0.0012, depth.shape).astype(np.float32)  # PrimeSense-like
    regions = segment_regions(noisy, CAMERA, depth < 0.595)
    assert len(regions) == 1
    assert regions[0].sum() > 0.9 * (depth < 0.595).sum()


# -- the cup's path ---------------------------------------------------------------------------------
def _shelf_model():
    """A 10 cm block on the floor, and a plate 10 cm above its left half (an overhang)."""
    xml = """<mujoco><worldbody>
      <body name="block" pos="0 0 0.05"><freejoint/><geom type="box" size="0.05 0.05 0.05" group="5"/></body>
      <body name="plate" pos="-0.03 0 0.2"><freejoint/><geom type="box" size="0.03 0.05 0.005" group="5"/></body>
    </worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def test_path_check_sees_an_overhang_but_not_the_target():
    model, data = _shelf_model()
    block = model.body("block").id
    down = np.array([0.0, 0.0, -1.0])
    # Under the plate (x = -0.03): the plate's underside is 9.3 cm above the ray's start, beyond the
    # cup's 8 cm but within the wrist ring's 25 cm, so the wrist would hit it.
    assert not path_is_clear(model, data, np.array([-0.03, 0.0, 0.1]), down, block, 0.01, 0.08)
    # At x = 0.045 every ray (cup ring x in [0.035, 0.055], wrist ring x in [0.01, 0.08]) passes
    # beside the plate, which ends at x = 0.
    assert path_is_clear(model, data, np.array([0.045, 0.0, 0.1]), down, block, 0.01, 0.08)
    # With the wrist ring inside the plate's span (x = 0.03: ring down to x = -0.005) it is not clear.
    assert not path_is_clear(model, data, np.array([0.03, 0.0, 0.1]), down, block, 0.01, 0.08)
    # The target itself never blocks (its own faces are excluded).
    assert path_is_clear(model, data, np.array([0.045, 0.0, 0.1]), down, block, 0.01, 0.3)


# -- filling the bin --------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def smoke_runner():
    from suctionbench.clutter.runner import BinRequest, BinRunner

    runner = BinRunner(BinRequest(load_bin_task("bin-smoke"), trial=0, policy="centroid"))
    runner.episode.reset(np.random.default_rng((0, 0, 0)))
    return runner


def test_filled_bin_holds_every_object_at_rest_inside(smoke_runner):
    ep = smoke_runner.episode
    assert ep.placement_error is None
    assert len(ep.present) + len(ep.spilled) == 3 and len(ep.present) >= 2
    for body in ep.present:
        com = ep.data.xipos[body]
        assert ep.bin.contains(com[:2])
        assert ep.bin.floor < float(ep._object_z(body).min()) + 0.002  # on or above the floor, not through it


def test_parked_objects_float_in_place(smoke_runner):
    # A parked object has gravity compensated and no contacts: with no force on it, it keeps its
    # pose exactly (to integration round-off) over a second of simulation.
    ep = smoke_runner.episode
    body = ep.present[-1]
    ep._park(body)
    mujoco.mj_forward(ep.model, ep.data)
    before = ep.data.xpos[body].copy()
    for _ in range(500):
        mujoco.mj_step(ep.model, ep.data)
    assert np.linalg.norm(ep.data.xpos[body] - before) < 1e-9
    ep._unpark(body)


def test_observation_regions_lie_inside_the_bin_mask(smoke_runner):
    observation, regions = smoke_runner.observe(0)
    assert regions
    for region in regions:
        assert np.all(observation.mask[region])


# -- the benchmark, end to end ----------------------------------------------------------------------
@pytest.mark.parametrize("policy", ["planarity-centroid", "gqcnn", "fc-gqcnn", "analytic"])
def test_bin_smoke_eval_from_the_cli(tmp_path, policy):
    out = tmp_path / "run"
    result = CliRunner().invoke(app, ["eval", "--task", "bin-smoke", "--policy", policy, "--out", str(out),
                                      "--workers", "1", "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout.strip().splitlines()[-1])
    run = json.loads((out / "run.json").read_text())
    assert (out / "bins" / "bin_0000.mcap").stat().st_size > 0
    # the run names the model a GQ-CNN policy planned with (the shipped default: none was given)
    assert run["model_used"] == ("assets/" + "/".join(DEFAULT_MODEL) if "gqcnn" in policy else None)
    # and the config it planned with, defaults included (a default that changes later, such as
    # the seed cone, leaves the run readable); the known-state policy has none
    if policy == "analytic":
        assert run["policy_config"] is None
    else:
        assert run["policy_config"] == to_dict(load_policy(policy, {}).config)
    (record,) = run["bins"]
    attempts = record["attempts"]
    assert attempts and summary["metrics"]["attempts"] == len(attempts)
    assert record["transported"] == sum(len(a["transported"]) for a in attempts)
    # An attempt succeeds exactly when the object the cup held reached the receptacle alone.
    for a in attempts:
        if a["success"]:
            assert a["transported"] == [a["held"]]
    # The episode ended for the reason it gives.
    if record["ended"] == "clear":
        assert attempts[-1]["remaining"] == 0
    if record["ended"] == "failures":
        assert not any(a["success"] for a in attempts[-2:])


def test_bin_eval_rejects_bad_masks_and_writes_nothing(tmp_path):
    out = tmp_path / "run"
    result = CliRunner().invoke(app, ["eval", "--task", "bin-smoke", "--policy", "centroid", "--out", str(out),
                                      "--masks", "bogus", "--json"])
    assert result.exit_code == 2
    assert "--masks" in json.loads(result.stdout.strip().splitlines()[-1])["error"]
    assert not out.exists()


# -- the environment --------------------------------------------------------------------------------
def test_bin_env_passes_gymnasium_checker_and_is_seeded():
    env = gymnasium.make("suctionbench/SuctionBin-v5", task="bin-smoke")
    with pytest.warns(UserWarning):  # the checker's advice on unbounded boxes; not errors
        check_env(env.unwrapped, skip_render_check=True)
    a, info_a = env.reset(seed=5)
    b, info_b = env.reset(seed=5)
    assert info_a == info_b
    assert all(np.array_equal(a[k], b[k]) for k in a)
    env.close()


def test_bin_env_invalid_action_costs_an_attempt_and_moves_nothing():
    env = gymnasium.make("suctionbench/SuctionBin-v5", task="bin-smoke")
    obs, _ = env.reset(seed=1, options={"trial": 0})
    after, reward, terminated, truncated, info = env.step(np.zeros(6, dtype=np.float32))
    assert reward == 0.0 and info["failure"] == "invalid_action" and info["failures_in_row"] == 1
    assert not truncated
    env.close()


# -- data in clutter --------------------------------------------------------------------------------
def test_generate_bin_scene_writes_seeded_cluttered_datapoints(tmp_path):
    from suctionbench.dataset.storage import DatasetReader

    def generate(out):
        result = CliRunner().invoke(app, ["generate", "--objects", "basic", "--datapoints", "150", "--scene", "bin",
                                          "--out", str(out), "--workers", "1", "--json"])
        assert result.exit_code == 0, result.output
        return DatasetReader(out)

    a, b = generate(tmp_path / "a"), generate(tmp_path / "b")
    assert 0 < a.num_datapoints <= 150 and a.num_datapoints == b.num_datapoints
    fields = ("robust_suction_wrench_resistance", "hand_poses", "object_labels", "object_context")
    first, second = ({name: r.field(name) for name in fields} for r in (a, b))
    for name in fields:
        assert np.array_equal(first[name], second[name]), name  # same seed, same data
    rwr = first["robust_suction_wrench_resistance"]
    assert np.all((rwr >= 0) & (rwr <= 1))
    from suctionbench.objects.registry import list_objects

    n_basic = len(list_objects("basic"))
    assert np.all((first["object_labels"] >= 0) & (first["object_labels"] < n_basic))
    # Grasps come from several objects of the bin, seen at their pixels inside the image.
    assert len(np.unique(first["object_labels"])) > 1


@pytest.mark.parametrize("options, named", [(["--scene", "heap"], "--scene"),
                                             (["--scene", "bin", "--grasps-per-image", "5"], "--grasps-per-image"),
                                             (["--scene", "bin", "--max-images-per-object", "5"],
                                              "--max-images-per-object")],
                         ids=["unknown-scene", "cap-in-bins", "image-cap-in-bins"])
def test_generate_rejects_an_unknown_scene_and_options_a_bin_does_not_read(tmp_path, options, named):
    result = CliRunner().invoke(app, ["generate", "--objects", "basic", "--datapoints", "10", *options,
                                      "--out", str(tmp_path / "d"), "--json"])
    assert result.exit_code == 2 and named in json.loads(result.stdout.strip().splitlines()[-1])["error"]
    assert not (tmp_path / "d").exists()  # nothing half-written


def test_an_object_without_convex_parts_collides_as_its_hull(monkeypatch):
    # Training-corpus objects are built without a convex decomposition; in a bin they must still
    # collide (they fell through the floor): their surface mesh becomes the one collision geom,
    # which MuJoCo treats as its convex hull.
    from suctionbench.objects.mjcf import add_object_body
    from suctionbench.objects.registry import load_object

    record = load_object("basic/box_tea")
    monkeypatch.setattr(type(record), "part_meshes", lambda self: [])
    spec = mujoco.MjSpec()
    add_object_body(spec, record)
    model = spec.compile()
    colliding = [g for g in range(model.ngeom) if model.geom_contype[g] or model.geom_conaffinity[g]]
    assert len(colliding) == 1
    assert model.geom_rbound[colliding[0]] == pytest.approx(np.linalg.norm(record.mesh().extents) / 2, rel=0.05)


def test_what_rests_on_an_object_is_load_the_cup_must_lift():
    # Two boxes stacked flat in the bin. In static equilibrium the top box's weight m2 g is carried
    # only by its contacts with the bottom box (it touches nothing else), so the downward force it
    # presses the bottom box with sums to m2 g (MuJoCo's soft contacts: to the solver's residual,
    # 2 % here), and by the top box's torque balance that force acts under its centre of mass. The
    # mass the cup must lift at the bottom box is m1 + m2 with their common centre of mass (xy);
    # nothing rests on the top box.
    from suctionbench.clutter.episode import BinEpisode
    from suctionbench.clutter.scene import PickBinConfig, build_bin_scene
    from suctionbench.config import CUP_DEFAULT
    from suctionbench.objects.registry import load_object
    from suctionbench.sensing.camera import resolve_camera

    bottom_record, top_record = load_object("basic/box_book"), load_object("basic/box_brick")
    scene = build_bin_scene([bottom_record, top_record], CUP_DEFAULT, resolve_camera("primesense"), np.eye(4))
    ep = BinEpisode(scene, PickBinConfig())
    ep.reset(np.random.default_rng(0))
    bottom, top = ep.bodies
    cx, cy = ep.bin.centre
    z = ep.bin.floor
    for body, record in ((bottom, bottom_record), (top, top_record)):
        ep._unpark(body)
        pose = record.most_probable_pose()
        adr = ep.model.jnt_qposadr[ep.model.body_jntadr[body]]
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, pose[:3, :3].ravel())
        ep.data.qpos[adr:adr + 3] = [cx + (0.01 if body == top else 0.0), cy, z + pose[2, 3] + 0.0005]
        ep.data.qpos[adr + 3:adr + 7] = quat
        ep.data.qvel[ep.dofs_of(body)] = 0.0
        mujoco.mj_forward(ep.model, ep.data)
        z = float(ep._object_z(body).max())
    ep.present = [bottom, top]
    q_hold = ep.data.qpos[ep.arm_qpos].copy()
    assert ep.settle(lambda: ep._step(q_hold), ep.present)
    g = 9.80665
    load, at = ep.resting_load(bottom)
    assert load == pytest.approx(top_record.mass * g, rel=0.02)
    assert ep.resting_load(top) == (0.0, None)
    com_bottom, com_top = ep.data.xipos[bottom].copy(), ep.data.xipos[top].copy()
    mass, com = ep.loaded(bottom, bottom_record.mass, com_bottom)
    assert mass == pytest.approx(bottom_record.mass + top_record.mass, rel=0.02)
    expected = (bottom_record.mass * com_bottom + top_record.mass * com_top) / (bottom_record.mass + top_record.mass)
    assert np.allclose(com[:2], expected[:2], atol=1e-3)


def test_bin_metrics_count_a_plan_per_region():
    from suctionbench.clutter.runner import bin_metrics

    def attempt(success, transported, regions, planned, sim_time=10.0):
        return {"success": success, "failure": None if success else "no_seal", "transported": transported,
                "sim_time": sim_time, "region": 0 if regions else None, "region_q": [0.5] * regions,
                "regions": regions, "planned": planned, "label_rwr": None}

    bins = [{"in_bin": ["a", "b", "c", "d"], "transported": 2, "ended": "failures",
             "attempts": [attempt(True, ["a"], 4, 4), attempt(False, [], 3, 3), attempt(True, ["b"], 2, 2)]}]
    m = bin_metrics(bins, {"sensing_s": 0.5, "planning_s": 1.0})
    # cycle = 3 x 10 s of motion + 3 x 0.5 s sensing + (4 + 3 + 2) plans x 1 s = 40.5 s for 2 objects
    assert m["picks_per_hour"] == pytest.approx(round(3600 * 2 / 40.5, 1))
    assert m["clearance"] == 0.5 and m["success_per_attempt"] == pytest.approx(0.6667, abs=1e-4)
    assert m["attempts_per_object"] == 1.5 and m["failures"] == {"no_seal": 1}


def test_the_clutter_model_loads_and_is_the_documented_one():
    # assets/models/gqcnn-bin/README.md documents its held-out clutter scores; the card must agree.
    from suctionbench.learning.checkpoint import load_model

    model = load_model("assets/models/gqcnn-bin")  # verifies the weights against the card's sha256
    assert model.arch == "context-pose"
    assert model.card["metrics"]["val_ap"] == pytest.approx(0.755, abs=5e-4)
    assert model.card["metrics"]["val_accuracy"] == pytest.approx(0.901, abs=5e-4)
    assert "--init assets/models/gqcnn-context-pose" in model.card["command"]
