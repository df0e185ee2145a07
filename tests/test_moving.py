"""The moving-obstacle course (chapter 10): the world, space-time planning, the switches, the student."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from husky_course.cli import main
from husky_course.config import (
    ConfigError,
    MovingWorldConfig,
    config_hash,
    get_profile,
    sim_for_world,
    with_world,
    world_kind,
)
from husky_course.course import exercises
from husky_course.data.collect import play_video
from husky_course.data.labels import survival_at
from husky_course.evaluation.episodes import eval_world_seeds, evaluate, run_episode
from husky_course.planners.perception import raster
from husky_course.planners.registry import make_planner
from husky_course.sim.env import HuskyNavEnv
from husky_course.sim.fast import FastSimulator
from husky_course.sim.lattice import disc_check, expand, expand_with, survival
from husky_course.sim.world import make_world

QUICK = get_profile("quick")
MOVING = with_world(QUICK, "moving")


@pytest.fixture(scope="module")
def sim():
    return FastSimulator(MOVING.sim)


def test_world_switch_keys_the_config():
    assert world_kind(QUICK.sim) == "static" and world_kind(MOVING.sim) == "moving"
    assert isinstance(MOVING.sim.world, MovingWorldConfig)
    assert config_hash(MOVING.sim) != config_hash(QUICK.sim)
    assert config_hash(with_world(MOVING, "static").sim) == config_hash(QUICK.sim)
    assert with_world(MOVING, "moving") == MOVING
    with pytest.raises(ConfigError, match="unknown world"):
        with_world(QUICK, "windy")


def test_moving_world_is_the_static_world_set_in_motion():
    cfg = MOVING.sim.world
    for seed in range(30):
        still, world = make_world(seed), make_world(seed, cfg)
        movers = world.moving
        assert len(movers) == round(cfg.moving_fraction * cfg.n_obstacles)
        assert np.all(np.abs(world.speeds[movers]) >= cfg.speed_range[0])
        assert np.all(np.abs(world.speeds[movers]) <= cfg.speed_range[1])
        np.testing.assert_array_equal(world.obstacles[:, [0, 2]], still.obstacles[:, [0, 2]])
        standing = np.setdiff1d(np.arange(cfg.n_obstacles), movers)
        np.testing.assert_array_equal(world.obstacles[standing], still.obstacles[standing])
        np.testing.assert_array_equal(world.start, still.start)
        assert still.speeds is None and len(still.moving) == 0
    again = make_world(7, cfg)
    assert make_world(7, cfg).obstacles_at(3.25).tobytes() == again.obstacles_at(3.25).tobytes()


def test_movers_walk_at_their_speed_and_bounce_inside_the_walls():
    world = make_world(3, MOVING.sim.world)
    t = np.linspace(0, 200, 20_001)
    pos = world.obstacles_at(t)  # (T, n, 3)
    m = world.moving
    r = world.obstacles[m, 2]
    assert np.all(np.abs(pos[:, m, 1]) <= world.wall_y - r + 1e-9)  # a mover's surface never crosses a wall
    step = np.abs(np.diff(pos[..., 1], axis=0))
    assert np.all(step <= np.abs(world.speeds) * (t[1] - t[0]) + 1e-9)  # continuous, never faster
    moved = np.abs(pos[-1, :, 1] - pos[0, :, 1]) + step.sum(0)
    assert np.all((moved > 0) == (world.speeds != 0))
    np.testing.assert_allclose(pos[:, :, 0], np.broadcast_to(world.obstacles[:, 0], pos.shape[:2]))
    # the path length walked equals speed x time (reflection keeps the speed; sampling cuts each
    # bounce's corner by at most one sample's walk)
    bounces = np.abs(world.speeds) * t[-1] / (2 * (world.wall_y - world.obstacles[:, 2])) + 1
    cut = 2 * bounces * np.abs(world.speeds) * (t[1] - t[0])
    assert np.all(np.abs(step.sum(0) - np.abs(world.speeds) * t[-1]) <= cut + 1e-9)


def _brute_force(sim, pose, t0, horizon):
    best = np.zeros(sim.library.n, int)
    for seq in itertools.product(range(sim.library.n), repeat=horizon):
        p, n = pose.copy(), 0
        for k, a in enumerate(seq):
            result = sim.apply(p, a, t0 + k)
            if result.collided:
                break
            p, n = result.pose, n + 1
        best[seq[0]] = max(best[seq[0]], n)
    return best


def test_space_time_lattice_matches_brute_force(sim):
    """Survival from the lattice in space-time = every sequence played back at its times; the same
    lattice with the cylinders frozen at their start would disagree (so the test can fail)."""
    rng = np.random.default_rng(0)
    checked = frozen_wrong = nontrivial = 0
    for seed in range(12):
        world = sim.load(1000 + seed)
        t0 = int(rng.integers(1, 6))
        pose = np.array([t0 + 0.0, world.start[1] + rng.uniform(-0.5, 0.5), 0.0])
        if sim.contact_along(pose[None], t0) >= 0:
            continue
        got = survival(expand(world, sim.library, pose, 2, 0.0, t0))
        np.testing.assert_array_equal(got, _brute_force(sim, pose, t0, 2), err_msg=f"world {world.seed}")
        frozen = disc_check(world.obstacles, world.wall_y, world.config.robot_radius, 0.0)
        frozen_wrong += int((survival(expand_with(frozen, sim.library, pose, 2)) != got).any())
        nontrivial += int((got < 2).any())
        checked += 1
    assert checked >= 8 and nontrivial >= 4 and frozen_wrong >= 2


def test_oracle_never_collides_on_a_world_it_calls_crossable(sim):
    oracle = make_planner("oracle")
    crossable = 0
    for seed in eval_world_seeds(40, 1):
        episode = run_episode(oracle, sim, int(seed))
        if oracle.crossable:
            crossable += 1
            assert episode.success, f"world {seed}"
    assert crossable >= 30


def test_episode_images_are_taken_at_their_step(sim):
    episode = run_episode(make_planner("heuristic", config=MOVING.sim), sim, int(eval_world_seeds(1, 1)[0]),
                          record=True)
    assert len(episode.observations) >= 3
    for k, obs in enumerate(episode.observations):
        np.testing.assert_array_equal(obs, sim.depth(episode.poses[k][None], k)[0])
    late = sim.depth(episode.poses[2][None], 0)[0]
    assert not np.array_equal(late, episode.observations[2])  # at time 0 the view would differ


def test_labels_and_videos_use_the_states_time(sim):
    video = play_video(sim, 0, 5, 10)
    again = play_video(FastSimulator(MOVING.sim), 0, 5, 10)
    assert all(np.array_equal(video[k], again[k]) for k in video)
    for k in range(len(video["step"])):
        np.testing.assert_array_equal(video["images"][k], sim.depth(video["poses"][k:k + 1].astype(float),
                                                                    k)[0].astype(np.float16))
    seeds = np.full(40, 1000 + 3)
    world = sim.load(1003)
    poses = np.c_[np.arange(40) % 8 + 1.0, np.linspace(-2, 2, 40), np.zeros(40)]
    times = np.arange(40) % 8
    timed = survival_at(seeds, poses, 3, MOVING.sim, workers=1, progress=False, times=times)
    at_zero = survival_at(seeds, poses, 3, MOVING.sim, workers=1, progress=False)
    assert (timed != at_zero).any()
    lattice = expand(world, sim.library, poses[11], 3, 0.0, float(times[11]))
    np.testing.assert_array_equal(timed[11], survival(lattice))
    with pytest.raises(ValueError, match="one time per state"):
        survival_at(seeds, poses, 3, MOVING.sim, workers=1, progress=False, times=times[:3])


def test_env_world_option():
    env = HuskyNavEnv(world="moving")
    obs, info = env.reset(options={"world_seed": 11})
    assert info["world"] == "moving" and env.world == "moving"
    still = HuskyNavEnv()
    obs_s, info_s = still.reset(options={"world_seed": 11})
    assert info_s["world"] == "static"
    np.testing.assert_array_equal(obs, obs_s)  # the same layout at time 0
    differ = False
    for _ in range(4):
        a, b = env.step(12), still.step(12)
        differ |= not np.array_equal(a[0], b[0])
        if a[2] or b[2]:
            break
    assert differ
    obs, info = still.reset(options={"world_seed": 11, "world": "moving"})
    assert info["world"] == "moving"
    with pytest.raises(ValueError, match="unknown world"):
        env.reset(options={"world": "windy"})
    with pytest.raises(ValueError, match="unknown reset options"):
        env.reset(options={"wrold": "moving"})
    env.close()
    still.close()


def test_cli_world_switch(tmp_path, capsys):
    assert main(["evaluate", "--planner", "oracle", "--world", "moving", "--worlds", "5", "--seed", "1",
                 "--json", "--no-progress", "--profile", "quick"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["world"] == "moving" and out["worlds"] == 5
    assert main(["collect", "--profile", "quick", "--videos", "3", "--world", "moving", "--out",
                 str(tmp_path / "m"), "--no-progress"]) == 0
    spec = json.loads((tmp_path / "m" / "spec.json").read_text())
    assert spec["sim"]["world"]["moving_fraction"] == MOVING.sim.world.moving_fraction
    capsys.readouterr()
    assert main(["evaluate", "--planner", "heuristic", "--trained-on", "moving", "--worlds", "2",
                 "--no-progress", "--profile", "quick"]) == 2
    assert "--trained-on applies only" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["evaluate", "--planner", "oracle", "--world", "windy"])


def test_moving_student_reads_its_motion_channels():
    """The quick profile's moving-trained student (built by `make test` before pytest); how well it
    drives is tests/test_learning_works.py's."""
    from husky_course.planners.base import episode_start

    student = make_planner("memory", profile=MOVING)
    assert student.model.channels == 4 and student.channels == 4
    assert make_planner("memory", profile=QUICK).channels == 1
    sim = FastSimulator(MOVING.sim)
    world = sim.load(int(eval_world_seeds(1, 1)[0]))
    student.reset(episode_start(student, sim, world.seed, world.start, 10))
    image, grid = student.prepare(sim.depth(world.start[None], 0)[0])
    cells = MOVING.memory.map_cells
    assert grid.shape == (4, cells, cells)
    now = raster(student.map.scan(image), cells, MOVING.memory.map_behind, MOVING.memory.map_ahead,
                 MOVING.memory.map_half_width)
    np.testing.assert_array_equal(grid[1], now)  # no previous scan yet: nothing is known to move
    np.testing.assert_array_equal(grid[2], now)
    scan = student.map.scan(image)  # and every cylinder is seen for the first time (walls are never tracked)
    once = raster(scan[student.map.motion.tracks.fresh], cells, MOVING.memory.map_behind,
                  MOVING.memory.map_ahead, MOVING.memory.map_half_width)
    np.testing.assert_array_equal(grid[3], once)
    assert once.any() and (once <= now).all()


