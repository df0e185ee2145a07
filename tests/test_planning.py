"""Planners, evaluation worlds, episode accounting, exact error bars and the ``evaluate`` CLI."""

from __future__ import annotations

import functools
import json
import math
import sys

import numpy as np
import pytest

from husky_course import cli
from husky_course.config import EVAL_SEED_BASE, SimConfig, WorldConfig, get_profile
from husky_course.data.collect import VIDEO_STRIDE, collect, world_seed_for
from husky_course.evaluation.episodes import (
    EVAL_SET_MAX,
    EVAL_SET_STRIDE,
    eval_world_seeds,
    evaluate,
    is_eval_seed,
    run_episode,
)
from husky_course.evaluation.rollout import Rollout
from husky_course.evaluation.statistics import clopper_pearson
from husky_course.planners.base import (
    Planner,
    PlannerError,
    check_look_ahead,
    check_observation,
    episode_start,
)
from husky_course.planners.oracle import OraclePlanner
from husky_course.planners.registry import PLANNERS, make_planner
from husky_course.sim.backends import make_simulator

QUICK = get_profile("quick")  # resolved once, passed down

BASIC = ("random", "heuristic", "mapping", "tracking", "oracle")
JSON_FIELDS = {
    "planner",
    "worlds",
    "success_rate",
    "mean_prims",
    "collision_rate",
    "collision_rate_upper95",
    "success_ci95",
    "ms_per_decision",
}


@pytest.fixture(scope="module")
def sim():
    with make_simulator("fast") as s:
        yield s


# --- planners -------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", BASIC)
def test_planners_return_valid_index(sim, name):
    planner = make_planner(name)
    rng = np.random.default_rng(0)
    for world_seed in eval_world_seeds(5, seed=7):
        world = sim.load(int(world_seed))
        planner.reset(episode_start(planner, sim, int(world_seed), world.start, 10))
        for obs in (rng.random((50, 50), dtype=np.float32), sim.depth(world.start[None])[0]):
            action = planner.act(obs, world.start.copy() if planner.privileged else None)
            assert type(action) is int and 0 <= action < 25
            assert planner.last_scores is not None and planner.last_scores.shape == (25,)
            assert np.isfinite(planner.last_scores).all()


@pytest.mark.parametrize("name", BASIC)
def test_bad_observations_raise(sim, name):
    planner = make_planner(name)
    world = sim.load(int(eval_world_seeds(1)[0]))
    planner.reset(episode_start(planner, sim, world.seed, world.start, 10))
    good = sim.depth(world.start[None])[0]
    nan = good.copy()
    nan[3, 4] = np.nan
    bad = {
        "shape": (good[:49], "shape"),
        "3d": (good[None], "shape"),
        "nan": (nan, "NaN"),
        "int": (good.astype(np.int32), "dtype"),
        "range": (good * 3.0, r"\[0, 1\]"),
        "list": (good.tolist(), "numpy array"),
    }
    for obs, message in bad.values():
        with pytest.raises(ValueError, match=message):
            planner.act(obs, world.start.copy())
    assert check_observation(good.astype(np.float16)).dtype == np.float32


def test_registry_errors(monkeypatch):
    everything = {"random", "heuristic", "mapping", "tracking", "lookahead", "rnn", "distilled", "memory",
                  "discs", "oracle"}
    assert set(PLANNERS) == everything
    names = "random, heuristic, mapping, tracking, lookahead, rnn, distilled, memory, discs, oracle"
    with pytest.raises(PlannerError, match=f"choose one of {names}"):
        make_planner("astar")
    assert issubclass(PlannerError, ValueError)
    with pytest.raises(PlannerError, match="bad arguments"):
        make_planner("heuristic", look_ahead=2)
    for name in ("lookahead", "rnn", "distilled", "memory", "discs"):
        with pytest.raises(PlannerError, match="is learned: pass profile="):
            make_planner(name, look_ahead=1)
    monkeypatch.setitem(sys.modules, "husky_course.planners.learned", None)  # module unavailable
    for name in ("lookahead", "rnn", "distilled"):
        with pytest.raises(PlannerError, match="learned: it needs torch and trained checkpoints"):
            make_planner(name, look_ahead=1, profile=QUICK)


