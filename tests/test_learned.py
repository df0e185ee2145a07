"""The RNN look-ahead, Algorithm 1 and the learned planners (issue 4), on untrained models."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from serial_survival import survival_steps

from husky_course.config import get_profile
from husky_course.data.dataset import load_dataset
from husky_course.data.labels import primitive_outcomes, survival_steps_parallel
from husky_course.evaluation.horizons import horizon_errors
from husky_course.models.rnn import RNNLookahead
from husky_course.models.safety import JointModel, SurvivalNet
from husky_course.planners.base import PlannerError
from husky_course.planners.learned import (
    DistilledPlanner,
    LookaheadPlanner,
    RNNPlanner,
    algorithm1,
    algorithm1_reference,
)
from husky_course.planners.registry import make_planner
from husky_course.training.datasets import sequence_data
from husky_course.training.inference import loop_predictions, rnn_predictions

QUICK = get_profile("quick")  # resolved once, passed down


@pytest.fixture(scope="module")
def joint():
    torch.manual_seed(0)
    return JointModel().eval()


@pytest.fixture(scope="module")
def rnn():
    torch.manual_seed(0)
    return RNNLookahead().eval()


def _obs(seed: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(0, 1, (50, 50)).astype(np.float32)


@pytest.mark.parametrize("reward", ["applied", "next_image"])
@pytest.mark.parametrize("look_ahead", [0, 1, 3])
def test_batched_algorithm1_matches_the_line_by_line_reference(joint, reward, look_ahead):
    for seed in range(3):
        obs = _obs(seed)
        fast = algorithm1(joint, obs, look_ahead, reward)
        slow = algorithm1_reference(joint, obs, look_ahead, reward)
        np.testing.assert_allclose(fast, slow, rtol=1e-5, atol=1e-6)
        assert int(np.argmin(fast)) == int(np.argmin(slow))


def test_learned_planners_return_valid_indices(joint, rnn):
    torch.manual_seed(0)
    planners = [
        LookaheadPlanner(joint, 0),
        LookaheadPlanner(joint, 2, reward="next_image"),
        RNNPlanner(rnn, 1),
        RNNPlanner(rnn, 3, samples=50),
        DistilledPlanner(SurvivalNet()),
    ]
    for planner in planners:
        for seed in range(3):
            a = planner.act(_obs(seed))
            assert isinstance(a, int) and 0 <= a < 25
            assert planner.last_scores is not None and planner.last_scores.shape == (25,)
            assert a == int(np.argmin(planner.last_scores))


def test_learned_planner_bad_inputs(joint, rnn, tmp_path, monkeypatch):
    with pytest.raises(PlannerError, match="look_ahead"):
        LookaheadPlanner(joint, -1)
    with pytest.raises(PlannerError, match="reward"):
        LookaheadPlanner(joint, 1, reward="bogus")
    with pytest.raises(ValueError, match="shape"):
        LookaheadPlanner(joint, 1).act(np.zeros((40, 40), np.float32))
    with pytest.raises(ValueError, match="NaN"):
        RNNPlanner(rnn, 1).act(np.full((50, 50), np.nan, np.float32))
    monkeypatch.setenv("HUSKY_ARTIFACTS", str(tmp_path))  # an empty store: no checkpoints
    (tmp_path / "quick").mkdir()
    for name in ("lookahead", "rnn", "distilled"):
        with pytest.raises(PlannerError, match="no trained"):
            make_planner(name, look_ahead=1, profile=QUICK)


def test_rnn_rollout_shapes_and_sequence_masks(rnn, small_dataset_dir):
    ds = load_dataset(small_dataset_dir)
    idx = np.arange(len(ds))
    data = sequence_data(ds, idx, horizon=4)
    lm, nm = data["label_mask"].numpy(), data["next_mask"].numpy()
    # step 0 always exists; a step's label is the pool label of that image, same video only
    assert lm[:, 0].all()
    np.testing.assert_array_equal(data["labels"][:, 0].numpy(), ds.labels)
    for i in (0, 7, len(ds) - 1):
        for k in range(4):
            j = i + k
            same = j < len(ds) and ds.episode[j] == ds.episode[i]
            assert lm[i, k] == same
            if nm[i, k]:
                assert (
                    ds.labels[j] == 0
                    and data["next_idx"][i, k] == j + 1
                    and ds.episode[j + 1] == ds.episode[i]
                )
    images = torch.from_numpy(np.asarray(ds.images[:6])).float()
    prims = data["prims"][:6]
    img, col = rnn_predictions(rnn, images, prims)
    assert img.shape == (6, 4, 50, 50) and col.shape == (6, 4)
    assert ((col >= 0) & (col <= 1)).all()
    torch.manual_seed(0)
    img2, col2 = loop_predictions(JointModel(), images, prims)
    assert img2.shape == img.shape and col2.shape == col.shape
    errs = horizon_errors(lambda i, p: rnn_predictions(rnn, i, p), ds, idx[:200], horizon=3)
    assert errs["mae"].shape == (3,) and errs["n"][0] >= errs["n"][1] >= errs["n"][2]


def test_survival_labels_agree_with_one_step_outcomes(small_dataset_dir):
    ds = load_dataset(small_dataset_dir)
    idx = np.arange(0, len(ds), 7)[:40]
    surv = survival_steps(ds, 2, idx)
    safe = ~primitive_outcomes(ds, idx)
    np.testing.assert_array_equal(surv >= 1, safe)  # survives a step iff the primitive is safe
    assert surv.max() <= 2
    np.testing.assert_array_equal(survival_steps_parallel(ds, 2, idx, workers=2, progress=False), surv)


def test_exercise_checks(small_dataset_dir):
    from husky_course.course import exercises
    from husky_course.course.diagnosis import shifted_labels
    from husky_course.evaluation.horizons import horizon_errors
    from husky_course.training.inference import rnn_predictions

    ds = load_dataset(small_dataset_dir)
    assert exercises.check_shifted_labels(ds, shifted_labels(ds))
    with pytest.raises(AssertionError, match="differ"):
        exercises.check_shifted_labels(ds, ds.labels)  # the un-shifted labels are not the slip
    torch.manual_seed(0)
    model = RNNLookahead().eval()
    n = horizon_errors(lambda i, p: rnn_predictions(model, i, p), ds, np.arange(len(ds)), horizon=4)["n"]
    assert exercises.check_pairs_per_horizon(ds.lengths, n.astype(int))
    with pytest.raises(AssertionError):
        exercises.check_pairs_per_horizon(ds.lengths, n.astype(int) + 1)
    assert exercises.worlds_for_certificate(0.01) == 299
    assert exercises.check_worlds_for_certificate(299)
    with pytest.raises(AssertionError, match="too few"):
        exercises.check_worlds_for_certificate(298)
