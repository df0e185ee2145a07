"""Reading motion off successive depth scans (chapter 10): pieces of surface, fitted circles,
tracks, and the map whose points walk (``husky_course.planners.motion``)."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

import numpy as np

from husky_course.config import get_profile, with_world
from husky_course.course import exercises
from husky_course.evaluation.episodes import eval_world_seeds
from husky_course.sim.fast import FastSimulator

QUICK = get_profile("quick")
MOVING = with_world(QUICK, "moving")
BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


def _benchmark(name: str) -> ModuleType:
    """The script ``benchmarks/<name>.py`` as a module (its ``main`` is not run)."""
    spec = importlib.util.spec_from_file_location(name, BENCH / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _arc(centre: tuple[float, float], radius: float) -> np.ndarray:
    """The scan points a cylinder gives the camera: the columns' rays cut with its circle."""
    return exercises.cylinder_points(np.array(centre), radius, MOVING.sim)


def test_piece_centre_locates_a_cylinder():
    """The fitted circle finds a cylinder's centre from the few columns that hit it (the points'
    mean is pulled towards the camera and jumps as the columns change)."""
    from husky_course.planners.pieces import piece_centre

    for cx, cy, r in [(2.0, 0.3, 0.2), (3.0, -0.8, 0.3), (3.0, 1.2, 0.25), (1.6, -1.0, 0.35)]:
        pts = _arc((cx, cy), r)
        assert len(pts) >= 2
        found = piece_centre(pts, MOVING.sim.camera.mount_forward, 0.25)
        assert abs(found[1] - cy) < 0.05  # across: what motion is read from
        assert abs(found[0] - cx) < 0.1  # along the ray: off by about the radius prior's error
        assert np.hypot(*(pts.mean(0) - (cx, cy))) > 0.1  # the mean is off by most of a radius


def test_piece_centre_fills_its_system_in_place_with_the_same_numbers_as_stacking_it():
    """Each Gauss-Newton step's system is filled in place; stacked anew at every step (as it once was),
    the same centres to the bit: the tracks, the disc maps and the artifacts built on them are unchanged."""
    from husky_course.planners.pieces import piece_centre

    def stacked(p: np.ndarray, camera_x: float, radius: float) -> np.ndarray:
        mean = p.mean(0)
        ray = mean - (camera_x, 0.0)
        c, r = mean + 0.8 * radius * ray / max(float(np.hypot(*ray)), 1e-9), radius
        for _ in range(8):
            d = p - c
            n = np.hypot(d[:, 0], d[:, 1]) + 1e-9
            jac = np.r_[np.c_[-d / n[:, None], -np.ones(len(p))], np.array([[0.0, 0.0, 1.0]])]
            step = np.linalg.lstsq(jac, -np.r_[n - r, r - radius], rcond=None)[0]
            c, r = c + step[:2], float(np.clip(r + step[2], 0.4 * radius, 2.0 * radius))
        return c

    rng = np.random.default_rng(3)
    for _ in range(200):
        radius = rng.uniform(0.1, 0.4)
        pts = _arc((rng.uniform(1.5, 5.0), rng.uniform(-2.0, 2.0)), radius)
        pts = pts + rng.normal(0.0, 0.01, pts.shape)  # a noisy scan
        if len(pts) and np.ptp(pts, axis=0).max() <= 1.0:
            assert piece_centre(pts, 0.3, radius).tobytes() == stacked(pts, 0.3, radius).tobytes()


