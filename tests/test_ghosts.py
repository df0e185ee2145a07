"""Ghosts of the moving disc planner (``husky_course.planners.ghosts``): the tracks' names, which dropped disc
becomes a ghost, which image ends it, and the planner's draws standing it at its open walks."""

from __future__ import annotations

import numpy as np
import pytest

from husky_course.config import ArrivalsConfig, get_profile, with_world
from husky_course.course import exercises
from husky_course.evaluation.episodes import eval_world_seeds
from husky_course.sim.fast import FastSimulator

QUICK = get_profile("quick")
MOVING = with_world(QUICK, "moving")


def _arc(centre: tuple[float, float], radius: float = 0.3) -> np.ndarray:
    """The scan points a cylinder gives the camera."""
    return exercises.cylinder_points(np.array(centre), radius, MOVING.sim)


def _ghosts():
    from husky_course.planners.arrivals import Arrivals
    from husky_course.planners.ghosts import Ghosts

    arrivals = Arrivals(MOVING.sim)
    return Ghosts(arrivals, MOVING.sim.world.moving_fraction, ArrivalsConfig.ghost_age), arrivals


def test_tracks_name_their_tracks_and_say_which_pieces_continue_one():
    """A piece that continues a track keeps its name and is marked continued; a new piece gets a new name;
    a piece over 1 m long (a wall) is not tracked (-1)."""
    from husky_course.planners.motion import MotionMemory

    m = MotionMemory(MOVING.sim)
    wall = np.c_[np.full(30, 3.0), np.linspace(-2.5, -1.2, 30)]
    names = []
    for k in range(3):
        arcs = [_arc((4.0 - k, 0.8)), _arc((3.5 - k, -0.4 + 0.3 * k))]
        arcs += [_arc((3.0, 1.8))] if k == 2 else []  # a new cylinder
        scan = np.concatenate([wall - (k, 0.0), *arcs])
        sizes = np.cumsum([0, len(wall), *map(len, arcs)])
        pieces = [np.arange(a, b) for a, b in zip(sizes[:-1], sizes[1:], strict=True)]
        m.update(scan, pieces)
        t = m.tracks
        assert len(t.piece_names) == len(pieces) and t.piece_names[0] == -1 and not t.continued[0]
        assert len(t.names) == len(t.tracks)
        names.append(t.piece_names.tolist())
        assert t.continued[1:3].tolist() == [k > 0, k > 0]
        m.move(1.0, 0.0)
    assert names[0][1:] == names[1][1:] == names[2][1:3]  # the same two cylinders, the same names
    assert names[0][1] != names[0][2] and names[2][3] not in names[2][1:3]  # a new cylinder, a new name
    assert not m.tracks.continued[3]
    m.reset()
    assert m.tracks.names == [] and len(m.tracks.piece_names) == 0


def test_a_cylinder_is_found_by_its_own_track_or_by_an_untracked_disc_landing_on_it():
    """``found``: 1 where a new disc continues the disc's own track (however far it moved), 2 where a new
    disc that continues no earlier track lands on it (any new disc, for a disc without a track), and 0
    where only a disc continuing another cylinder's track lands on it."""
    from husky_course.planners.ghosts import found

    discs = np.array([[3.0, 0.0, 0.3], [3.0, 2.0, 0.3], [3.0, -2.0, 0.3]])
    names = np.array([5, 6, -1])
    new = np.array([[3.0, 0.1, 0.3], [3.0, 2.5, 0.3], [3.0, -2.05, 0.3]])
    new_names, strange = np.array([7, 6, 7]), np.array([False, False, False])
    assert found(discs, names, new, new_names, strange).tolist() == [0, 1, 2]
    assert found(discs, names, new, new_names, np.array([True, False, False])).tolist() == [2, 1, 2]
    assert found(discs, names, new[:0], new_names[:0], strange[:0]).tolist() == [0, 0, 0]


def test_a_ghost_keeps_the_walks_no_image_ruled_out_and_ends_when_its_cylinder_is_found():
    """A disc an image sees through, with no new disc its cylinder, becomes a ghost: one hypothesis per walk
    from where its disc was made. A later image that sees through all but the walks one way closes the
    others. A disc continuing another track over an open walk leaves it; its own track, or an untracked disc
    over an open walk, ends it; so does closing every walk."""
    ghosts, arrivals = _ghosts()
    h, far = arrivals.hypotheses, arrivals.camera.far
    disc, blind = np.array([[3.0, 0.0, 0.3]]), np.full(MOVING.sim.camera.size, 1.0)  # a wall at 1 m: no news
    none, no_names = np.empty((0, 3)), np.zeros(0, int)
    ghosts.update(blind, disc, np.zeros(1), np.array([2]), np.array([9]), np.array([True]), none, no_names,
                  np.zeros(0, bool))
    assert len(ghosts) == 1
    g = ghosts.items[0]
    np.testing.assert_allclose(g.ys, 2 * h)  # two steps old, standing: each walk from where it was made
    assert g.open.all() and g.name == 9 and g.life == 2
    right = np.isfinite(arrivals.front(g.x, g.ys[h > 0], g.r)).any(0)  # the columns the rightward walks cover
    ghosts.update(np.where(right, 1.0, far), np.empty((0, 3)), np.zeros(0), no_names, no_names,
                  np.zeros(0, bool), none, no_names, np.zeros(0, bool))
    assert len(ghosts) == 1 and g.open[h > 0].all() and not g.open[h <= 0].any()
    walk = np.array([[g.x, g.ys[np.argmax(h)], 0.3]])
    args = (blind, np.empty((0, 3)), np.zeros(0), no_names, no_names, np.zeros(0, bool))
    ghosts.update(*args, walk, np.array([4]), np.array([False]))  # another cylinder's track
    assert len(ghosts) == 1
    ghosts.update(*args, walk + (0.0, 3.0, 0.0), np.array([9]), np.array([False]))  # its own track, far off
    assert len(ghosts) == 0
    ghosts.items = [g]
    ghosts.update(*args, walk, np.array([11]), np.array([True]))  # a first sight over an open walk
    assert len(ghosts) == 0
    ghosts.items = [g]
    ghosts.update(np.full(MOVING.sim.camera.size, far), *args[1:], none, no_names, np.zeros(0, bool))
    assert len(ghosts) == 0  # every walk seen through