def test_check_look_ahead():
    assert check_look_ahead(0) == 0 and check_look_ahead(np.int64(4)) == 4
    for bad in (-1, 1.5, True, "2", None):
        with pytest.raises(PlannerError, match="look_ahead"):
            check_look_ahead(bad)


# --- evaluation worlds ----------------------------------------------------------------------------
def test_eval_seeds_disjoint_from_training(tmp_path):
    # the last world seed collection can produce is EVAL_SEED_BASE - 1; the next one is refused
    top_seed, top_video = divmod(EVAL_SEED_BASE - 1, VIDEO_STRIDE)
    highest_training = world_seed_for(top_seed, top_video)
    assert highest_training == EVAL_SEED_BASE - 1 and not is_eval_seed(highest_training)
    assert world_seed_for(0, 0) == 0 and not is_eval_seed(0)
    for seed, video in ((top_seed, top_video + 1), (top_seed + 1, 0)):
        with pytest.raises(ValueError):
            world_seed_for(seed, video)  # would reach the evaluation range
    with pytest.raises(ValueError):
        collect(tmp_path / "a", QUICK, videos=top_video + 2, seed=top_seed, progress=False)
    with pytest.raises(ValueError):
        collect(tmp_path / "b", QUICK, videos=1, seed=top_seed + 1, progress=False)
    for s in (0, 1, EVAL_SET_MAX):
        seeds = eval_world_seeds(1000, s)
        assert seeds.min() >= EVAL_SEED_BASE > highest_training and seeds.max() < 2**32
        assert all(is_eval_seed(int(w)) for w in seeds[[0, -1]])
        assert len(np.unique(seeds)) == 1000
    assert not set(eval_world_seeds(10, 0)) & set(eval_world_seeds(10, 1))
    assert eval_world_seeds(EVAL_SET_STRIDE, EVAL_SET_MAX).max() < 2**32
    for n, s in (
        (0, 0),
        (-1, 0),
        (1.5, 0),
        (True, 0),
        (EVAL_SET_STRIDE + 1, 0),
        (5, -1),
        (5, EVAL_SET_MAX + 1),
    ):
        with pytest.raises(ValueError):
            eval_world_seeds(n, s)
    assert not is_eval_seed(True) and not is_eval_seed(float(EVAL_SEED_BASE))


# --- episodes and evaluation ----------------------------------------------------------------------
class Recorder(Planner):
    """Always primitive 0 (hard left): ends in the wall or an obstacle; records the protocol."""

    name = "recorder"

    def __init__(self) -> None:
        super().__init__()
        self.calls: list[tuple] = []

    def reset(self, start):
        self.calls.append(("reset",))

    def act(self, obs, pose=None):
        check_observation(obs)
        self.calls.append(("act",))
        return 0

    def observe(self, action, obs_next):
        self.calls.append(("observe", action, None if obs_next is None else obs_next.shape))


def test_run_episode_accounting(sim):
    planner = Recorder()
    ep = run_episode(planner, sim, int(eval_world_seeds(1)[0]))
    assert ep.collided and not ep.success and ep.n_prims == len(ep.actions) < 10
    assert ep.poses.shape == (ep.n_prims + 1, 3) and ep.path.shape[1] == 3
    assert planner.calls[0] == ("reset",) and planner.calls[-1] == ("observe", 0, None)
    observes = [c for c in planner.calls if c[0] == "observe"]
    assert observes[:-1] == [("observe", 0, (50, 50))] * (ep.n_prims - 1)
    assert len(ep.decision_times) == ep.n_prims
    oracle_ep = run_episode(OraclePlanner(), sim, int(eval_world_seeds(1)[0]), max_primitives=3)
    assert oracle_ep.success and oracle_ep.n_prims == 3 and not oracle_ep.collided