def test_lateral_velocities_from_two_scans():
    """A cylinder that walked 0.4 m across between two scans is estimated to walk 0.4 m per step
    (the columns that hit it differ between the two); standing surfaces at 0; a piece with no match
    within one step's walk at 0; a second look averages with the first. The two-image estimator
    lives in the benchmark that compares it (``benchmarks/exp_moving_tracker.py``); the memory is the
    library's."""
    from husky_course.planners.motion import MotionMemory
    from husky_course.planners.pieces import segments

    lateral_velocities = _benchmark("exp_moving_tracker").lateral_velocities

    wall = np.c_[np.linspace(1.0, 4.0, 30), np.full(30, 2.5)]
    far = np.c_[np.full(5, 4.5), np.linspace(-3.0, -2.8, 5)]
    before = np.concatenate([wall, _arc((3.0, 0.0), 0.3)])
    arc = _arc((3.0, 0.4), 0.3)
    after = np.concatenate([wall, arc, far])
    assert [len(s) for s in segments(after)] == [30, len(arc), 5]
    m = MotionMemory(MOVING.sim)
    v = lateral_velocities(before, after, 0.6, camera_x=m.camera_x, radius=m.radius)
    np.testing.assert_allclose(v[30 : 30 + len(arc)], 0.4, atol=0.03)
    np.testing.assert_allclose(v[:30], 0.0, atol=1e-12)
    np.testing.assert_array_equal(v[30 + len(arc) :], 0.0)  # nothing near it before: taken as standing
    assert (lateral_velocities(before, after, max_step=0.3)[30 : 30 + len(arc)] == 0).all()  # too fast
    assert (lateral_velocities(np.empty((0, 2)), after, 0.6) == 0).all()
    # the memory, over three images, the robot standing still: the second look averages
    assert (m.update(before) == 0).all()
    np.testing.assert_allclose(m.update(after)[30 : 30 + len(arc)], 0.4, atol=0.03)
    third = np.concatenate([wall, _arc((3.0, 0.6), 0.3)])
    np.testing.assert_allclose(m.update(third)[30:], (0.2 + 0.4) / 2, atol=0.03)
    m.move(1.0, 0.0)
    np.testing.assert_allclose(m.previous, third - [1.0, 0.0])


def test_walking_map_points_walk_on():
    """The moving course's map: a point keeps its velocity and walks one step per primitive (also
    where the camera no longer sees it); dead reckoning moves everything by the robot's displacement."""
    from husky_course.planners.motion import WalkingMap

    sim = FastSimulator(MOVING.sim)
    world = sim.load(int(eval_world_seeds(1, 1)[0]))
    walking = WalkingMap(MOVING.sim, forget_behind=1.0)
    first = walking.add(sim.depth(world.start[None], 0)[0])
    assert (first == 0).all() and len(walking.points) == len(first)  # one image: nothing known to move
    walking.velocity[:] = 0.3  # as if every point had been seen walking
    before = walking.points.copy()
    np.testing.assert_allclose(walking.at(2.0)[:, 1], before[:, 1] + 0.6)
    walking.move(1.0, 0.2)
    kept = before[:, 0] - 1.0 > -1.0
    np.testing.assert_allclose(walking.points, before[kept] - [1.0, 0.2 - 0.3, 0.0])
    np.testing.assert_allclose(walking.motion.previous, walking.map.scan(sim.depth(world.start[None], 0)[0])
                               - [1.0, 0.2])


def test_segments_cut_two_cylinders_side_by_side():
    """Two touching cylinders give one run of close points; the peak of forward distance where
    their arcs meet cuts it in two. A wall along the course has no such peak and stays whole."""
    from husky_course.planners.pieces import segments

    left, right = _arc((1.6, 0.3), 0.3), _arc((1.6, -0.3), 0.3)
    assert np.hypot(*(left[-1] - right[0])) < 0.3  # close enough to be one piece by distance alone
    assert [len(s) for s in segments(np.concatenate([left, right]))] == [len(left), len(right)]
    wall = np.c_[np.linspace(1.0, 4.0, 30), np.full(30, 2.5)]
    assert [len(s) for s in segments(wall)] == [30]


def test_tracks_fit_a_weighted_line_through_their_looks():
    """A track's velocity is the weighted least-squares slope of its looks: a far, coarse look
    counts for little beside two near, precise ones; one look gives no velocity."""
    from husky_course.planners.motion import Tracks

    looks = np.array([[2.0, 4.0, 0.3, 0.3], [1.0, 3.0, 0.4, 0.02], [0.0, 2.0, 0.8, 0.02]])  # age, x, y, sigma
    y, v = Tracks.line(looks)
    assert abs(v - 0.4) < 0.01 and abs(y - 0.8) < 0.01  # the two precise looks' line
    assert abs(np.polyfit([-2, -1, 0], looks[:, 2], 1)[0] - 0.25) < 1e-9  # unweighted: pulled to 0.25
    assert Tracks.line(looks[:1]) == (0.3, 0.0)


