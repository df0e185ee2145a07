"""The side walls as the moving disc planner knows them (:mod:`husky_course.planners.walls`)."""

from __future__ import annotations

import numpy as np
import pytest

from husky_course.config import MovingWorldConfig, WallsConfig
from husky_course.planners.walls import NO_WALLS, bounced, walk_on, wall_faces
from husky_course.sim.world import make_world


def test_a_cylinder_bounces_as_the_course_moves_it() -> None:
    """In a frame shifted by the robot's unknown ``y``, :func:`bounced` follows the course's own
    triangle wave (``World.obstacle_y``) for every walking cylinder, many bounces on."""
    cfg = MovingWorldConfig()
    world = next(w for w in (make_world(s, cfg) for s in range(50)) if len(w.moving) >= 3)
    robot_y = 1.3
    faces = (-world.wall_y - robot_y, world.wall_y - robot_y)
    t = np.arange(0.0, 40.0, 0.25)
    for i in world.moving:
        x, y, r = world.obstacles[i]
        truth = world.obstacle_y(np.array([i]), t[None])[0] - robot_y
        y0 = world.obstacle_y(np.array([i]), np.zeros((1, 1)))[0, 0] - robot_y
        np.testing.assert_allclose(bounced(y0, world.speeds[i], t, r, faces), truth, atol=1e-9)


def test_without_faces_or_motion_a_walk_is_straight() -> None:
    t = np.arange(5.0)
    np.testing.assert_allclose(bounced(4.0, 0.5, t, 0.3, NO_WALLS), 4.0 + 0.5 * t)
    np.testing.assert_allclose(bounced(4.0, 0.0, t, 0.3, (-5.0, 5.0)), np.full(5, 4.0))


def test_walk_on_turns_a_disc_at_a_face() -> None:
    discs = np.array([[3.0, 4.5, 0.3], [3.0, 0.0, 0.3], [3.0, -4.0, 0.3]])
    y, v = walk_on(discs, np.array([0.5, -0.4, 0.0]), (-5.0, 5.0))
    np.testing.assert_allclose(y, [4.4, -0.4, -4.0])  # 4.5 + 0.5 passes the face at 4.7 by 0.3: 4.4
    np.testing.assert_allclose(v, [-0.5, -0.4, 0.0])


def test_the_faces_are_read_off_a_wall_of_points() -> None:
    """A line of points along the course beyond ``beyond`` is a face; the width gives the other; a
    few scattered points are none, and then the previous faces stay."""
    cfg = WallsConfig()
    x = np.linspace(1.0, 5.0, 12)
    left = np.c_[x, np.full(12, 3.62), np.zeros(12)]
    scattered = np.array([[2.0, 3.0, 0.0], [3.0, -3.4, 0.0], [4.0, -4.1, 0.0], [1.0, 0.5, 0.0]])
    lo, hi = wall_faces(np.r_[left, scattered], 10.0, config=cfg)
    assert hi == pytest.approx(3.62) and lo == pytest.approx(3.62 - 10.0)
    right = np.c_[x, np.full(12, -6.1), np.zeros(12)]
    assert wall_faces(right, 10.0, config=cfg) == pytest.approx((-6.1, 3.9))
    assert wall_faces(scattered, 10.0, (-7.0, 3.0), cfg) == (-7.0, 3.0)
    assert wall_faces(np.empty((0, 3)), 10.0) == NO_WALLS
    near = np.c_[x, np.full(12, 1.5), np.zeros(12)]  # a line, but not beyond 2.5 m: not a wall
    assert wall_faces(near, 10.0) == NO_WALLS


def _walking_map():
    import torch

    from husky_course.config import get_profile, with_world
    from husky_course.models.discs import DiscNet
    from husky_course.planners.moving_discs import DiscTrackingPlanner

    profile = with_world(get_profile("quick"), "moving")
    torch.manual_seed(0)
    planner = DiscTrackingPlanner(DiscNet(profile.sim.world.radius_range).eval(), profile.sim)
    return planner, planner.map