def test_a_rollout_stops_at_each_decision_before_it_is_played_and_plays_run_episodes_episode(sim):
    seed = int(eval_world_seeds(1)[0])
    planner = Recorder()
    rollout = Rollout(planner, sim, seed)
    assert planner.calls == [("reset",)]  # made: reset, nothing chosen yet
    seen = []
    for d in rollout:
        assert d.result is None and planner.calls[-1] == ("act",)  # chosen, not yet played or observed
        seen.append(d)
    assert [d.step for d in seen] == list(range(len(seen)))
    assert all(d.result is not None for d in seen) and seen[-1].result.collided
    assert all(np.array_equal(a.result.pose, b.pose) for a, b in zip(seen, seen[1:], strict=False))
    ep = run_episode(Recorder(), sim, seed)  # each starts where the last ended; run_episode plays the same
    assert ep.actions == [d.action for d in seen] and np.array_equal(ep.poses[-1], seen[-1].result.pose)
    with pytest.raises(RuntimeError, match="once"):
        next(iter(rollout))
    stopped = Recorder()
    for d in Rollout(stopped, sim, seed):
        if d.step == 1:
            break
    assert [c[0] for c in stopped.calls] == ["reset", "act", "observe", "act"]  # the second never played


def test_random_planner_is_reproducible(sim):
    a = evaluate(make_planner("random", seed=4), 30, seed=2, sim=sim, progress=False)
    b = evaluate(make_planner("random", seed=4), 30, seed=2, sim=sim, progress=False)
    reused = make_planner("random", seed=4)
    evaluate(reused, 5, seed=9, sim=sim, progress=False)
    c = evaluate(reused, 30, seed=2, sim=sim, progress=False)
    d = evaluate(make_planner("random", seed=5), 30, seed=2, sim=sim, progress=False)
    actions = [[e.actions for e in r.episodes] for r in (a, b, c, d)]
    assert actions[0] == actions[1] == actions[2] != actions[3]
    assert a.to_json() | {"ms_per_decision": 0, "ms_per_reset": 0} == b.to_json() | {
        "ms_per_decision": 0,
        "ms_per_reset": 0,
    }


def _max_safe_steps(sim, world, horizon=10):
    """Brute force: the most safe primitives from the start, by memoised search with sim.apply."""

    @functools.cache
    def best(k, yq):
        if k == horizon:
            return 0
        pose = np.array([world.start[0] + k, yq / 1e6, 0.0])
        safe = [m for m in range(sim.library.n) if not sim.apply(pose, m).collided]
        return max(
            (1 + best(k + 1, round((pose[1] + sim.library.offsets[m]) * 1e6)) for m in safe), default=0
        )

    return best(0, round(world.start[1] * 1e6))


def test_oracle_never_collides_when_crossable(sim):
    oracle = OraclePlanner()
    crossable = 0
    for world_seed in eval_world_seeds(60, seed=5):
        ep = run_episode(oracle, sim, int(world_seed))
        crossable += oracle.crossable
        assert ep.success == oracle.crossable and ep.collided != oracle.crossable
    assert crossable >= 50  # sparse courses: almost all can be crossed
    # dense courses: the oracle survives exactly as long as the best sequence (brute force)
    with make_simulator("fast", SimConfig(world=WorldConfig(n_obstacles=70))) as dense:
        results = []
        for world_seed in eval_world_seeds(8, seed=6):
            ep = run_episode(oracle, dense, int(world_seed))
            best = _max_safe_steps(dense, dense.world)
            assert ep.n_prims - ep.collided == best and oracle.crossable == (best == 10)
            results.append(best)
        assert min(results) < 10  # the dense check exercises uncrossable worlds


def test_heuristic_beats_random(sim):
    rand = evaluate(make_planner("random"), 100, seed=3, sim=sim, progress=False)
    heur = evaluate(make_planner("heuristic"), 100, seed=3, sim=sim, progress=False)
    assert rand.success_rate < 0.15 and 3.5 < rand.mean_prims < 5.5
    assert heur.success_rate >= rand.success_rate + 0.35
    assert heur.mean_prims >= rand.mean_prims + 2.5
    assert heur.success_ci95[0] > rand.success_ci95[1]  # the exact intervals do not overlap


