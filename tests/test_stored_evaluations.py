"""Evaluations kept in the artifact store (husky_course.evaluation.stored)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from husky_course.config import get_profile
from husky_course.data import code
from husky_course.data.store import ARTIFACTS_ENV
from husky_course.evaluation import stored
from husky_course.evaluation.episodes import evaluate
from husky_course.models.paper import Encoder
from husky_course.planners.registry import make_planner

PROFILE = get_profile("quick")


@pytest.fixture(autouse=True)
def _store(tmp_path, monkeypatch):
    monkeypatch.setenv(ARTIFACTS_ENV, str(tmp_path))


def _same(a, b):
    assert a.to_json() == b.to_json()
    assert len(a.episodes) == len(b.episodes) > 0
    for x, y in zip(a.episodes, b.episodes, strict=True):
        assert (x.world_seed, x.actions, x.collided, x.success, x.n_prims) == \
            (y.world_seed, y.actions, y.collided, y.success, y.n_prims)
        np.testing.assert_array_equal(x.poses, y.poses)
        np.testing.assert_array_equal(x.path, y.path)
        assert x.decision_times == y.decision_times and x.reset_time == y.reset_time


def test_a_second_run_is_read_back_whole(monkeypatch):
    first = stored.evaluate_stored(make_planner("heuristic"), 4, 1, PROFILE, progress=False)
    # the stored run is the library's run (timings aside)
    fresh = evaluate(make_planner("heuristic"), 4, 1, config=PROFILE.sim, progress=False)
    assert [e.actions for e in fresh.episodes] == [e.actions for e in first.episodes]

    def no_run(*args, **kwargs):
        raise AssertionError("the stored run should have been read back")

    monkeypatch.setattr(stored, "evaluate", no_run)
    again = stored.evaluate_stored(make_planner("heuristic"), 4, 1, PROFILE, progress=False)
    _same(first, again)
    with pytest.raises(AssertionError, match="read back"):  # other worlds: a new run
        stored.evaluate_stored(make_planner("heuristic"), 4, 2, PROFILE, progress=False)


def test_the_key_follows_the_planner_state_and_the_worlds():
    path = stored.evaluation_path
    base = path(make_planner("heuristic"), 4, 1, PROFILE, PROFILE.sim)
    assert base == path(make_planner("heuristic"), 4, 1, PROFILE, PROFILE.sim)
    assert base != path(make_planner("heuristic", depth=1), 4, 1, PROFILE, PROFILE.sim)
    assert base != path(make_planner("heuristic"), 5, 1, PROFILE, PROFILE.sim)
    assert base != path(make_planner("heuristic"), 4, 1, PROFILE, PROFILE.sim, max_primitives=3)
    assert base != path(make_planner("mapping"), 4, 1, PROFILE, PROFILE.sim)


def test_network_weights_are_part_of_the_key():
    torch.manual_seed(0)
    enc = Encoder(PROFILE.dims)
    a = stored.planner_fingerprint(enc)  # type: ignore[arg-type]
    with torch.no_grad():
        next(enc.parameters()).view(-1)[0] += 1e-6
    assert stored.planner_fingerprint(enc) != a  # type: ignore[arg-type]


def test_an_unknown_attribute_means_no_store(monkeypatch):
    planner = make_planner("heuristic")
    planner.callback = lambda x: x  # a function's behaviour cannot be hashed
    with pytest.raises(stored.Unfingerprintable):
        stored.planner_fingerprint(planner)
    result = stored.evaluate_stored(planner, 2, 1, PROFILE, progress=False)
    assert result.worlds == 2
    assert not list((stored.artifacts_root() / "quick").rglob("*.npz"))


def test_a_stored_run_records_its_code_and_goes_stale_when_that_code_changes(monkeypatch):
    planner = make_planner("heuristic")
    path = stored.evaluation_path(planner, 2, 1, PROFILE, PROFILE.sim)
    stored.evaluate_stored(make_planner("heuristic"), 2, 1, PROFILE, progress=False)
    assert path.is_file()
    fingerprint, modules = stored.evaluation_code(planner)
    assert type(planner).__module__ in modules and "husky_course.evaluation.episodes" in modules
    assert "husky_course.training.builders" not in code.closure(*modules)  # training edits keep it
    assert not stored.stale_evaluation(path)
    monkeypatch.setattr(stored, "code_fingerprint", lambda *modules: "other code")
    assert stored.stale_evaluation(path)
    assert stored.evaluation_path(planner, 2, 1, PROFILE, PROFILE.sim) != path  # and is run again


def test_a_run_without_recorded_code_is_stale(tmp_path):
    (tmp_path / "old.npz").write_bytes(b"")
    assert stored.stale_evaluation(tmp_path / "old.npz")
