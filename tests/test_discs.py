"""The disc planner: its pieces, labels and map, and (quick profile, trained) that it learned.

The learning tests load the network ``make test`` trains before pytest (``train all`` builds
``discs``) and never train; they run on evaluation set 3, which no chapter, certificate or
tuning uses (0 reports, 1 tunes, 2 is the certificate's held-out set).
"""

from __future__ import annotations

import checkpoints
import numpy as np
import pytest
import torch

from husky_course.config import get_profile
from husky_course.evaluation.episodes import eval_world_seeds, evaluate, run_episode
from husky_course.imitation.discs import piece_views, view_poses
from husky_course.models.discs import PIECE_GLOBALS, PIECE_POINTS, DiscNet
from husky_course.planners.base import PlannerError
from husky_course.planners.discs import DiscMap, DiscPlanner, PieceReader, _NumpyMLP
from husky_course.planners.reference import TrueDiscsPlanner
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator
from husky_course.sim.world import World

QUICK = get_profile("quick")

TEST_SET, WORLDS = 3, 200


def _net(seed: int = 0) -> DiscNet:
    torch.manual_seed(seed)
    return DiscNet(QUICK.sim.world.radius_range).eval()


def test_the_planner_computes_the_network_exactly():
    """The planner runs the network's weights in numpy: the same numbers as torch."""
    model = _net()
    x = np.random.default_rng(0).normal(size=(9, 2 * PIECE_POINTS + PIECE_GLOBALS)).astype(np.float32)
    logit, centre, radius = _NumpyMLP(model)(x.astype(np.float64))
    with torch.no_grad():
        t_logit, t_centre, t_radius = model(torch.from_numpy(x))
    np.testing.assert_allclose(logit, t_logit.numpy(), atol=1e-5)
    np.testing.assert_allclose(centre, t_centre.numpy(), atol=1e-5)
    np.testing.assert_allclose(radius, t_radius.numpy(), atol=1e-5)
    lo, hi = QUICK.sim.world.radius_range
    assert (radius >= lo).all() and (radius <= hi).all()


def _lone_cylinder(x: float, y: float, r: float) -> World:
    world = FastSimulator(QUICK.sim).load(int(eval_world_seeds(1, TEST_SET)[0]))
    return World(world.seed, world.config, np.array([[x, y, r]]), np.array([0.0, 0.0, 0.0]))


def test_a_labelled_piece_points_back_at_its_cylinder():
    """The label's frame is the one the planner decodes with: mean + a ray + b across is the centre."""
    sim, reader = FastSimulator(QUICK.sim), PieceReader(QUICK.sim)
    world = _lone_cylinder(3.0, 0.4, 0.3)
    sim.load(world)
    pose = np.zeros(3)
    image = sim.depth(pose[None])[0]
    d, cols, pts, pieces = reader.pieces(image)
    cylinder = [i for i in pieces if (sim.column_hits(pose[None])[1][0][cols[i]] >= 2).all()]
    assert len(cylinder) == 1
    feats, (mean, ray, across) = reader.features(pts[cylinder[0]], cols[cylinder[0]], d)
    assert feats.shape == (2 * PIECE_POINTS + PIECE_GLOBALS,)
    np.testing.assert_allclose([np.linalg.norm(ray), ray @ across], [1.0, 0.0], atol=1e-12)
    rel = np.array([3.0, 0.4]) - mean
    a, b = rel @ ray, rel @ across
    np.testing.assert_allclose(mean + a * ray + b * across, [3.0, 0.4])
    assert 0.1 < a < 0.35 and abs(b) < 0.05  # the centre lies behind the visible arc, along the ray


def test_training_views_are_collision_free_and_labelled(monkeypatch):
    from dataclasses import replace

    profile = replace(QUICK, discs=replace(QUICK.discs, worlds=3, poses_per_world=4))
    data = piece_views(profile, progress=False)
    assert set(data) == {"features", "cylinder", "centre", "radius", "world_seed"}
    assert len(np.unique(data["world_seed"])) == 3 and data["cylinder"].any() and (~data["cylinder"]).any()
    lo, hi = QUICK.sim.world.radius_range
    radii = data["radius"][data["cylinder"]]
    assert (radii >= lo - 1e-6).all() and (radii <= hi + 1e-6).all()
    assert (data["radius"][~data["cylinder"]] == 0).all()
    again = piece_views(profile, progress=False)  # same seed, same bytes
    assert all(np.array_equal(data[k], again[k]) for k in data)
    world = FastSimulator(QUICK.sim).load(int(data["world_seed"][0]))
    poses = view_poses(world, 50, np.random.default_rng(0), 9.0)
    gap = np.hypot(*(poses[:, None, :2] - world.obstacles[None, :, :2]).transpose(2, 0, 1))
    assert (gap > world.obstacles[None, :, 2] + world.config.robot_radius).all()
    assert (np.abs(poses[:, 1]) + world.config.robot_radius <= world.wall_y).all()