def test_tracks_judge_a_slope_against_the_courses_motion_model():
    """With the motion model (40% walk, at 0.2 to 0.6 m per step), a slope within its error of 0
    reads as standing, a clear walk as itself, a walk faster than any cylinder's is clipped;
    without it (or with one look) the slope is the velocity, unjudged."""
    from husky_course.planners.motion import Tracks

    judge = Tracks(0.6, 0.3, 0.25, 0.02, 0.5, prior=(0.4, 0.2, 0.6))
    raw = Tracks(0.6, 0.3, 0.25, 0.02, 0.5)

    def track(v: float, sigma: float) -> np.ndarray:  # two looks one step apart: age, x, y, sigma
        return np.array([[1.0, 3.0, 0.0, sigma], [0.0, 2.0, v, sigma]])

    assert judge.judged(track(0.12, 0.1)) == 0.0  # coarse looks: 0.12 is noise about a standing one
    assert abs(raw.judged(track(0.12, 0.1)) - 0.12) < 1e-9
    assert abs(judge.judged(track(0.35, 0.02)) - 0.35) < 1e-9  # precise looks: a walk
    assert abs(judge.judged(track(-0.12, 0.02)) + 0.2) < 1e-9  # precise, too fast to stand: slowest walk
    assert abs(judge.judged(track(0.9, 0.05)) - 0.6) < 1e-9  # clipped to the fastest walk
    assert judge.judged(track(0.3, 0.02)[1:]) == 0.0  # one look: no velocity yet


def test_motion_memory_follows_a_walking_cylinder_as_the_robot_drives():
    """Driving 1 m per step towards a cylinder walking 0.4 m per step across: its first image
    gives no velocity (its points are marked seen once), later ones the walk; on the static
    course nothing walks and nothing is new."""
    from husky_course.planners.motion import MotionMemory

    m = MotionMemory(MOVING.sim)
    for k in range(3):
        scan = _arc((4.0 - k, -0.5 + 0.4 * k), 0.3)  # the robot's frame: it drove k metres
        v = m.update(scan)
        if k == 0:
            assert (v == 0).all() and m.tracks.fresh.all()
        else:
            np.testing.assert_allclose(v, 0.4, atol=0.05)
            assert not m.tracks.fresh.any()
        m.move(1.0, 0.0)
    still = MotionMemory(QUICK.sim)
    for k in range(2):
        assert (still.update(_arc((4.0 - k, 0.4 * k), 0.3)) == 0).all() and not still.tracks.fresh.any()
        still.move(1.0, 0.0)


def test_tracks_locate_a_piece_by_the_centre_they_are_given():
    """Given a centre per piece (the disc planner's network), a track's looks are those centres, not
    the fitted circle's: a standing cylinder whose given centres walk 0.4 m per step reads as walking;
    a ``nan`` centre leaves the fit, and without centres it stands."""
    from husky_course.planners.motion import MotionMemory
    from husky_course.planners.pieces import piece_centre

    told, fitted, partly = MotionMemory(MOVING.sim), MotionMemory(MOVING.sim), MotionMemory(MOVING.sim)
    for k in range(3):
        scan = _arc((4.0 - k, -0.5), 0.3)  # standing: the robot drove k metres towards it
        pieces = [np.arange(len(scan))]
        v = told.update(scan, pieces, np.array([[4.0 - k, -0.5 + 0.4 * k]]))
        np.testing.assert_allclose(told.tracks.tracks[0][-1, 1:3], [4.0 - k, -0.5 + 0.4 * k])
        np.testing.assert_allclose(v, 0.4 if k else 0.0, atol=1e-6)
        assert (fitted.update(scan) == 0).all()
        partly.update(scan, pieces, np.full((1, 2), np.nan))
        fit = piece_centre(scan, partly.camera_x, partly.radius)
        np.testing.assert_allclose(partly.tracks.tracks[0][-1, 1:3], fit)
        for memory in (told, fitted, partly):
            memory.move(1.0, 0.0)


