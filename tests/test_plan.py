"""`suctionbench plan` as a function (suctionbench.planning): a grasp on a user's depth image, on
images built here with numpy (a ray-cast box on a table, no project renderer) and on images the
project renders; files, the RANSAC support plane, segmentation, drawing and every input error."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from suctionbench.errors import InputError
from suctionbench.planning import (
    PlanConfig,
    camera_for_image,
    draw_grasp,
    plan_grasp,
    read_camera_pose,
    read_depth,
    read_mask,
)
from suctionbench.sensing.camera import PRIMESENSE, REALSENSE_D415

BOX = np.array([[-0.04, -0.03, 0.0], [0.04, 0.03, 0.06]])
"""Axis-aligned box on the table (world frame, metres): 8 x 6 x 6 cm."""


def tilted_pose(distance: float = 0.6, tilt_deg: float = 15.0, azimuth_deg: float = 30.0) -> np.ndarray:
    """World-from-camera (OpenCV frame) looking at the world origin from `distance`, tilted."""
    tilt, azimuth = math.radians(tilt_deg), math.radians(azimuth_deg)
    position = distance * np.array([math.sin(tilt) * math.cos(azimuth), math.sin(tilt) * math.sin(azimuth),
                                    math.cos(tilt)])
    z = -position / np.linalg.norm(position)
    x = np.cross(z, [0.0, 0.0, 1.0]) if tilt_deg else np.array([1.0, 0.0, 0.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([x, y, z])
    pose[:3, 3] = position
    return pose


def ray_cast_box(pose: np.ndarray, intrinsics=PRIMESENSE, box=BOX) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """z-depth image of the table z = 0 with `box` on it (slab-method ray casting in numpy), the
    box's pixels, and the box top's pixels."""
    v, u = np.mgrid[0:intrinsics.height, 0:intrinsics.width].astype(float)
    rays_cam = np.stack([(u - intrinsics.cx) / intrinsics.fx, (v - intrinsics.cy) / intrinsics.fy,
                         np.ones_like(u)], axis=-1)  # z component 1: t is the z-depth
    rays = rays_cam @ pose[:3, :3].T
    origin = pose[:3, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = (box[0] - origin) / rays
        t1 = (box[1] - origin) / rays
    t_near = np.nanmax(np.minimum(t0, t1), axis=-1)
    t_far = np.nanmin(np.maximum(t0, t1), axis=-1)
    on_box = (t_near <= t_far) & (t_far > 0)
    t_table = -origin[2] / rays[..., 2]
    depth = np.where(on_box, t_near, t_table)
    hit_z = origin[2] + depth * rays[..., 2]
    top = on_box & np.isclose(hit_z, box[1, 2], atol=1e-9)
    return depth.astype(np.float32), on_box, top


@pytest.fixture(scope="module")
def box_scene():
    pose = tilted_pose()
    depth, on_box, top = ray_cast_box(pose)
    return pose, depth, on_box, top


def test_box_on_a_plane_built_with_numpy_fitted_segmented_and_grasped_on_its_top(box_scene):
    pose, depth, on_box, top = box_scene
    noisy = depth + np.random.default_rng(0).normal(0.0, 0.001, depth.shape).astype(np.float32)  # 1 mm noise
    result = plan_grasp(noisy, "primesense", policy="planarity-centroid", seed=0)
    up_true = pose[2, :3]  # world z in the camera frame
    angle = math.degrees(math.acos(np.clip(result.plane.normal @ up_true, -1, 1)))
    assert angle < 0.3
    assert abs(result.plane.offset - (-pose[2, 3])) < 0.002  # plane 0.6 m x cos(0) along its normal
    mask = result.observation.mask
    assert (mask & ~on_box).sum() <= 0.01 * mask.sum()  # nothing but the box
    assert (top & ~mask).sum() <= 0.01 * top.sum()  # and all of its top
    a = result.action
    world = pose[:3, :3] @ a.point + pose[:3, 3]  # in the true world
    assert abs(world[2] - BOX[1, 2]) < 0.004  # on the top face
    assert np.all(np.abs(world[:2]) < 0.015)  # near its centre (planarity-centroid)
    # Near straight down: 1 mm of per-pixel noise tilts 1 px-smoothed normals by several degrees
    assert math.degrees(math.acos(-(pose[:3, :3] @ a.approach)[2])) < 15.0
    assert abs(a.point_world[2] - BOX[1, 2]) < 0.004  # the fitted plane's frame: the table is z = 0 too
    assert math.degrees(math.acos(-a.approach_world[2])) < 15.0
    out = result.to_dict()
    assert out["camera_pose"] == "fitted" and out["pixel"] == [float(a.pixel[0]), float(a.pixel[1])]
    assert set(out["timings"]) == {"plane", "segment", "plan", "total"}
    json.dumps(out)


def test_same_seed_same_grasp_and_a_given_pose_skips_the_fit(box_scene):
    pose, depth, _, top = box_scene
    first = plan_grasp(depth, PRIMESENSE, policy="centroid", seed=4)
    second = plan_grasp(depth, PRIMESENSE, policy="centroid", seed=4)
    np.testing.assert_array_equal(first.action.point, second.action.point)
    np.testing.assert_array_equal(first.observation.camera_pose, second.observation.camera_pose)
    given = plan_grasp(depth, PRIMESENSE, policy="centroid", camera_pose=pose, seed=4)
    assert given.plane is None and "plane" not in given.timings
    assert top[int(given.action.pixel[1]), int(given.action.pixel[0])]
    masked = plan_grasp(depth, PRIMESENSE, policy="centroid", mask=top, seed=4)
    assert np.array_equal(masked.observation.mask, top)


def test_object_choice_skips_regions_cut_by_the_image_border(box_scene):
    pose, depth, on_box, _ = box_scene
    cluttered = depth.copy()
    cluttered[:, :60] -= 0.1  # a wall along the left border, larger than the box
    result = plan_grasp(cluttered, PRIMESENSE, policy="centroid", seed=0)
    assert (result.observation.mask & on_box).sum() >= 0.95 * result.observation.mask.sum()
    everything = plan_grasp(cluttered, PRIMESENSE, policy="centroid", seed=0, config=PlanConfig(keep="all"))
    assert everything.observation.mask[:, :60].sum() > 0


def test_plane_only_and_no_plane_are_input_errors(box_scene):
    pose, _, _, _ = box_scene
    table, _, _ = ray_cast_box(pose, box=np.array([[5.0, 5.0, 0.0], [5.1, 5.1, 0.1]]))  # box out of view
    with pytest.raises(InputError, match="nothing stands"):
        plan_grasp(table, PRIMESENSE, policy="centroid")
    scatter = np.random.default_rng(1).uniform(0.4, 1.2, (480, 640)).astype(np.float32)
    with pytest.raises(InputError, match="plane"):
        plan_grasp(scatter, PRIMESENSE, policy="centroid")
    with pytest.raises(InputError, match="640 x 480"):
        plan_grasp(np.ones((100, 100), np.float32), PRIMESENSE, policy="centroid")
    with pytest.raises(InputError, match="unknown"):
        plan_grasp(table, "no-such-camera")
    with pytest.raises(InputError, match="unknown"):
        plan_grasp(table, PRIMESENSE, policy="no-such-policy")


def test_scaled_image_uses_scaled_intrinsics():
    half = camera_for_image(REALSENSE_D415, (360, 640))
    assert (half.width, half.height) == (640, 360) and math.isclose(half.fx, REALSENSE_D415.fx / 2)
    pose = tilted_pose(tilt_deg=10)
    depth, on_box, _ = ray_cast_box(pose, PRIMESENSE.scaled(0.5))
    result = plan_grasp(depth, "primesense", policy="centroid", seed=0)
    assert result.observation.intrinsics.width == 320
    assert on_box[int(result.action.pixel[1]), int(result.action.pixel[0])]


def test_depth_files_round_trip_and_refuse_what_is_not_depth(tmp_path, box_scene):
    _, depth, _, _ = box_scene
    np.save(tmp_path / "d.npy", depth)
    np.testing.assert_array_equal(read_depth(tmp_path / "d.npy"), depth)
    millimetres = np.round(depth * 1000).astype(np.uint16)
    Image.fromarray(millimetres).save(tmp_path / "d.png")
    assert Image.open(tmp_path / "d.png").mode.startswith("I")
    np.testing.assert_allclose(read_depth(tmp_path / "d.png"), millimetres / 1000.0, atol=1e-6)
    np.save(tmp_path / "mm.npy", millimetres)
    np.testing.assert_allclose(read_depth(tmp_path / "mm.npy"), millimetres / 1000.0, atol=1e-6)
    tenth_mm = np.round(depth * 10000).astype(np.uint16)  # 0.1 mm units, as some sensors store
    Image.fromarray(tenth_mm).save(tmp_path / "tenth.png")
    np.testing.assert_allclose(read_depth(tmp_path / "tenth.png", depth_scale=1e-4), tenth_mm * 1e-4, atol=1e-6)
    with_nan = depth.copy()
    with_nan[0, 0] = np.nan
    np.save(tmp_path / "nan.npy", with_nan)
    assert read_depth(tmp_path / "nan.npy")[0, 0] == 0.0  # NaN = no return
    np.save(tmp_path / "mm_float.npy", depth * 1000)
    with pytest.raises(InputError, match="--depth-scale 0.001"):
        read_depth(tmp_path / "mm_float.npy")
    Image.fromarray((depth * 100).astype(np.uint8)).save(tmp_path / "eight.png")
    with pytest.raises(InputError, match="holds no depth"):
        read_depth(tmp_path / "eight.png")
    np.save(tmp_path / "neg.npy", -depth)
    with pytest.raises(InputError, match="negative"):
        read_depth(tmp_path / "neg.npy")
    np.save(tmp_path / "rgb.npy", np.zeros((4, 4, 3), np.float32) + 0.5)
    with pytest.raises(InputError, match="one channel"):
        read_depth(tmp_path / "rgb.npy")
    (tmp_path / "d.exr").write_bytes(b"x")
    with pytest.raises(InputError, match="unknown format"):
        read_depth(tmp_path / "d.exr")
    with pytest.raises(InputError, match="not found"):
        read_depth(tmp_path / "missing.npy")
    with pytest.raises(InputError, match="positive"):
        read_depth(tmp_path / "d.npy", depth_scale=0.0)
    (tmp_path / "junk.png").write_bytes(b"not a png")
    with pytest.raises(InputError, match="not a readable image"):
        read_depth(tmp_path / "junk.png")


def test_mask_and_camera_pose_files(tmp_path, box_scene):
    pose, depth, on_box, _ = box_scene
    Image.fromarray(on_box.astype(np.uint8) * 255).save(tmp_path / "m.png")
    np.testing.assert_array_equal(read_mask(tmp_path / "m.png", depth.shape), on_box)
    np.save(tmp_path / "m.npy", on_box)
    np.testing.assert_array_equal(read_mask(tmp_path / "m.npy", depth.shape), on_box)
    with pytest.raises(InputError, match="shape"):
        read_mask(tmp_path / "m.npy", (10, 10))
    np.save(tmp_path / "empty.npy", np.zeros_like(on_box))
    with pytest.raises(InputError, match="no object pixel"):
        read_mask(tmp_path / "empty.npy", depth.shape)
    np.save(tmp_path / "p.npy", pose)
    (tmp_path / "p.json").write_text(json.dumps({"camera_pose": pose.tolist()}))
    np.savetxt(tmp_path / "p.txt", pose)
    for name in ("p.npy", "p.json", "p.txt"):
        np.testing.assert_allclose(read_camera_pose(tmp_path / name), pose)
    skew = pose.copy()
    skew[0, 0] = 2.0
    np.save(tmp_path / "skew.npy", skew)
    with pytest.raises(InputError, match="rotation"):
        read_camera_pose(tmp_path / "skew.npy")
    (tmp_path / "short.txt").write_text("1 2 3")
    with pytest.raises(InputError, match="4x4"):
        read_camera_pose(tmp_path / "short.txt")


def test_draw_grasp_marks_the_grasp(tmp_path, box_scene):
    _, depth, _, _ = box_scene
    result = plan_grasp(depth, PRIMESENSE, policy="planarity-centroid", seed=0)
    draw_grasp(result, tmp_path / "grasp.png")
    image = np.array(Image.open(tmp_path / "grasp.png"))
    assert image.shape == (480, 640, 3)
    u, v = (int(round(x)) for x in result.action.pixel)
    assert tuple(image[v, u]) == (40, 200, 60)  # q >= 0.5: a green dot on the grasp pixel
    assert (np.all(image == (40, 110, 255), axis=-1)).sum() > 50  # the object's outline


@pytest.mark.parametrize("key", ["basic/box_tea", "typical/mug_classic"])
def test_on_images_the_project_renders(key):
    from suctionbench.sim.pick import PickRequest, PickRunner

    runner = PickRunner(PickRequest(key, seed=2))
    runner.reset()
    obs = runner.observe()  # rendered with the simulated sensor's noise; the bin and robot in view
    result = plan_grasp(obs.depth, "primesense", policy="planarity-centroid", seed=0)
    angle = math.degrees(math.acos(np.clip(result.plane.normal @ obs.camera_pose[2, :3], -1, 1)))
    assert angle < 0.3
    mask, truth = result.observation.mask, obs.mask
    assert (mask & truth).sum() / (mask | truth).sum() > 0.9
    u, v = (int(round(x)) for x in result.action.pixel)
    assert truth[v, u]


def _last_json(output: str) -> dict:
    return json.loads(output.strip().splitlines()[-1])


def test_plan_command_prints_the_grasp_and_draws_it(tmp_path):
    from typer.testing import CliRunner

    from suctionbench.cli import app

    image = Path(__file__).resolve().parents[1] / "examples" / "scene_mug.png"
    out = tmp_path / "grasp.png"
    args = ["plan", "--depth", str(image), "--camera", "primesense", "--policy", "centroid",
            "--policy-arg", "num_candidates=50", "--out", str(out), "--seed", "3"]
    result = CliRunner().invoke(app, [*args, "--json"])
    assert result.exit_code == 0, result.output
    data = _last_json(result.stdout)
    assert data["ok"] and data["policy"] == "centroid(num_candidates=50)" and data["candidates"] == 50
    assert len(data["point"]) == 3 and abs(np.linalg.norm(data["approach"]) - 1) < 1e-5
    assert data["plane"]["inlier_fraction"] > 0.7 and data["camera_pose"] == "fitted"
    assert Image.open(out).size == (640, 480)
    again = _last_json(CliRunner().invoke(app, [*args, "--json"]).stdout)
    assert again["point"] == data["point"] and again["pixel"] == data["pixel"]  # --seed: same grasp
    human = CliRunner().invoke(app, args)
    assert human.exit_code == 0 and "approach (camera frame)" in human.stdout and "q = " in human.stdout


@pytest.mark.parametrize(("args", "message"), [
    (["--depth", "missing.npy", "--camera", "primesense"], "not found"),
    (["--depth", "EXAMPLE", "--camera", "kinect-9"], "unknown"),
    (["--depth", "EXAMPLE", "--camera", "primesense", "--policy-arg", "x"], "key=value"),
    (["--depth", "EXAMPLE", "--camera", "primesense", "--policy", "nowhere.py:make"], "not found"),
    (["--depth", "EXAMPLE", "--camera", "realsense-d435"], "give the camera's intrinsics"),
    (["--depth", "EXAMPLE", "--camera", "primesense", "--depth-scale", "-1"], "--depth-scale -1"),
])
def test_plan_command_bad_input_exits_2_with_one_line(args, message):
    from typer.testing import CliRunner

    from suctionbench.cli import app

    image = str(Path(__file__).resolve().parents[1] / "examples" / "scene_mug.png")
    result = CliRunner().invoke(app, ["plan", *[image if a == "EXAMPLE" else a for a in args], "--json"])
    assert result.exit_code == 2, result.output
    data = _last_json(result.stdout)
    assert not data["ok"] and message in data["error"] and "\n" not in data["error"]


class _RecordingPolicy:
    """Plans planarity-centroid's grasp and notes in its info the camera pose it was given."""

    def __init__(self) -> None:
        from suctionbench.policies.plugins import load_policy

        self.inner = load_policy("planarity-centroid", {})

    def plan(self, observation, rng):
        action = self.inner.plan(observation, rng)
        action.info["given_camera_pose"] = np.array(observation.camera_pose)
        return action


