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
from husky_course.planners.mapping import TABLE_RADIUS, ClearanceGrid, MappingPlanner, path_table
from husky_course.planners.perception import DepthScan, EgoMap
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator
from husky_course.sim.primitives import make_library
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


def _path_clearance(lib, pts: np.ndarray, x0: float, y0: np.ndarray, reach: float) -> np.ndarray:
    """Brute force: each start's and primitive's nearest point disc over all of the path's samples."""
    xy = lib.local_paths[:, :, :2]  # (n, S, 2)
    dx = x0 + xy[None, :, :, None, 0] - pts[None, None, None, :, 0]
    dy = y0[:, None, None, None] + xy[None, :, :, None, 1] - pts[None, None, None, :, 1]
    gap = (np.hypot(dx, dy) - pts[:, 2]).min((2, 3))  # (starts, n)
    return np.minimum(gap, reach)


def test_path_table_matches_brute_force():
    """The search's clearance of a whole primitive path from map points, read off the path table, is
    the brute-force distance over every sample within half a cell's diagonal; points off the table
    (further than its margin from every path) change nothing; a wider point gets a wider table."""
    lib, rng, reach, res = make_library(), np.random.default_rng(0), 0.77, 0.025
    table = path_table(lib, res, reach + TABLE_RADIUS)
    assert table.margin >= reach + TABLE_RADIUS
    pts = np.c_[rng.uniform(-1, 6, 40), rng.uniform(-3, 3, 40), rng.uniform(0, 0.3, 40)]
    for x0 in (0.0, 1.0, 3.0):
        y0 = rng.uniform(-2, 2, 7)
        got = table.clearance(pts, x0, y0, reach)
        want = _path_clearance(lib, pts, x0, y0, reach)
        assert got.shape == (7, lib.n) and (want < reach).any()
        assert np.abs(got - want).max() <= res / np.sqrt(2) + 1e-9
    far = np.array([[0.5, table.y0 - 3.0, 0.1], [table.x0 - 3.0, 0.0, 0.1]])  # off the table
    assert (table.clearance(far, 0.0, np.zeros(3), reach) == reach).all()
    r = reach + TABLE_RADIUS + 0.5  # a point wider than the first table covers, off it
    wide = np.array([[0.5, 1.0 + 0.8 + reach + TABLE_RADIUS, r]])
    assert path_table(lib, res, reach + wide[0, 2]).margin >= reach + wide[0, 2]
    got = path_table(lib, res, reach + wide[0, 2]).clearance(wide, 0.0, np.zeros(1), reach)
    want = _path_clearance(lib, wide, 0.0, np.zeros(1), reach)
    assert (want < reach).any() and np.abs(got - want).max() <= res / np.sqrt(2) + 1e-9


def test_mapping_search_matches_the_sample_search():
    """The mapping planner's search (path tables, every sample) and the clearance-grid search over its
    own 21 samples judge the same edges of real maps alike, up to the two readings' rounding and
    the samples the grid search skips."""
    sim, planner = FastSimulator(), MappingPlanner()
    every = (sim.library.local_paths.shape[1] - 1) // (planner.path_samples - 1)
    local, y0 = sim.library.local_paths[:, ::every], np.linspace(-2.0, 2.0, 9)
    worst, compared = 0.0, 0
    for seed in eval_world_seeds(6, seed=1):
        world = sim.load(int(seed))
        planner.reset(EpisodeStart(library=sim.library, max_primitives=10, key=0))
        planner.map.add(sim.depth(world.start[None])[0])
        table, grid = planner._start_check(), planner._edge_check(5)
        for x0 in (0.0, 1.0, 2.0, 3.0):
            hit_t, clear_t = table(x0, y0, 0.0)
            hit_g, clear_g = grid(x0 + local[..., 0], y0[:, None, None] + local[None, :, :, 1], np.zeros(21))
            worst = max(worst, float(np.abs(clear_t - clear_g).max()))
            compared += int((clear_g < planner.cap).sum())
    assert compared > 100 and worst <= 0.05


def test_a_pickled_mapping_planner_leaves_its_path_table_behind():
    """Workers get the planner pickled: without its table (megabytes), which reset finds again."""
    import pickle

    sim, planner = FastSimulator(), MappingPlanner()
    planner.reset(EpisodeStart(library=sim.library, max_primitives=10, key=0))
    assert planner._table is not None and planner._table.rows.nbytes > 1e6
    copy = pickle.loads(pickle.dumps(planner))
    assert len(pickle.dumps(planner)) < 1e6 and copy._table is None
    copy.reset(EpisodeStart(library=sim.library, max_primitives=10, key=0))
    assert copy._table is planner._table  # the process's cache


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


def test_round_worlds_per_course():
    """The moving course's rounds may have their own size (the quick profile halves them); the rounds
    follow one another on the collection seed, and no world is a round's twice."""
    from husky_course.config import with_world

    moving = with_world(QUICK, "moving")
    assert QUICK.memory.moving_worlds_per_round is not None
    for course, n in ((QUICK, QUICK.memory.worlds_per_round), (moving, QUICK.memory.moving_worlds_per_round)):
        rounds = [dagger.round_worlds(course, r) for r in range(2)]
        assert [len(w) for w in rounds] == [n, n]
        assert not set(rounds[0]) & set(rounds[1])
    np.testing.assert_array_equal(dagger.round_worlds(moving, 0),
                                  dagger.round_worlds(QUICK, 0)[:QUICK.memory.moving_worlds_per_round])
    same = replace(moving, memory=replace(QUICK.memory, moving_worlds_per_round=None))
    assert len(dagger.round_worlds(same, 1)) == QUICK.memory.worlds_per_round