def test_the_disc_map_moves_with_the_robot_and_forgets_behind():
    dmap = DiscMap(_net(), QUICK.sim, forget_behind=1.0)
    dmap.discs = np.array([[2.0, 0.5, 0.2], [0.5, -1.0, 0.3]])
    dmap.move(1.0, 0.4)
    np.testing.assert_allclose(dmap.discs, [[1.0, 0.1, 0.2], [-0.5, -1.4, 0.3]])
    dmap.move(1.0, 0.0)
    np.testing.assert_allclose(dmap.discs, [[0.0, 0.1, 0.2]])  # the second fell 1.5 m behind


def test_a_disc_the_camera_sees_through_is_dropped_and_one_it_cannot_see_is_kept():
    """Where the camera looks now it is the truth; beside the robot, memory is."""
    sim = FastSimulator(QUICK.sim)
    sim.load(_lone_cylinder(30.0, 0.0, 0.2))  # nothing within far: an empty view
    image = sim.depth(np.zeros((1, 3)))[0]
    dmap = DiscMap(_net(), QUICK.sim)
    dmap.discs = np.array([[3.0, 0.0, 0.3], [0.3, 2.0, 0.3]])  # ahead in view; beside, out of view
    dmap.add(image)  # (the walls' pieces may add discs of their own: this net is untrained)
    assert any(np.allclose(disc, [0.3, 2.0, 0.3]) for disc in dmap.discs)
    assert not any(np.allclose(disc, [3.0, 0.0, 0.3]) for disc in dmap.discs)


def test_the_truth_reading_reference_uses_only_rendered_cylinders():
    """The privileged reference claims to know only what images have shown: every disc it plans with
    is a cylinder some image so far rendered, never a hidden one."""
    sim = FastSimulator(QUICK.sim)
    planner = TrueDiscsPlanner(QUICK.sim)
    eyes = FastSimulator(QUICK.sim)
    hidden = 0
    for seed in eval_world_seeds(8, TEST_SET):
        world = eyes.load(int(seed))
        rendered: set[int] = set()
        original_act = planner.act

        def spy(obs, pose=None, _act=original_act, _seen=rendered, _cyl=world.obstacles):
            _seen.update(eyes.visible_obstacles(pose).tolist())
            action = _act(obs, pose)
            for x, y, _ in planner.map.discs:  # robot frame -> world (heading 0 at every decision)
                found = np.flatnonzero(np.hypot(_cyl[:, 0] - pose[0] - x, _cyl[:, 1] - pose[1] - y) < 1e-6)
                assert len(found) == 1 and int(found[0]) in _seen
            return action

        planner.act = spy
        run_episode(planner, sim, int(seed))
        del planner.act
        hidden += len(world.obstacles) - len(rendered)
    assert hidden > 0, "some cylinder should stay hidden from every image (else the test proves nothing)"


def test_bad_disc_planner_arguments():
    with pytest.raises(PlannerError, match="bad arguments"):
        make_planner("discs", profile=QUICK, horizon_steps=3)
    with pytest.raises(PlannerError, match="is learned: pass profile="):
        make_planner("discs")


@pytest.fixture(scope="module")
def trained():
    planner = checkpoints.trained("discs")  # a missing network fails, naming the command that trains it
    assert isinstance(planner, DiscPlanner) and not planner.privileged
    sim = FastSimulator(QUICK.sim)
    return {name: evaluate(p, WORLDS, TEST_SET, sim=sim, progress=False)
            for name, p in (("discs", planner), ("mapping", make_planner("mapping")),
                            ("heuristic", make_planner("heuristic")))}


def test_the_disc_planner_beats_the_heuristic(trained):
    """Non-overlapping exact 95% intervals on 200 worlds of the test-only set."""
    assert trained["discs"].success_ci95[0] > trained["heuristic"].success_ci95[1]


