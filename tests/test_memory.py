"""The mapping planner and the memory student (chapter 8): memory without privileged input."""

from __future__ import annotations

import shutil
from dataclasses import replace

import numpy as np
import pytest

from husky_course.config import TrainConfig, get_profile
from husky_course.data import store
from husky_course.evaluation.episodes import eval_world_seeds, evaluate, run_episode
from husky_course.imitation import dagger
from husky_course.planners.base import EpisodeStart
from husky_course.planners.mapping import ClearanceGrid, MappingPlanner
from husky_course.planners.perception import DepthScan, EgoMap
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator
from husky_course.training.memory import load_memory
from husky_course.training.trainer import CheckpointError

QUICK = get_profile("quick")
TINY = replace(
    QUICK,
    memory=replace(QUICK.memory, rounds=2, worlds_per_round=12, train=TrainConfig(epochs=2, patience=1)),
)


def test_ego_map_moves_with_dead_reckoning_and_forgets_behind():
    sim = FastSimulator()
    world = sim.load(int(eval_world_seeds(1)[0]))
    ego = EgoMap(DepthScan(), forget_behind=1.0)
    ego.add(sim.depth(world.start[None])[0])
    before = ego.points.copy()
    assert len(before) > 0 and (before[:, 2] > 0).all()
    ego.move(1.0, 0.2)
    np.testing.assert_allclose(ego.points[:, :2], before[before[:, 0] - 1.0 > -1.0, :2] - [1.0, 0.2])
    raster = ego.raster(32, 1.0, 5.4, 3.2)
    assert raster.shape == (32, 32) and raster.sum() > 0


def test_map_points_lie_on_the_true_obstacles():
    """Every scan point of the start image is on an obstacle's surface or a wall (no privileged input)."""
    sim = FastSimulator()
    for seed in eval_world_seeds(5, seed=3):
        world = sim.load(int(seed))
        pts = DepthScan()(sim.depth(world.start[None])[0]) + world.start[:2]
        diff = pts[:, None, :] - world.obstacles[None, :, :2]
        gap = np.hypot(diff[..., 0], diff[..., 1]) - world.obstacles[:, 2]
        on_wall = np.abs(np.abs(pts[:, 1]) - world.wall_y) < 0.03
        assert ((np.abs(gap).min(1) < 0.05) | on_wall).all()


def test_clearance_grid_matches_brute_force():
    rng = np.random.default_rng(0)
    pts = np.c_[rng.uniform(0, 4, 30), rng.uniform(-2, 2, 30), rng.uniform(0, 0.1, 30)]
    grid = ClearanceGrid(pts, -1.0, 5.0, 3.0, 0.025, reach=0.8)
    x, y = rng.uniform(-0.5, 4.5, 500), rng.uniform(-2.5, 2.5, 500)
    want = np.minimum((np.hypot(x[:, None] - pts[:, 0], y[:, None] - pts[:, 1]) - pts[:, 2]).min(1), 0.8)
    assert np.abs(grid(x, y) - want).max() <= 0.025  # within a cell diagonal


def test_mapping_planner_sees_only_images():
    planner = make_planner("mapping")
    assert not planner.privileged
    with pytest.raises(RuntimeError, match="reset"):
        MappingPlanner().act(np.ones((50, 50), np.float32))
    episode = run_episode(planner, FastSimulator(), int(eval_world_seeds(3)[2]), record=True)
    assert episode.n_prims >= 1 and all(s is not None for s in episode.scores)


def test_mapping_beats_the_memoryless_heuristic():
    """On 100 held-out worlds (a tuning set): memory of past scans crosses more worlds."""
    sim = FastSimulator()
    mapping = evaluate(make_planner("mapping"), 100, seed=1, sim=sim, progress=False)
    heuristic = evaluate(make_planner("heuristic"), 100, seed=1, sim=sim, progress=False)
    assert mapping.success_rate > heuristic.success_rate


def test_dagger_rounds_are_resumable_artifacts(tmp_path, monkeypatch):
    monkeypatch.setenv(store.ARTIFACTS_ENV, str(tmp_path / "a"))
    with pytest.raises(CheckpointError, match="train memory --profile quick"):
        load_memory(TINY)
    first = dagger.get_memory(TINY, progress=False)
    assert [r["acting"] for r in first.rounds] == ["teacher", "student"]
    assert all(r["states"] > 0 for r in first.rounds)
    # a run killed after round 0: the second round and the final model are rebuilt identically
    run = tmp_path / "a"
    resumed_root = tmp_path / "b"
    shutil.copytree(run, resumed_root)
    (mdir,) = list((resumed_root / "quick" / "models").glob("memory-*"))
    shutil.rmtree(mdir / "round_1")
    (mdir / "round_1.npz").unlink()
    (mdir / "model.pt").unlink()
    monkeypatch.setenv(store.ARTIFACTS_ENV, str(resumed_root))
    again = dagger.get_memory(TINY, progress=False)
    for a, b in zip(first.model.state_dict().values(), again.model.state_dict().values(), strict=True):
        assert np.array_equal(a.numpy(), b.numpy())
    model, _, _ = load_memory(TINY)
    planner = make_planner("memory", profile=TINY)
    assert not planner.privileged
    planner.reset(EpisodeStart(FastSimulator().library, 10, 0))
    assert 0 <= planner.act(np.ones((50, 50), np.float32)) < 25
