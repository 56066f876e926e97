"""User policies (`--policy PATH.py:FACTORY`, `package.module:FACTORY`, entry-point plug-ins and
`--policy-arg`), and the deterministic picks-per-hour cycle that names them in run tables."""

from __future__ import annotations

import importlib
import json
import math
import textwrap

import numpy as np
import pytest

from suctionbench.errors import InputError
from suctionbench.evaluation.cycle import CYCLE_MODEL, PLANNING_S, SENSOR_FRAME_S
from suctionbench.evaluation.runner import trial_metrics
from suctionbench.policies.base import GraspAction, Observation, make_policy
from suctionbench.policies.heuristics import CentroidPolicy
from suctionbench.policies.plugins import (
    ENTRY_POINT_GROUP,
    PluginPolicy,
    canonical_spec,
    known_policies,
    load_policy,
    parse_policy_args,
    policy_label,
)
from suctionbench.sensing.camera import PRIMESENSE

POLICY_FILE = '''
import numpy as np
from suctionbench.policies.base import GraspAction, SamplerConfig, scene_cloud

class Fixed:
    name = "fixed"
    def __init__(self, q=0.5, column=None):
        self.q, self.column = q, column
    def plan(self, observation, rng):
        cloud = scene_cloud(observation, SamplerConfig())
        rows, cols = np.nonzero(cloud.valid)
        k = int(rng.integers(len(rows)))
        pixels, points, approaches = cloud.grasps_at(rows[k:k + 1], cols[k:k + 1])
        return GraspAction(point=points[0], approach=2.0 * approaches[0], pixel=pixels[0], q=self.q,
                           camera_pose=observation.camera_pose)

def make(q=0.5, column=None):
    return Fixed(q=q, column=column)

def no_plan():
    return object()

class BadSignature:
    def plan(self):
        return None

def bad_signature():
    return BadSignature()

def raises():
    raise ValueError("no licence key")

class WrongReturn:
    def plan(self, observation, rng):
        return (0.0, 0.0, 0.5)

def wrong_return():
    return WrongReturn()

NOT_CALLABLE = 3
'''


def box_on_table(box_height: float = 0.05, half: int = 40) -> Observation:
    """A PrimeSense camera 0.6 m straight above the table (z = 0) and a box's flat top, in numpy."""
    depth = np.full((PRIMESENSE.height, PRIMESENSE.width), 0.6, dtype=np.float32)
    depth[240 - half:240 + half, 320 - half:320 + half] = 0.6 - box_height
    pose = np.eye(4)
    pose[:3, :3] = np.diag([1.0, -1.0, -1.0])  # OpenCV optical frame looking down (world -z)
    pose[:3, 3] = [0.0, 0.0, 0.6]
    return Observation(depth=depth, intrinsics=PRIMESENSE, camera_pose=pose)


@pytest.fixture()
def policy_file(tmp_path):
    path = tmp_path / "my_policy.py"
    path.write_text(textwrap.dedent(POLICY_FILE))
    return path


def test_parse_policy_args_reads_toml_values_and_keeps_other_text():
    args = parse_policy_args(["n=3", "scale=0.5", "flag=true", 'name="x y"', "model=runs/m1", "ids=[1, 2]"])
    assert args == {"n": 3, "scale": 0.5, "flag": True, "name": "x y", "model": "runs/m1", "ids": [1, 2]}
    assert isinstance(args["n"], int)
    for bad, message in (("novalue", "key=value"), ("1x=2", "key=value"), ("=3", "key=value")):
        with pytest.raises(InputError, match=message):
            parse_policy_args([bad])
    with pytest.raises(InputError, match="twice"):
        parse_policy_args(["a=1", "a=2"])


def test_file_policy_is_loaded_with_options_wrapped_and_checked(policy_file):
    spec = f"{policy_file}:make"
    policy = make_policy(spec, q=0.25)
    assert isinstance(policy, PluginPolicy) and policy.name == "fixed"
    action = policy.plan(box_on_table(), np.random.default_rng(0))
    assert isinstance(action, GraspAction) and action.q == 0.25
    np.testing.assert_allclose(np.linalg.norm(action.approach), 1.0)  # the plug-in returned 2x a unit vector
    np.testing.assert_allclose(action.point[2], 0.55, atol=1e-6)  # on the box top
    np.testing.assert_allclose(action.approach_world, [0, 0, -1], atol=1e-6)  # straight down
    again = make_policy(spec, q=0.25).plan(box_on_table(), np.random.default_rng(0))
    np.testing.assert_array_equal(action.point, again.point)  # same rng, same grasp
    assert canonical_spec(spec) == spec  # already absolute


def test_relative_file_spec_becomes_absolute_for_workers(policy_file, monkeypatch):
    monkeypatch.chdir(policy_file.parent)
    assert canonical_spec("my_policy.py:make") == f"{policy_file}:make"
    assert canonical_spec(" Planarity-Centroid ") == "planarity-centroid"
    assert canonical_spec("gqcnn-cem") == "gqcnn"
    label = policy_label("examples/p.py:make", {"band": 0.02, "mode": "top"})
    assert label == "examples/p.py:make(band=0.02, mode='top')"
    assert policy_label("gqcnn") == "gqcnn"


@pytest.mark.parametrize(("factory", "message"), [
    ("missing", "no factory 'missing'.*callables there: .*make"),
    ("no_plan", "no plan\\(observation, rng\\) method"),
    ("bad_signature", "cannot be called as plan\\(observation, rng\\)"),
    ("raises", "factory raised ValueError: no licence key"),
    ("NOT_CALLABLE", "not callable"),
])
def test_file_policy_errors_are_input_errors(policy_file, factory, message):
    with pytest.raises(InputError, match=message):
        make_policy(f"{policy_file}:{factory}")


