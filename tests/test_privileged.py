"""Privileged information goes only where it belongs: the oracle. Every other planner gets images,
the primitives it applied and its own primitive library, nothing else."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from husky_course.evaluation.episodes import eval_world_seeds, run_episode
from husky_course.models.discs import DiscNet
from husky_course.models.rnn import RNNLookahead
from husky_course.models.safety import JointModel, SurvivalNet
from husky_course.planners import base, classic, learned, oracle, reference
from husky_course.planners.base import EpisodeStart, Planner, episode_key
from husky_course.planners.discs import DiscPlanner
from husky_course.planners.registry import PLANNERS, REFERENCE_PLANNERS, make_planner
from husky_course.sim.backends import make_simulator


class Spy(Planner):
    """Records everything it is handed."""

    name = "spy"

    def __init__(self, privileged: bool) -> None:
        super().__init__()
        self.privileged = privileged
        self.starts: list[EpisodeStart] = []
        self.poses: list = []
        self.observed: list = []

    def reset(self, start):
        self.starts.append(start)

    def act(self, obs, pose=None):
        self.poses.append(pose)
        return 12

    def observe(self, action, obs_next):
        self.observed.append(action)


@pytest.fixture(scope="module")
def sim():
    with make_simulator("fast") as s:
        yield s


def test_an_ordinary_planner_gets_no_simulator_and_no_pose(sim):
    spy = Spy(privileged=False)
    episode = run_episode(spy, sim, int(eval_world_seeds(1)[0]))
    (start,) = spy.starts
    assert start.sim is None and start.pose is None
    assert all(p is None for p in spy.poses)
    assert spy.observed == episode.actions  # it does learn which primitives it applied
    assert start.library is sim.library and start.max_primitives == 10
    assert start.key == episode_key(episode.world_seed) != episode.world_seed  # no world seed


def test_a_privileged_planner_gets_the_simulator_and_the_true_pose(sim):
    spy = Spy(privileged=True)
    episode = run_episode(spy, sim, int(eval_world_seeds(1)[0]))
    (start,) = spy.starts
    assert start.sim is sim and np.array_equal(start.pose, episode.poses[0])
    for pose, true in zip(spy.poses, episode.poses[:-1], strict=True):
        np.testing.assert_array_equal(pose, true)


def _all_planner_classes() -> set[type]:
    found, todo = set(), [Planner]
    while todo:
        for sub in todo.pop().__subclasses__():
            if sub.__module__.startswith("husky_course") and sub not in found:
                found.add(sub)
                todo.append(sub)
    return found


def test_only_the_oracle_and_the_analysis_references_are_privileged():
    """Among the planners a student picks, only the oracle; beside it, the references (analysis tools
    in ``planners/reference.py``, built by the names in ``REFERENCE_PLANNERS``, never a learner or a
    planner the book ranks as one). Every module that defines planners is imported here, so the
    answer does not depend on which tests ran first."""
    assert {base, classic, learned, oracle, reference}
    privileged = {c for c in _all_planner_classes() if c.privileged}
    assert {c.__name__ for c in privileged if c.__module__ != reference.__name__} == {"OraclePlanner"}
    public = {c.__name__ for c in privileged if not c.__name__.startswith("_")} - {"OraclePlanner"}
    assert public == {"SeenObstaclesPlanner", "SeenMotionPlanner", "SecondLookPlanner", "SnapshotPlanner",
                      "TrueDiscsPlanner", "ToldDiscsPlanner"}
    assert not set(REFERENCE_PLANNERS) & set(PLANNERS)  # no list a student picks from names them
    built = {type(make_planner(name)) for name in REFERENCE_PLANNERS}
    assert {c.__name__ for c in built} == public and all(c.privileged for c in built)


@pytest.mark.parametrize("name", ["random", "heuristic", "lookahead", "rnn", "distilled", "discs"])
def test_every_unprivileged_planner_runs_without_the_world(sim, name):
    """A whole episode with the simulator hidden from the planner (it is only stepped by run_episode)."""
    torch.manual_seed(0)
    models = {
        "lookahead": learned.LookaheadPlanner(JointModel(), 1),
        "rnn": learned.RNNPlanner(RNNLookahead(), 1),
        "distilled": learned.DistilledPlanner(SurvivalNet()),
        "discs": DiscPlanner(DiscNet((0.15, 0.35))),
    }
    planner = models.get(name) or make_planner(name)
    assert not planner.privileged
    episode = run_episode(planner, sim, int(eval_world_seeds(2)[1]))
    assert episode.n_prims >= 1


def test_the_oracle_refuses_to_run_blind():
    with pytest.raises(RuntimeError, match="privileged"):
        oracle.OraclePlanner().reset(EpisodeStart(make_simulator("fast").library, 10, 0))
