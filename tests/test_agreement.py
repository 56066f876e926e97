"""The agreement study (suctionbench.evaluation.agreement): its figures from hand-made trials, its
cause classification, and one real seeded trial end to end."""

import math

import pytest

from suctionbench.evaluation.agreement import lift_cause, run_agreement, seal_cause, summarize


def _row(label_seal, sim_seal, rwr, success, *, wr=True, tilt=5.0, torque_ratio=0.5, failure=None):
    return {"set": "basic", "object": "basic/x", "seed": 0, "label_seal": label_seal, "label_wr": wr,
            "label_rwr": rwr, "sim_seal": sim_seal, "success": success, "valid": True,
            "failure": failure if not success else None, "approach_tilt_deg": tilt, "torque_ratio": torque_ratio}


def test_summary_counts_match_hand_computed_confusion():
    rows = [
        _row(True, True, 0.9, True),  # agree on both
        _row(True, True, 0.8, False, failure="seal_lost_lift"),  # false positive
        _row(False, True, 0.1, True, wr=False),  # seal disagreement and false negative
        _row(False, False, 0.0, False, failure="no_seal"),  # agree
        {**_row(True, False, 0.9, False), "failure": "unreachable"},  # never executed: left out
    ]
    out = summarize(rows, threshold=0.5, tolerance_deg=21.8)
    assert out["executed"] == 4 and out["not_executed"] == {"unreachable": 1}
    assert out["seal_agreement"] == 0.75  # 3 of 4 executed trials agree on the seal
    assert out["lift_confusion"] == {"label_pos_sim_success": 1, "label_pos_sim_fail": 1,
                                     "label_neg_sim_success": 1, "label_neg_sim_fail": 1}
    assert out["precision"] == 0.5 and out["recall"] == 0.5 and out["accuracy"] == 0.5
    assert out["lift_disagreements"] == {"labeller robust, sim fails: seal_lost_lift": 1,
                                         "sim succeeds, labeller: no seal": 1}


def test_causes_follow_the_cup_limits():
    # An approach tilted beyond 80 % of the tolerance is blamed on the tilt, a flatter one on the lip contact.
    assert "tilt tolerance" in seal_cause(_row(True, False, 0.0, False, tilt=20.0), 21.8)
    assert "lip contact" in seal_cause(_row(True, False, 0.0, False, tilt=3.0), 21.8)
    assert seal_cause(_row(True, True, 0.9, True), 21.8) is None
    # The labeller's lip would seal, but the press pushes the object away (contact/press.py).
    assert "pushed away" in seal_cause({**_row(False, True, 0.0, False), "label_seal_failure": "pushed_away"}, 21.8)
    # The sim held a grasp whose gravity torque exceeds r (V - m g) / 2: the sim holds more torque.
    assert "peel limit" in lift_cause(_row(True, True, 0.0, True, wr=False, torque_ratio=1.4), 0.5)
    assert "perturbation" in lift_cause(_row(True, True, 0.3, True, wr=True, torque_ratio=0.5), 0.5)
    assert lift_cause(_row(True, True, 0.9, True), 0.5) is None


def test_real_trials_are_seeded_and_classified():
    first = run_agreement(sets=("basic",), trials=2, seed=3)
    again = run_agreement(sets=("basic",), trials=2, seed=3)
    assert first["per_trial"] == again["per_trial"]  # same seed, same trials
    assert math.isclose(first["approach_tolerance_deg"], 21.8, abs_tol=0.01)
    for row in first["per_trial"]:
        assert row["set"] == "basic" and isinstance(row["success"], bool)


def test_bad_arguments_are_rejected():
    from suctionbench.errors import InputError

    with pytest.raises(InputError):
        run_agreement(sets=("basic",), trials=0)
    with pytest.raises(InputError):
        run_agreement(sets=("basic",), trials=5, threshold=float("nan"))