def test_other_spec_errors_are_input_errors(policy_file, tmp_path):
    with pytest.raises(InputError, match="bad options"):
        make_policy(f"{policy_file}:make", nonsense=1)
    with pytest.raises(InputError, match="not found"):
        make_policy(f"{tmp_path / 'nowhere.py'}:make")
    broken = tmp_path / "broken.py"
    broken.write_text("def make(:\n")
    with pytest.raises(InputError, match="SyntaxError"):
        make_policy(f"{broken}:make")
    with pytest.raises(InputError, match="no module named 'no_such_package'"):
        make_policy("no_such_package.policies:make")
    with pytest.raises(InputError, match="not a Python identifier"):
        make_policy(f"{policy_file}:make-it")
    with pytest.raises(InputError, match="unknown"):
        make_policy("no-such-policy")
    wrong = make_policy(f"{policy_file}:wrong_return")
    with pytest.raises(InputError, match="returned tuple, expected"):
        wrong.plan(box_on_table(), np.random.default_rng(0))


def test_module_spec_loads_an_importable_factory():
    policy = load_policy("suctionbench.policies.heuristics:CentroidPolicy", {"num_candidates": 20})
    assert isinstance(policy, PluginPolicy) and isinstance(policy.inner, CentroidPolicy)
    assert policy.inner.config.num_candidates == 20
    action = policy.plan(box_on_table(), np.random.default_rng(1))
    assert action.info["chosen"] == int(np.argmax(action.candidates["q"]))
    assert isinstance(make_policy("centroid"), CentroidPolicy)  # built-ins are not wrapped


def test_entry_point_plugin_is_found_by_name(tmp_path, monkeypatch):
    # A distribution installed the ordinary way: a module and a dist-info with entry_points.txt.
    (tmp_path / "sb_demo_plugin.py").write_text(textwrap.dedent(POLICY_FILE))
    info = tmp_path / "sb_demo_plugin-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: sb-demo-plugin\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[{ENTRY_POINT_GROUP}]\nfixed-q = sb_demo_plugin:make\n"
                                           "centroid = sb_demo_plugin:make\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.invalidate_caches()
    assert "fixed-q" in known_policies()
    policy = make_policy("fixed-q", q=0.75)
    assert isinstance(policy, PluginPolicy)
    assert policy.plan(box_on_table(), np.random.default_rng(0)).q == 0.75
    assert isinstance(make_policy("centroid"), CentroidPolicy)  # a plug-in cannot shadow a built-in


def _record(success: bool, sim_time: float, sensing: float, plan: float) -> dict:
    return {"valid": True, "success": success, "policy_q": 0.5, "label_rwr": 0.6, "sim_time": sim_time,
            "sensing_time": sensing, "plan_time": plan, "failure": None if success else "no_seal",
            "object": "basic/a", "label_scores": None}


def test_picks_per_hour_is_deterministic_and_wall_time_reported_beside_it():
    compute = CYCLE_MODEL.compute_time("gqcnn")
    assert compute == {"sensing_s": SENSOR_FRAME_S, "planning_s": PLANNING_S["gqcnn"]}
    assert CYCLE_MODEL.compute_time("/x/p.py:make")["planning_s"] == PLANNING_S["gqcnn"]
    assert CYCLE_MODEL.compute_time("analytic") == {"sensing_s": 0.0, "planning_s": 0.0}
    # the ADV model's policies run their base policy's search on the same network: its time
    assert CYCLE_MODEL.compute_time("gqcnn-adv") == compute
    assert CYCLE_MODEL.compute_time("fc-gqcnn-adv")["planning_s"] == PLANNING_S["fc-gqcnn"]
    fast = [_record(True, 4.0, 0.1, 0.1), _record(False, 5.0, 0.2, 0.3)]
    slow = [_record(True, 4.0, 0.9, 1.7), _record(False, 5.0, 0.5, 2.3)]  # same trials, a busier machine
    a, b = trial_metrics(fast, compute), trial_metrics(slow, compute)
    cycle = 4.5 + SENSOR_FRAME_S + PLANNING_S["gqcnn"]
    assert a["mean_cycle_s"] == b["mean_cycle_s"] == round(cycle, 3)
    assert a["picks_per_hour"] == b["picks_per_hour"] == round(3600 * 0.5 / cycle, 1)
    assert math.isclose(a["picks_per_hour_wall"], 3600 * 0.5 / (4.5 + 0.15 + 0.2), abs_tol=0.05)
    assert b["picks_per_hour_wall"] < a["picks_per_hour_wall"]


def test_eval_runs_a_file_policy_with_options_in_worker_processes(policy_file, tmp_path):
    from suctionbench.evaluation.runner import run_eval, run_records
    from suctionbench.evaluation.tasks import Task
    from suctionbench.runlog.reader import read_run

    out = tmp_path / "run"
    summary = run_eval(Task(name="basic", set="basic", trials=2), f"{policy_file}:make", out, workers=2,
                       policy_args={"q": 0.125}, command="suctionbench eval ...")
    assert summary["label"] == f"{policy_file}:make(q=0.125)" and summary["trials"] == 2
    records = run_records(out)
    assert [r["policy_q"] for r in records] == [0.125, 0.125]  # the option reached every worker
    run = json.loads((out / "run.json").read_text())
    assert run["policy_spec"] == f"{policy_file}:make" and run["policy_args"] == {"q": 0.125}
    assert run["command"] == "suctionbench eval ..." and run["versions"]["mujoco"]
    metadata = read_run(out / "trials")[0]["metadata"]
    assert f"{policy_file}:make" in json.dumps(metadata)