def test_clopper_pearson_known_values():
    _, hi = clopper_pearson(0, 500, 0.95, "upper")
    assert hi == pytest.approx(1 - 0.05 ** (1 / 500), rel=1e-9) and hi == pytest.approx(0.005974, abs=1e-6)
    lo, hi = clopper_pearson(5, 100)  # R: binom.test(5, 100)$conf.int
    assert (lo, hi) == pytest.approx((0.01643188, 0.11283491), abs=1e-8)
    assert clopper_pearson(100, 100)[0] == pytest.approx(0.025 ** (1 / 100), rel=1e-9)
    assert clopper_pearson(1, 10, 0.95, "lower")[0] == pytest.approx(1 - 0.95**0.1, rel=1e-9)
    lo, hi = clopper_pearson(7, 40, 0.9)
    assert clopper_pearson(33, 40, 0.9) == pytest.approx((1 - hi, 1 - lo), abs=1e-12)
    assert clopper_pearson(0, 10) == pytest.approx((0.0, 1 - 0.025**0.1))
    for bad in ((-1, 10), (11, 10), (0, 0), (1.5, 10)):
        with pytest.raises(ValueError):
            clopper_pearson(*bad)
    with pytest.raises(ValueError):
        clopper_pearson(1, 10, 1.0)
    assert math.isclose(clopper_pearson(3, 10, alternative="upper")[0], 0.0)


# --- command line ---------------------------------------------------------------------------------
@pytest.mark.parametrize("name", BASIC)
def test_cli_evaluate_json(capsys, name):
    rc = cli.main(["evaluate", "--planner", name, "--worlds", "5", "--seed", "1", "--json", "--no-progress"])
    out = capsys.readouterr().out
    assert rc == 0
    result = json.loads(out)
    assert JSON_FIELDS <= set(result) and result["planner"] == name and result["worlds"] == 5
    assert 0 <= result["collision_rate"] <= result["collision_rate_upper95"] <= 1
    lo, hi = result["success_ci95"]
    assert lo <= result["success_rate"] <= hi
    assert 1 <= result["mean_prims"] <= 10 and result["ms_per_decision"] >= 0


@pytest.mark.parametrize(
    "args, message",
    [
        (["--planner", "astar"], "unknown planner"),
        (["--planner", "random", "--worlds", "0"], "evaluation worlds"),
        (["--planner", "random", "--seed", "-1"], "evaluation seed"),
        (["--planner", "heuristic", "--look-ahead", "2"], "look-ahead"),
        (["--planner", "lookahead", "--look-ahead", "-1"], "look_ahead"),
        (["--planner", "random", "--profile", "huge"], "profile"),
    ],
)
def test_cli_evaluate_bad_input(capsys, args, message):
    rc = cli.main(["evaluate", *args, "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("error:") and message in err


def test_serial_evaluation_runs_in_the_given_simulator_with_a_bar(capsys):
    """``evaluate(..., sim=...)`` with the defaults (local engine, one worker) plays every world in that
    simulator, even one no worker could rebuild, leaves it open, shows its bar, and gives the numbers
    of the chunked path."""
    from husky_course.sim.fast import FastSimulator

    class Counting(FastSimulator):  # not a backend a worker can build: only the serial path takes it
        def __init__(self, config):
            super().__init__(config)
            self.loaded, self.closed = [], False

        def _load(self, world):
            self.loaded.append(world.seed)
            super()._load(world)

        def close(self):
            self.closed = True

    sim = Counting(QUICK.sim)
    planner = make_planner("heuristic")
    mine = evaluate(planner, 4, seed=2, sim=sim, progress=True)
    assert sim.loaded == eval_world_seeds(4, 2).tolist() and not sim.closed
    assert "evaluate heuristic" in capsys.readouterr().err
    chunked = evaluate(planner, 4, seed=2, config=QUICK.sim, progress=False, worlds_per_task=3, workers=2)
    timing = ("ms_per_decision", "ms_per_reset")
    assert {k: v for k, v in mine.to_json().items() if k not in timing} == {
        k: v for k, v in chunked.to_json().items() if k not in timing
    }
    assert mine.seed == 2 and [e.actions for e in mine.episodes] == [e.actions for e in chunked.episodes]
    with pytest.raises(ValueError, match="cannot be rebuilt in a worker"):
        evaluate(planner, 2, sim=sim, progress=False, workers=2)