def recording_policy() -> _RecordingPolicy:
    return _RecordingPolicy()


def test_a_table_height_in_the_given_world_is_where_the_policy_sees_the_table(box_scene):
    # The same image and camera, its pose given in a world whose table top is at z = 0.75 m (a
    # robot's base frame): the policy must be given the table at z = 0 (the policies' samplers
    # and the object context measure heights above z = 0), so it plans the same grasp, and the
    # grasp is reported in the given world: 0.75 m higher.
    pose, depth, _, _ = box_scene
    raised = pose.copy()
    raised[2, 3] += 0.75
    policy = f"{Path(__file__).resolve()}:recording_policy"
    low = plan_grasp(depth, PRIMESENSE, policy=policy, camera_pose=pose, seed=2)
    high = plan_grasp(depth, PRIMESENSE, policy=policy, camera_pose=raised, table_height=0.75, seed=2)
    seen = [result.action.info["given_camera_pose"] for result in (low, high)]
    np.testing.assert_allclose(seen[1], seen[0], atol=1e-12)  # the table at z = 0 both times
    np.testing.assert_array_equal(high.action.point, low.action.point)
    assert high.action.q == low.action.q
    np.testing.assert_allclose(high.action.point_world, low.action.point_world + [0.0, 0.0, 0.75], atol=1e-12)
    np.testing.assert_array_equal(high.observation.camera_pose, raised)
    np.testing.assert_array_equal(high.observation.mask, low.observation.mask)