def test_the_disc_maps_tracks_follow_its_network_centres_of_cylinder_pieces_only():
    """The disc map hands its tracks the network's disc centre of each piece it reads as a cylinder
    (``TrackingConfig.disc_centres``), and the fit for the others; switched off, the fit for all."""
    import torch

    from husky_course.config import TrackingConfig
    from husky_course.models.discs import DiscNet
    from husky_course.planners.moving_discs import DiscTrackingPlanner
    from husky_course.planners.pieces import piece_centre

    assert TrackingConfig.disc_centres
    sim = FastSimulator(MOVING.sim)
    world = sim.load(int(eval_world_seeds(1, 1)[0]))
    obs = sim.depth(world.start[None], 0.0)[0]
    looked = {}
    for centres in (True, False):
        torch.manual_seed(0)
        disc_map = DiscTrackingPlanner(DiscNet(MOVING.sim.world.radius_range).eval(), MOVING.sim,
                                       centres=centres).map
        net = disc_map.forward

        def alternate(x: np.ndarray, net=net) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
            logit, offset, radius = net(x)  # every other piece a cylinder, the rest not
            return np.where(np.arange(len(logit)) % 2, 1.0, -1.0) * np.abs(logit), offset, radius

        disc_map.forward = alternate
        d, cols, pts, pieces = disc_map.reader.pieces(obs)
        discs, cyl, _ = disc_map.decode(d, cols, pts, pieces)
        small = [k for k, idx in enumerate(pieces) if np.ptp(pts[idx], axis=0).max() <= 1.0]
        assert cyl[small].any() and not cyl[small].all()  # both kinds, for the check to mean something
        disc_map.add(obs)
        looks = np.array([t[-1, 1:3] for t in disc_map.motion.tracks.tracks])
        fits = np.array([piece_centre(pts[pieces[k]], disc_map.motion.camera_x, disc_map.motion.radius)
                         for k in small])
        expect = np.where(cyl[small, None] & centres, discs[small, :2], fits)
        np.testing.assert_allclose(looks, expect)
        looked[centres] = looks
    assert not np.allclose(looked[True], looked[False])


def test_tracks_unfold_a_walk_that_bounced_off_a_face_between_looks():
    """A walker going up at 0.5 m per step that turned at the left face (centre 4.75) between two
    looks reads as walking down at 0.5, not standing (its straight line is flat); a straight walk,
    a standing one, and any track while the faces are unknown read as before; a line walking into
    a face is predicted back off it."""
    from husky_course.planners.motion import Tracks
    from husky_course.planners.walls import NO_WALLS, reflected_line

    tracks = Tracks(0.6, 0.45, 0.25, 0.05, 2.1, prior=(0.4, 0.2, 0.6))

    def looks(*y: float) -> np.ndarray:  # ages 3, 2, 1, 0: age, x, y, sigma
        return np.c_[np.arange(len(y))[::-1], np.full(len(y), 2.0), y, np.full(len(y), 0.05)]

    folded, straight = looks(4.0, 4.5, 4.5, 4.0), looks(3.0, 3.5, 4.0, 4.5)
    standing = looks(3.0, 3.02, 2.98, 3.0)
    assert tracks.judged(folded) == 0.0 and abs(Tracks.line(folded)[1]) < 1e-9  # faces unknown: standing
    tracks.faces = (-5.0, 5.0)
    y, v = tracks.walk(folded)
    assert abs(v + 0.5) < 1e-9 and abs(y - 4.0) < 1e-9 and abs(tracks.judged(folded) + 0.5) < 1e-9
    for track in (straight, standing):  # no fold fits better: the straight line, as before
        assert np.allclose(tracks.walk(track), Tracks.line(track))
    assert tracks.judged(standing) == 0.0
    later = straight + (1.0, 0.0, 0.0, 0.0)  # a step on, its straight line reaches 5.0 ...
    assert abs(tracks.walk(later)[0] - 4.5) < 1e-9  # ... but turns at the face (4.75): back 0.25
    tracks.bounce_gain = None  # off: every line straight, as before the fold
    assert tracks.walk(folded) == Tracks.line(folded) and tracks.walk(later) == Tracks.line(later)
    s, yy, w = -folded[:, 0], folded[:, 2], np.ones(4)
    assert reflected_line(s, yy, w, NO_WALLS, 0.25, 0.5, 4.0) is None
    assert reflected_line(s[:2], yy[:2], w[:2], (-5.0, 5.0), 0.25, 0.5, 4.0) is None  # two looks: no fold