def test_sim_for_world_round_trip():
    assert sim_for_world(sim_for_world(QUICK.sim, "moving"), "static") == QUICK.sim


def test_exercise_checks():
    world = make_world(5, MOVING.sim.world)
    i = int(world.moving[0])
    y = float(world.obstacles_at(3.5)[i, 1])
    assert exercises.check_mover_position(5, MOVING.sim, i, 3.5, y)
    with pytest.raises(AssertionError, match="bounces"):
        exercises.check_mover_position(5, MOVING.sim, i, 3.5, float(world.obstacles[i, 1]))
    still = int(np.flatnonzero(world.speeds == 0)[0])
    with pytest.raises(AssertionError, match="does not move"):
        exercises.check_mover_position(5, MOVING.sim, still, 3.5, 0.0)
    assert exercises.check_sample_time(4, 25, 101, 4.25)
    arc, r = exercises.cylinder_arc(3, MOVING.sim)
    from husky_course.planners.pieces import piece_centre

    found = piece_centre(arc, MOVING.sim.camera.mount_forward, r)  # the radius known: the fit is exact
    assert exercises.check_arc_centre(arc, r, found, MOVING.sim)
    with pytest.raises(AssertionError, match="off your circle"):
        exercises.check_arc_centre(arc, r, arc.mean(0), MOVING.sim)
    ends = arc[[0, -1]]  # two of its points: the other circle of radius r through them is in front
    chord, mid = ends[1] - ends[0], ends.mean(0)
    normal = np.array([chord[1], -chord[0]]) / np.hypot(*chord)
    front = mid - normal * np.sqrt(r**2 - (np.hypot(*chord) / 2) ** 2) * np.sign(normal @ (found - mid))
    assert exercises.check_arc_centre(ends, r, found, MOVING.sim)
    with pytest.raises(AssertionError, match="in front of them"):
        exercises.check_arc_centre(ends, r, front, MOVING.sim)
    with pytest.raises(AssertionError):
        exercises.check_sample_time(4, 25, 101, 4.2475)


