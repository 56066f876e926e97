"""The benchmark end to end: eval -> MCAP logs -> table; one real pick per policy; bad input."""

from __future__ import annotations

import json
from collections import Counter

import pytest
from typer.testing import CliRunner

from suctionbench.cli import app
from suctionbench.evaluation.report import build_report
from suctionbench.evaluation.runner import plan_trials
from suctionbench.evaluation.tasks import load_task
from suctionbench.policies.gqcnn import DEFAULT_MODEL
from suctionbench.runlog.reader import read_run
from suctionbench.sim.episode_config import FAILURES

POLICIES = ["random", "centroid", "planarity", "planarity-centroid", "gqcnn", "fc-gqcnn", "gqcnn-adv", "fc-gqcnn-adv",
            "analytic", "analytic-image", "analytic-image-uniform", "random-surface"]
"""Every built-in policy: CI's one real pick each (`test_smoke_list_covers_every_policy` keeps it complete)."""


def last_json(result):
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_smoke_eval_end_to_end_from_the_logs(tmp_path):
    result = CliRunner().invoke(app, ["eval", "--policy", "gqcnn", "--task", "smoke", "--workers", "1",
                                      "--out", str(tmp_path / "run"), "--json"])
    assert result.exit_code == 0, result.output
    summary = last_json(result)
    assert summary["trials"] == 3 and summary["invalid"] == 0
    logs = read_run(tmp_path / "run" / "trials")
    assert len(logs) == 3 and all(log["result"] is not None for log in logs)
    for log in logs:  # every log holds the observation, the candidates and the state stream
        for topic in ("/camera/depth", "/grasps/candidates", "/tf", "/suction", "/result"):
            assert log["topics"].get(topic, 0) >= 1, topic
        assert log["metadata"]["policy"] == "gqcnn"
    # the table is the logs' results: counted here straight from the re-read result records
    results = [log["result"] for log in logs]
    assert summary["success_rate"] == pytest.approx(sum(r["success"] for r in results) / len(results), abs=1e-4)
    assert summary["outcomes"] == dict(Counter(r["failure"] or "success" for r in results))
    # the run names the model it planned with, though none was given: the default changes between
    # releases, and a report of the run says which one it was
    run = json.loads((tmp_path / "run" / "run.json").read_text())
    assert run["model"] is None and run["model_used"] == "assets/" + "/".join(DEFAULT_MODEL)
    # and the policy's config it planned with, defaults included: a default seed cone or normal
    # smoothing that changes later leaves this run readable
    from suctionbench.config import to_dict
    from suctionbench.policies.gqcnn import CEMConfig

    assert run["policy_config"] == to_dict(CEMConfig())
    build_report([tmp_path / "run"], tmp_path / "report")
    assert f"model {run['model_used']};" in (tmp_path / "report" / "report.md").read_text()


def test_trials_are_identical_across_policies():
    task = load_task("basic")
    a = plan_trials(task, "gqcnn", model=None, trials=30, seed=None)
    b = plan_trials(task, "centroid", model=None, trials=30, seed=None)
    assert [(t.object_key, t.seed) for t in a] == [(t.object_key, t.seed) for t in b]
    assert len({t.object_key for t in a}) == 25  # every object of the set appears


def test_smoke_list_covers_every_policy():
    from suctionbench.policies.base import POLICIES as IMAGE_POLICIES
    from suctionbench.sim.pick import KNOWN_STATE_POLICIES

    assert set(POLICIES) == set(IMAGE_POLICIES) | set(KNOWN_STATE_POLICIES)


@pytest.mark.parametrize("policy", POLICIES)
def test_one_real_pick_per_policy(policy):
    from suctionbench.sim.pick import PickRequest, PickRunner

    result = PickRunner(PickRequest("basic/box_tea", policy=policy, seed=3)).run()
    assert result["valid"], result
    assert result["failure"] is None or result["failure"] in FAILURES


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--policy", "nope", "--set", "basic"], "nope"),
        (["--policy", "centroid", "--set", "no_such_set"], "no_such_set"),
        (["--policy", "centroid", "--task", "no_such_task"], "no_such_task"),
        (["--policy", "gqcnn", "--set", "basic", "--model", "/no/such/model"], "model"),
        (["--policy", "gqcnn-adv", "--set", "basic", "--model", "assets/models/gqcnn-context"], "reads no model"),
        (["--policy", "fc-gqcnn-adv", "--set", "basic", "--model", "assets/models/gqcnn-context"], "reads no model"),
        (["--policy", "planarity", "--set", "basic", "--model", "assets/models/gqcnn-context"], "reads no model"),
        (["--policy", "centroid"], "--set"),
        (["--policy", "centroid", "--set", "basic", "--engine", "spark"], "spark"),
        (["--policy", "centroid", "--set", "basic", "--cup", "huge"], "huge"),
        (["--policy", "analytic", "--set", "basic", "--metric", "nope"], "nope"),
        (["--policy", "analytic-image", "--task", "bin-basic"], "single-object"),
    ],
)
def test_eval_bad_input_exits_2(tmp_path, args, needle):
    result = CliRunner().invoke(app, ["eval", *args, "--trials", "1", "--out", str(tmp_path / "r"), "--json"])
    assert result.exit_code == 2, result.output
    assert needle in last_json(result)["error"]
    assert not (tmp_path / "r").exists()  # nothing half-written


def test_eval_unwritable_output_exits_2():
    result = CliRunner().invoke(app, ["eval", "--policy", "centroid", "--set", "basic", "--trials", "1",
                                      "--out", "/proc/no/such/dir", "--json"])
    assert result.exit_code == 2 and "cannot create" in last_json(result)["error"]



def test_a_policy_that_finds_no_grasp_fails_the_trial_without_executing(tmp_path, monkeypatch):
    # An observation with no object pixel (as when the object lies out of view): the policy raises
    # NoGraspError; the trial is a valid failure "no_grasp", logged, and the run's table counts it.
    from suctionbench.evaluation.runner import trial_metrics
    from suctionbench.sim.pick import PickRequest, PickRunner

    real_observe = PickRunner.observe

    def empty_view(self):
        observation = real_observe(self)
        observation.mask[:] = False
        return observation

    monkeypatch.setattr(PickRunner, "observe", empty_view)
    log = tmp_path / "trial.mcap"
    result = PickRunner(PickRequest("basic/box_tea", policy="centroid", seed=3)).run(log=log)
    assert result["valid"] and not result["success"] and result["failure"] == "no_grasp"
    assert result["grasp_world"] is None and result["sim_time"] == 0.0 and "no object pixel" in result["detail"]
    assert read_run(tmp_path)[0]["result"]["failure"] == "no_grasp"
    table = trial_metrics([result])
    assert table["success_rate"] == 0.0 and table["outcomes"] == {"no_grasp": 1} and table["label_precision"] is None