def test_the_disc_map_reads_the_faces_and_its_discs_bounce_off_them() -> None:
    """After a step the map reads the faces off its wall points (shifted by the robot's own move) and
    a disc walking into one comes back; with no wall seen, the faces stay where dead reckoning puts them."""
    planner, disc_map = _walking_map()
    x = np.linspace(1.0, 5.0, 12)
    disc_map.walls.points = np.c_[x, np.full(12, 4.0), np.full(12, 0.05)]
    disc_map.discs = np.array([[3.0, 3.4, 0.3], [3.0, 0.0, 0.3]])
    disc_map.speeds, disc_map.fresh = np.array([0.5, 0.5]), np.zeros(2, bool)
    disc_map.move(1.0, 0.2)  # the robot moved 0.2 m left: the wall at 3.8; the disc at 3.2 walks to 3.7, past
    assert disc_map.faces == pytest.approx((3.8 - 10.0, 3.8))  # its limit 3.5 by 0.2: back to 3.3
    np.testing.assert_allclose(disc_map.discs[:, 1], [3.3, 0.3], atol=1e-9)
    np.testing.assert_allclose(disc_map.speeds, [-0.5, 0.5])
    disc_map.walls.points = np.empty((0, 3))
    disc_map.move(1.0, -0.5)
    assert disc_map.faces == pytest.approx((4.3 - 10.0, 4.3))


def test_the_search_sees_a_walker_come_back_from_the_wall() -> None:
    """The space-time check places a walking disc where the bounce puts it: with the faces known, a
    plan through the place it returns to is blocked later on; without them it is not."""
    planner, disc_map = _walking_map()
    from husky_course.planners.base import EpisodeStart
    from husky_course.sim.primitives import make_library

    library = make_library(planner.config.primitives)
    planner.reset(EpisodeStart(library=library, max_primitives=planner.config.max_primitives, key=0))
    disc_map.discs = np.array([[3.0, 1.0, 0.3]])
    disc_map.speeds, disc_map.fresh = np.array([0.6]), np.zeros(1, bool)
    x0, y0 = 2.0, np.array([0.0])  # an edge from 2 m ahead, two steps from now: the disc is at 2.2 straight
    straight = planner._start_check()(x0, y0, 2.0)[1]
    disc_map.faces = (-10.0 + 1.6, 1.6)  # the face 1.6 m to the left: it turned back at 1.3
    back = planner._start_check()(x0, y0, 2.0)[1]
    assert (back < straight - 0.2).any()


def test_the_wall_rule_is_part_of_the_planners_stored_key() -> None:
    """``WallsConfig``'s values live in the disc map's state, so a stored evaluation of the planner
    (keyed by its whole state; config modules are not in the code fingerprint) changes with them."""
    import dataclasses

    from husky_course.evaluation.stored import planner_fingerprint

    planner, disc_map = _walking_map()
    before = planner_fingerprint(planner)
    disc_map.wall_rule = dataclasses.replace(disc_map.wall_rule, points=disc_map.wall_rule.points + 1)
    assert planner_fingerprint(planner) != before