def test_ceilings_order_snapshot_below_seen_motion_on_the_moving_course():
    """Knowing the motion of what the camera has shown beats knowing every position without motion;
    on the static course the two coincide with knowing everything (nothing moves)."""
    from husky_course.planners.reference import SeenMotionPlanner, SnapshotPlanner

    seen = evaluate(SeenMotionPlanner(), 30, 1, config=MOVING.sim, progress=False)
    snap = evaluate(SnapshotPlanner(), 30, 1, config=MOVING.sim, progress=False)
    assert seen.success_rate >= snap.success_rate + 0.2
    still = evaluate(SnapshotPlanner(), 20, 1, config=QUICK.sim, progress=False)
    oracle = evaluate(make_planner("oracle"), 20, 1, config=QUICK.sim, progress=False)
    assert still.success_rate == oracle.success_rate


def test_second_look_knows_a_cylinders_motion_from_its_second_image():
    """On the static course it is "seen, with motion" world for world (nothing moves); on the moving
    course a first sight's motion is unknown to it, so somewhere it chooses differently."""
    from husky_course.planners.reference import SecondLookPlanner, SeenMotionPlanner

    def actions(planner, course, seed):  # type: ignore[no-untyped-def]
        return run_episode(planner, FastSimulator(course.sim), int(seed), course.sim.max_primitives).actions

    static = eval_world_seeds(10, 1)
    assert all(actions(SecondLookPlanner(), QUICK, s) == actions(SeenMotionPlanner(), QUICK, s)
               for s in static)
    moving = eval_world_seeds(20, 1)
    assert any(actions(SecondLookPlanner(), MOVING, s) != actions(SeenMotionPlanner(), MOVING, s)
               for s in moving)
    wide = SecondLookPlanner(widen=1)
    assert "widened" in wide.name
    assert any(actions(wide, MOVING, s) != actions(SecondLookPlanner(), MOVING, s) for s in moving)


