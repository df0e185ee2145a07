"""The one lattice search (oracle and survival labels) against brute force over every sequence."""

from __future__ import annotations

import numpy as np
import pytest

from husky_course.data.labels import best_continuations
from husky_course.planners.base import episode_start
from husky_course.planners.oracle import OraclePlanner
from husky_course.sim.fast import FastSimulator
from husky_course.sim.lattice import LatticeError, expand, survival


def brute_force_survival(sim: FastSimulator, pose: np.ndarray, horizon: int) -> np.ndarray:
    """Steps survived by the best of all n**horizon sequences starting with each primitive."""
    lib = sim.library
    n = lib.n
    poses = pose[None].copy()
    alive = np.ones(1, bool)  # every sequence prefix survived so far
    steps = np.zeros(1, int)
    for _ in range(horizon):
        paths = lib.paths_from(np.repeat(poses, n, 0), np.tile(np.arange(n), len(poses)))
        safe = ~sim.contacts(paths).any(1)
        alive = np.repeat(alive, n) & safe
        steps = np.repeat(steps, n) + alive
        poses = paths[:, -1]
    per_first = steps.reshape(n, -1)  # sequences are grouped by their first primitive
    return per_first.max(1)


def _states(n_worlds: int, per_world: int, seed: int = 0):
    """Lattice states (yaw 0) from the start of random worlds and a few safe steps in."""
    sim = FastSimulator()
    rng = np.random.default_rng(seed)
    for _ in range(n_worlds):
        world = sim.load(int(rng.integers(0, 2**31 - 1)))
        pose = world.start.copy()
        for _ in range(per_world):
            yield sim, pose.copy()
            for k in rng.permutation(sim.library.n):
                r = sim.apply(pose, int(k))
                if not r.collided:
                    pose = r.pose
                    break


@pytest.mark.parametrize("horizon", [1, 2, 3])
def test_survival_labels_match_brute_force(horizon):
    checked = 0
    for sim, pose in _states(12, 4, seed=horizon):
        got = best_continuations(sim, pose, horizon)
        want = brute_force_survival(sim, pose, horizon)
        np.testing.assert_array_equal(got, want, err_msg=f"world {sim.world.seed}, pose {pose}")
        checked += 1
    assert checked == 48


def test_oracle_safe_steps_match_brute_force():
    """The oracle's best plan over 3 steps survives as long as the best of all 25**3 sequences."""
    for sim, pose in _states(10, 3, seed=7):
        oracle = OraclePlanner(horizon=3)
        oracle.reset(episode_start(oracle, sim, sim.world.seed, pose, 3))
        best = int(brute_force_survival(sim, pose, 3).max())
        assert oracle.crossable == (best == 3)
        assert int(survival(expand(sim.world, sim.library, pose, 3, cap=0.3)).max()) == best


def test_lattice_refuses_a_turned_start():
    sim = FastSimulator()
    world = sim.load(0)
    with pytest.raises(LatticeError, match="start heading of 0"):
        expand(world, sim.library, np.array([0.0, 0.0, 0.1]), 2, cap=0.0)