def test_the_trackers_walking_points_bounce_off_the_faces_of_its_wall_points() -> None:
    """The tracker's map reads the faces off the points of its long pieces (walls), not off a
    cylinder's points, and a walking point turns back at the face; without ``bounce`` it walks on."""
    from husky_course.config import SimConfig, sim_for_world
    from husky_course.planners.motion import WalkingMap

    config = sim_for_world(SimConfig(), "moving")
    walls = np.c_[np.linspace(1.0, 5.0, 12), np.full(12, -3.0), np.full(12, 0.05)]  # a face at y = -3
    crowd = np.c_[np.full(8, 2.0), np.full(8, 3.0), np.full(8, 0.05)]  # a cylinder's points, not a wall
    walker = np.array([[2.5, -2.7, 0.05]])  # 0.25 m from touching the face, walking 0.6 m a step: to -2.6
    ys = {}
    for bounce in (False, True):
        walking = WalkingMap(config, forget_behind=1.8, bounce=bounce)
        walking.map.points = np.concatenate([walker, walls, crowd])
        walking.velocity = np.r_[-0.6, np.zeros(20)]
        walking.fresh, walking.wall = np.zeros(21, bool), np.r_[False, np.ones(12, bool), np.zeros(8, bool)]
        walking.move(0.0, 0.0)
        ys[bounce] = (walking.map.points[0, 1], walking.velocity[0], walking.faces)
    assert ys[False][0] == pytest.approx(-3.3) and ys[False][2] == NO_WALLS
    assert ys[True][2] == pytest.approx((-3.0, config.world.width - 3.0))
    assert ys[True][0] == pytest.approx(-2.6) and ys[True][1] == pytest.approx(0.6)


def test_the_space_time_check_counts_every_walker_within_reach_and_skips_only_the_rest() -> None:
    """For each state it judges, the check skips a walker whose walk stays further than a reach and its
    radius beside every sample of that state's edges (it could not lower a gap capped at the reach).
    Against a brute force over every walker and sample, with walkers near the states, far beside them,
    and one that only comes back among them off a wall, the clearances agree to the bit, and the near
    walkers do matter."""
    from husky_course.planners.base import EpisodeStart
    from husky_course.sim.primitives import make_library
    from husky_course.sim.world import sample_times

    planner, disc_map = _walking_map()
    library = make_library(planner.config.primitives)
    planner.reset(EpisodeStart(library=library, max_primitives=planner.config.max_primitives, key=0))
    rng = np.random.default_rng(3)
    near = np.c_[rng.uniform(2.0, 4.0, 6), rng.uniform(-2.0, 2.0, 6), rng.uniform(0.2, 0.4, 6)]
    far = np.c_[rng.uniform(2.0, 4.0, 4), rng.choice((-1, 1), 4) * rng.uniform(6.0, 8.0, 4), np.full(4, 0.3)]
    back = np.array([[3.0, 3.4, 0.3]])  # walking left into the face at 3.9: back among the states later
    disc_map.discs = np.r_[near, far, back]
    disc_map.speeds = np.r_[rng.choice((-1, 1), 6) * rng.uniform(0.2, 0.6, 6), [0.3, -0.3, 0.5, -0.5], [0.6]]
    disc_map.fresh = np.zeros(len(disc_map.discs), bool)
    disc_map.faces = (3.9 - 10.0, 3.9)
    x0, y0, t0 = 2.0, np.linspace(-1.0, 1.0, 7), 1.0
    hit, clear = planner._start_check()(x0, y0, t0)

    local = library.local_paths
    every = max(1, (local.shape[1] - 1) // (planner.path_samples - 1))
    x, ly, t = local[:, ::every, 0], local[:, ::every, 1], sample_times(0.0, local.shape[1])[::every]
    reach = planner._reach
    gap = np.full((len(y0), len(x)), reach)
    for px, py, r, v in np.c_[disc_map.discs, disc_map.speeds]:
        if not x0 + x.min() - reach < px < x0 + x.max() + reach:
            continue
        walk = bounced(py, v, t0 + t, r, disc_map.faces)
        dx, dy = x0 + x - px, y0[:, None, None] + ly[None] - walk
        d = np.sqrt((dx**2 + dy**2).min(-1)) - r  # the check's own arithmetic: the skip must change no bit
        np.testing.assert_allclose(d, (np.hypot(dx, dy) - r).min(-1), rtol=0, atol=1e-12)  # the distance
        gap = np.minimum(gap, d)
    expected = gap - planner.radius - planner.margin
    np.testing.assert_array_equal(clear, expected)
    np.testing.assert_array_equal(hit, expected < 0)
    assert (clear < reach - planner.radius - planner.margin - 0.1).any()  # the walkers near do count