def test_widening_replaces_each_first_sight_by_a_standing_row_and_leaves_the_rest():
    """What ``widen`` changes in the world the second look plans in: each cylinder seen for the first
    time becomes ``2 * widen + 1`` standing copies, half the fastest walk apart across the course;
    every cylinder seen before keeps its place and its motion."""
    from husky_course.planners.reference import SecondLookPlanner

    world = make_world(5, MOVING.sim.world)
    known = np.arange(len(world.obstacles))
    first = np.isin(known, world.moving[:2]) | (known == int(np.flatnonzero(world.speeds == 0)[0]))
    plain, wide = SecondLookPlanner(), SecondLookPlanner(widen=2)
    plain._time = wide._time = 3
    seen, widened = plain._known_world(world, known, first), wide._known_world(world, known, first)
    now = world.obstacles_at(3.0)
    np.testing.assert_array_equal(seen.obstacles[first], now[first])  # a first sight stands where it is
    assert not seen.speeds[first].any() and seen.speeds[~first].tolist() == world.speeds[~first].tolist()
    rest = int((~first).sum())
    np.testing.assert_array_equal(widened.obstacles[:rest], seen.obstacles[~first])
    np.testing.assert_array_equal(widened.speeds[:rest], seen.speeds[~first])
    rows = widened.obstacles[rest:].reshape(int(first.sum()), 5, 3)
    assert len(widened.obstacles) == rest + 5 * first.sum() and not widened.speeds[rest:].any()
    step = world.max_speed / 2
    for row, disc in zip(rows, now[first], strict=True):
        np.testing.assert_allclose(row[:, 1] - disc[1], np.arange(-2, 3) * step)
        np.testing.assert_array_equal(row[:, [0, 2]], np.repeat(disc[None, [0, 2]], 5, axis=0))


def test_tracking_planner_is_mapping_on_static_and_reads_motion_on_moving():
    """The mapping planner with motion: on the static course every velocity is 0 and it chooses as
    the mapping planner does, world for world; on the moving course it crosses clearly more tuning
    worlds than the mapping planner, whose map stands still."""
    static = [run_episode(make_planner(n, config=QUICK.sim), FastSimulator(QUICK.sim), int(s), 10).actions
              for n in ("mapping", "tracking") for s in eval_world_seeds(6, 1)]
    assert static[:6] == static[6:]
    tracking = evaluate(make_planner("tracking", config=MOVING.sim), 100, 1, config=MOVING.sim,
                        progress=False, workers=2)
    mapping = evaluate(make_planner("mapping", config=MOVING.sim), 100, 1, config=MOVING.sim, progress=False)
    assert tracking.success_ci95[0] > mapping.success_ci95[1], (tracking.success_rate, mapping.success_rate)