def test_no_ghost_of_a_cylinder_the_tracks_found_or_of_a_disc_too_old():
    """No ghost is made where a new disc continues the disc's track, nor of a disc older than
    ``ghost_age`` steps; ghosts walk on after each step, bouncing off the faces, and end when they age past
    it or fall behind."""
    ghosts, arrivals = _ghosts()
    h, blind = arrivals.hypotheses, np.full(MOVING.sim.camera.size, 1.0)
    disc, none = np.array([[3.0, 0.0, 0.3]]), np.empty((0, 3))
    seen = np.array([True])
    ghosts.update(blind, disc, np.zeros(1), np.array([1]), np.array([3]), seen, disc + (0.0, 0.2, 0.0),
                  np.array([3]), np.array([False]))
    assert len(ghosts) == 0
    ghosts.update(blind, disc, np.zeros(1), np.array([ghosts.age + 1]), np.array([3]), seen, none,
                  np.zeros(0, int), np.zeros(0, bool))
    assert len(ghosts) == 0
    ghosts.update(blind, disc, np.zeros(1), np.array([1]), np.array([3]), seen, none, np.zeros(0, int),
                  np.zeros(0, bool))
    g = ghosts.items[0]
    ghosts.move(0.5, 0.0, (-10.0, 10.0), 1.8)
    assert g.x == 2.5 and g.life == 2
    np.testing.assert_allclose(g.ys, 2 * h)  # made one step old: one more step of each walk
    ghosts.move(0.5, 0.0, (-10.0, 0.5), 1.8)  # a face at y = 0.5: the walks up turn back
    assert (g.ys + g.r <= 0.5 + 1e-9).all() and (g.vs[g.ys + g.r > 0.5 - 1e-9] <= 0).all()
    for _ in range(ghosts.age - 3):
        ghosts.move(0.5, 0.0, (-10.0, 10.0), 1.8)
    assert len(ghosts) == 1 and g.life == ghosts.age
    ghosts.move(0.5, 0.0, (-10.0, 10.0), 1.8)
    assert len(ghosts) == 0
    ghosts.items = [g]
    g.life = 1
    ghosts.move(5.0, 0.0, (-10.0, 10.0), 1.8)  # behind the robot
    assert len(ghosts) == 0


def test_the_planners_draws_stand_each_ghost_at_an_open_walk():
    """The disc planner (an untrained network) on the moving course: its map keeps ghosts (none on the
    static course, or with ``ghosts`` off); a ghost joins the points only within a draw, at one of its open
    walks, and a standing ghost straight ahead changes how the first primitives rank."""
    import torch

    from husky_course.evaluation.rollout import Rollout
    from husky_course.models.discs import DiscNet
    from husky_course.planners.ghosts import TINY, Ghost
    from husky_course.planners.moving_discs import DiscTrackingPlanner

    torch.manual_seed(0)
    net = DiscNet(MOVING.sim.world.radius_range).eval()
    assert DiscTrackingPlanner(net, QUICK.sim).map.dropped is None
    assert DiscTrackingPlanner(net, MOVING.sim, ghosts=False).map.dropped is None
    with pytest.raises(ValueError, match="age"):
        DiscTrackingPlanner(net, MOVING.sim, ghost_age=0)
    planner = DiscTrackingPlanner(net, MOVING.sim, samples=4)
    sim = FastSimulator(MOVING.sim)
    next(iter(Rollout(planner, sim, int(eval_world_seeds(1, 1)[0]), 5)))
    ghosts, h = planner.map.dropped, planner.map.arrivals.hypotheses
    ghosts.items = []
    before = planner._decide(planner.horizon)
    n = len(planner.points)
    ghosts.items = [Ghost(1.2, 0.3, np.zeros(len(h)), h.copy(), h == 0, 1, -1)]  # standing, straight ahead
    assert len(planner.points) == n
    drawn: list[tuple[np.ndarray, np.ndarray]] = []
    keys_if = planner._keys_if

    def record(horizon, speeds):
        drawn.append((planner.points.copy(), np.asarray(speeds).copy()))
        return keys_if(horizon, speeds)

    planner._keys_if = record
    after = planner._decide(planner.horizon)
    assert len(drawn) == 4 and ghosts.draw is None and len(planner.points) == n
    for points, speeds in drawn:
        assert len(points) == len(speeds) == n + 1
        np.testing.assert_allclose(points[-1], [1.2, 0.0, 0.3])
        assert speeds[-1] == TINY
    assert not np.array_equal(before[1], after[1])