def test_the_disc_planner_crosses_more_worlds_than_the_mapping_planner(trained):
    """The strongest ordering 200 quick worlds support: more successes than the classical planner over
    its raw scan points (their intervals overlap at this size; the full profile's tables in chapter 8)."""
    assert trained["discs"].success_rate > trained["mapping"].success_rate


def _first_move(planner, sim: FastSimulator, world: World) -> int:
    from husky_course.planners.base import episode_start

    sim.load(world)
    planner.reset(episode_start(planner, sim, world.seed, world.start, sim.config.max_primitives))
    return planner.act(sim.depth(world.start[None])[0], world.start.copy())


def test_references_that_know_only_what_images_showed_ignore_a_hidden_cylinder():
    """A world whose unrendered cylinder changes the oracle's first move: the references that claim to
    use only rendered cylinders (perfect perception of the seen; discs read from the truth) make the
    same first move with it and without it."""
    from dataclasses import replace

    from husky_course.planners.oracle import OraclePlanner
    from husky_course.planners.reference import SeenObstaclesPlanner

    sim = FastSimulator(QUICK.sim)
    for seed in eval_world_seeds(40, TEST_SET):
        world = sim.load(int(seed))
        hidden = sorted(set(range(len(world.obstacles))) - set(sim.visible_obstacles(world.start).tolist()))
        for i in hidden:
            without = replace(world, obstacles=np.delete(world.obstacles, i, axis=0))
            if _first_move(OraclePlanner(), sim, world) != _first_move(OraclePlanner(), sim, without):
                for reference in (SeenObstaclesPlanner(memory=True), TrueDiscsPlanner(QUICK.sim)):
                    assert _first_move(reference, sim, world) == _first_move(reference, sim, without)
                return
    pytest.fail("no world of the test set has a hidden cylinder that changes the oracle's first move")


def test_the_told_disc_planner_is_told_exactly_what_its_rule_gives(monkeypatch):
    """Chapter 10's ladder: the moving disc planner's map told the truth. Told every cylinder seen, its
    map holds exactly the cylinders the first image rendered, where they are, with their true motion
    (no other); told every disc's motion, or its first sights' (here the discs of pieces tracked once),
    each such disc on a cylinder walks with that cylinder's true velocity."""
    from husky_course.config import with_world
    from husky_course.planners.base import episode_start
    from husky_course.planners.reference import TOLD_RULES, ToldDiscsPlanner, truth_in_frame

    monkeypatch.setattr("husky_course.training.discs.load_discs", lambda profile: (_net(), None, ""))
    moving = with_world(QUICK, "moving")
    sim = FastSimulator(moving.sim)
    for seed in eval_world_seeds(40, TEST_SET):
        world = sim.load(int(seed))
        seen = sim.visible_obstacles(world.start, 0.0)
        if (world.speeds[seen] != 0).any() and len(seen) < len(world.obstacles):
            break
    else:
        pytest.fail("no world of the test set shows a walking cylinder in its first image")
    cyl, velocity = truth_in_frame(world, world.start, 0.0)
    assert (velocity[seen] != 0).any()
    obs = sim.depth(world.start[None], 0)[0]
    for rule in TOLD_RULES[::-1]:
        planner = ToldDiscsPlanner(QUICK, rule)
        planner.reset(episode_start(planner, sim, int(seed), world.start.copy(), moving.sim.max_primitives))
        planner.act(obs, world.start.copy())
        m = planner.map
        if rule == TOLD_RULES[2]:
            np.testing.assert_allclose(m.discs, cyl[np.sort(seen)])
            np.testing.assert_allclose(m.speeds, velocity[np.sort(seen)])
            continue
        gap = np.hypot(m.discs[:, :1] - cyl[:, 0], m.discs[:, 1:2] - cyl[:, 1]) - cyl[:, 2]
        told = (gap.min(1) < 0.3) & (m.fresh | (rule == TOLD_RULES[1]))  # a first sight: a piece tracked once
        assert (velocity[gap.argmin(1)][told] != 0).any()  # some told disc walks: the check can fail
        np.testing.assert_allclose(m.speeds[told], velocity[gap.argmin(1)][told])
        np.testing.assert_array_equal(m.speeds[~told & (gap.min(1) >= 0.3)], 0.0)  # on no cylinder: stands
    with pytest.raises(ValueError, match="rule must be one of"):
        ToldDiscsPlanner(QUICK, "every secret")