def test_hedged_choice_reads_safe_steps_off_the_ranking_and_stays_off_the_static_course():
    """The hedge (an experiment, off by default) counts each first primitive's safe steps from the ranking's
    keys: they agree with :func:`survival` of the same lattice; on the static course (no walking share)
    the hedged tracker chooses as the plain one, world for world."""
    from husky_course.planners.tracking import _steps
    from husky_course.sim.lattice import rank_plans

    sim, varied = FastSimulator(QUICK.sim), False
    for seed in eval_world_seeds(4, 1):
        world = sim.load(int(seed))
        for ahead in range(5):  # further into the course, where some first primitives are doomed
            lattice = expand(world, sim.library, world.start + (ahead, 0.0, 0.0), 5, 0.3)
            keys = rank_plans(lattice, np.abs(sim.library.offsets), 0.3, 0.02).keys[0][0]
            np.testing.assert_array_equal(_steps(keys), survival(lattice))
            varied |= len(np.unique(survival(lattice))) > 2
    assert varied
    plain, hedged = ([run_episode(make_planner("tracking", config=QUICK.sim, hedge=h), sim, int(s)).actions
                      for s in eval_world_seeds(4, 1)] for h in (False, True))
    assert plain == hedged


@pytest.mark.parametrize("name", ["tracking", "discs"])
def test_first_decision_samples_the_motion_model_for_its_first_sights_and_only_there(name):
    """With ``first_samples``, the episode's first decision (one image: every first sight doubtful) draws
    that many motions of the doubtful pieces from the course's motion model (each stands, or walks at
    a speed in ``speed_range``, all its points as one; every other point keeps its own velocity) and
    takes the first primitive whose plans survive the most steps on average; no later decision samples,
    the draws come from the episode's own number, and on the static course nothing is doubtful, so it
    is the plain tracker. The disc planner (quick network) samples its doubtful discs the same way."""
    sim, samples = FastSimulator(MOVING.sim), 8
    extra = {"profile": QUICK, "samples": 0} if name == "discs" else {}
    lo, hi = MOVING.sim.world.speed_range
    with pytest.raises(ValueError, match="first_samples"):
        make_planner(name, config=MOVING.sim, first_samples=-1, **extra)
    checked = 0
    for seed in eval_world_seeds(6, 1):
        planner = make_planner(name, config=MOVING.sim, first_samples=samples, **extra)
        calls: list[tuple[np.ndarray, np.ndarray]] = []
        hypothesis = planner._hypothesis

        def record(horizon, speed, hypothesis=hypothesis, calls=calls, planner=planner):
            steps = hypothesis(horizon, speed)
            doubtful, speed = planner.doubtful, np.broadcast_to(speed, planner.doubtful.shape)
            assert (speed[~doubtful] == 0).all()  # only the doubtful points' velocities are drawn
            p, v = planner.points[doubtful], speed[doubtful]
            near = np.hypot(p[:, None, 0] - p[None, :, 0], p[:, None, 1] - p[None, :, 1]) < 0.1
            assert (v[:, None] == v[None, :])[near].all()  # one piece (a cylinder's points) walks as one
            calls.append((speed.copy(), steps))
            return steps

        planner._hypothesis = record
        episode = run_episode(planner, sim, int(seed))
        if not calls:
            continue
        assert len(calls) == samples  # the first decision only
        speeds = np.array([s for s, _ in calls])
        walking = np.abs(speeds[speeds != 0])
        assert ((walking >= lo - 1e-9) & (walking <= hi + 1e-9)).all()
        mean = np.mean([steps for _, steps in calls], axis=0)
        assert mean[episode.actions[0]] == mean.max()
        again = make_planner(name, config=MOVING.sim, first_samples=samples, **extra)
        assert run_episode(again, sim, int(seed)).actions == episode.actions  # the same draws
        checked += 1
    assert checked >= 3
    if name == "discs":
        return
    static = FastSimulator(QUICK.sim)
    plain, sampled = ([run_episode(make_planner("tracking", config=QUICK.sim, first_samples=n), static,
                                   int(s)).actions for s in eval_world_seeds(4, 1)] for n in (0, samples))
    assert plain == sampled
