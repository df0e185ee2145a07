"""First sightings on the moving course (:mod:`husky_course.planners.arrivals`)."""

from __future__ import annotations

import numpy as np
import pytest

from husky_course.config import SimConfig, sim_for_world
from husky_course.planners.arrivals import Arrivals

MOVING = sim_for_world(SimConfig(), "moving")


def _half_occluded(config: SimConfig) -> np.ndarray:
    """A previous image: something 1 m ahead in the left half of the columns, nothing in the right."""
    size = config.camera.size
    return np.r_[np.full(size // 2, 1.0), np.full(size - size // 2, np.inf)]


def test_a_cylinder_where_free_space_was_seen_walked_in_from_the_hidden_side():
    arrivals = Arrivals(MOVING)
    arrivals.remember(_half_occluded(MOVING))
    (v,) = arrivals.speeds(np.array([[3.0, 0.0, 0.25]]))
    lo, hi = MOVING.world.speed_range
    # standing, and every walk from the right (the seen half), are ruled out: it came from the left,
    # so it walks towards -y, at the mean of the speeds left
    assert v == pytest.approx(-(lo + hi) / 2)


def test_dead_reckoning_carries_the_previous_image():
    arrivals = Arrivals(MOVING)
    arrivals.remember(_half_occluded(MOVING))
    arrivals.move(1.0, 0.0)  # the robot advanced 1 m: the same place is now 1 m nearer
    moved = arrivals.speeds(np.array([[2.0, 0.0, 0.25]]))
    fresh = Arrivals(MOVING)
    fresh.remember(_half_occluded(MOVING))
    assert moved == pytest.approx(fresh.speeds(np.array([[3.0, 0.0, 0.25]])))
    assert moved[0] != 0


def test_standing_stays_possible_behind_an_occluder_or_beyond_the_far_plane():
    arrivals = Arrivals(MOVING)
    arrivals.remember(np.full(MOVING.camera.size, 1.0))  # a wall 1 m ahead hid everything
    far = MOVING.camera.far + MOVING.camera.mount_forward + 1.0
    discs = np.array([[3.0, 0.0, 0.25], [3.0, 1.0, 0.25]])
    assert np.all(arrivals.speeds(discs) == 0)
    arrivals.remember(np.full(MOVING.camera.size, np.inf))  # nothing seen, and the cylinder beyond far
    assert arrivals.speeds(np.array([[far, 0.0, 0.25]]))[0] == 0


def test_seen_through_both_ways_or_no_previous_image_or_static_course_stands():
    arrivals = Arrivals(MOVING)
    disc = np.array([[3.0, 0.0, 0.25]])
    assert arrivals.speeds(disc)[0] == 0  # no previous image yet
    arrivals.remember(np.full(MOVING.camera.size, np.inf))  # free everywhere: every hypothesis out
    assert arrivals.speeds(disc)[0] == 0
    static = Arrivals(SimConfig())
    static.remember(_half_occluded(SimConfig()))
    assert static.speeds(disc)[0] == 0


# -- the evidence of the earlier images' columns (Arrivals.read / evidence) ---------------------------------


def _seen(arrivals: Arrivals, circles: list[tuple[float, float, float]], hidden: float = 0.0) -> np.ndarray:
    """A remembered image's per-column depth showing ``circles`` ``(x, y, r)`` (nearest first wins),
    free elsewhere; the columns with ``|u| < hidden`` see an occluder 1 m ahead."""
    depth = np.full(MOVING.camera.size, np.inf)
    for x, y, r in circles:
        depth = np.minimum(depth, arrivals.front(x, np.array([y]), r)[0])
    return np.where(np.abs(arrivals.u) < hidden, 1.0, depth)


def test_front_is_where_each_column_meets_the_circle():
    arrivals = Arrivals(MOVING)
    x, y, r = 3.0, -0.4, 0.25
    d = arrivals.front(x, np.array([y]), r)[0]
    hit = np.isfinite(d)
    assert 2 <= hit.sum() < MOVING.camera.size // 2
    cam = MOVING.camera.mount_forward
    gap = np.hypot(cam + d[hit] - x, d[hit] * arrivals.u[hit] - y)  # each hit lies on the circle
    assert gap == pytest.approx(np.full(hit.sum(), r))
    assert np.all(d[hit] >= x - cam - r - 1e-9)  # and no nearer than its front


def test_a_first_sight_hidden_last_time_at_its_place_is_read_off_the_columns_where_it_was():
    arrivals = Arrivals(MOVING, images=1)
    walk = 0.4  # it walks towards +y: one step ago it stood 0.4 m to the right, in view
    arrivals.remember(_seen(arrivals, [(3.0, -walk, 0.25)], hidden=0.06))
    disc = np.array([[3.0, 0.0, 0.25]])
    assert arrivals.speeds(disc)[0] == 0  # the centre column was hidden: standing stays possible
    assert arrivals.read(disc)[0] == pytest.approx(walk, abs=0.051)
    still = Arrivals(MOVING, images=1)  # where it stands now, seen the same one step ago: standing
    still.remember(_seen(still, [(3.0, 0.0, 0.25)]))
    assert still.evidence(disc)[0] == 0


def test_an_older_image_decides_when_the_last_one_saw_nothing_of_it_carried_by_dead_reckoning():
    disc, walk = np.array([[3.0, 0.0, 0.25]]), -0.3
    reads = {}
    for images in (1, 3):
        arrivals = Arrivals(MOVING, images=images)
        arrivals.remember(_seen(arrivals, [(5.0, -2 * walk, 0.25)]))  # two steps ago, 2 m further back
        arrivals.move(1.0, 0.0)
        arrivals.remember(np.full(MOVING.camera.size, 1.0))  # one step ago: a wall hid everything
        arrivals.move(1.0, 0.0)
        reads[images] = arrivals.read(disc)[0]
    assert reads[1] == 0
    assert reads[3] == pytest.approx(walk, abs=0.051)


def test_evidence_is_silent_without_a_match_without_images_and_on_the_static_course():
    disc = np.array([[3.0, 0.0, 0.25], [2.5, 1.0, 0.3]])
    arrivals = Arrivals(MOVING)
    assert np.isnan(arrivals.evidence(disc)).all()  # no image yet
    arrivals.remember(np.full(MOVING.camera.size, np.inf))  # free everywhere: every hypothesis out
    assert np.isnan(arrivals.evidence(disc)).all()
    assert np.array_equal(arrivals.read(disc), arrivals.speeds(disc))
    off = Arrivals(MOVING, images=0)
    off.remember(_seen(off, [(3.0, -0.4, 0.25)], hidden=0.06))
    assert np.isnan(off.evidence(disc)).all()
    assert np.array_equal(off.read(disc), off.speeds(disc))
    static = Arrivals(SimConfig())
    static.remember(_seen(static, [(3.0, -0.4, 0.25)], hidden=0.06))
    assert np.isnan(static.evidence(disc)).all()
    with pytest.raises(ValueError, match="images"):
        Arrivals(MOVING, images=-1)


def test_a_column_that_saw_through_rules_a_walk_out_however_many_columns_match_it():
    x = 1.6  # near: a circle spans about six columns
    disc = np.array([[x, 0.0, 0.25]])
    arrivals = Arrivals(MOVING, images=1)
    old = _seen(arrivals, [(x, -0.4, 0.25)])  # where it stood: only two columns of it in view
    shown = np.flatnonzero(np.isfinite(old))
    old[shown[2:]] = 0.5
    decoy = _seen(arrivals, [(x, 0.6, 0.25)])  # a walk of -0.6 matches five of this circle's columns...
    hit = np.flatnonzero(np.isfinite(decoy))
    decoy[hit[np.argmax(decoy[hit])]] = np.inf  # ...but one saw through where it would stand
    arrivals.remember(np.minimum(old, decoy))
    assert arrivals.read(disc)[0] == pytest.approx(0.4, abs=0.051)


def test_without_a_matching_column_the_evidence_is_silent():
    arrivals = Arrivals(MOVING, images=1)
    u = arrivals.u  # the centre and the right hidden, the left free: only walks from the right are left
    arrivals.remember(np.where(u > 0.06, np.inf, 1.0))
    disc = np.array([[3.0, 0.0, 0.25]])
    assert np.isnan(arrivals.evidence(disc)[0])
    assert arrivals.read(disc)[0] == 0  # the centre column was hidden: the rule leaves it standing


def test_the_planners_first_sights_take_the_evidence_as_configured():
    import torch

    from husky_course.config import ArrivalsConfig
    from husky_course.models.discs import DiscNet
    from husky_course.planners.moving_discs import DiscTrackingPlanner
    from husky_course.planners.tracking import TrackingPlanner

    torch.manual_seed(0)
    discs = DiscTrackingPlanner(DiscNet(MOVING.world.radius_range).eval(), MOVING).map
    tracker = TrackingPlanner(MOVING).map
    assert discs.arrivals.images == ArrivalsConfig.images > 0
    assert tracker.arrivals.images == ArrivalsConfig.tracker_images
    assert TrackingPlanner(MOVING, evidence_images=2).map.arrivals.images == 2
    discs.arrivals.remember(_seen(discs.arrivals, [(3.0, -0.4, 0.25)], hidden=0.06))
    first = np.array([[3.0, 0.0, 0.25], [2.0, 1.0, 0.3]])
    speed, fresh = discs.first_sights(first, np.array([True, True]), np.zeros(2), np.array([True, False]))
    assert speed[0] == pytest.approx(0.4, abs=0.051) and speed[1] == 0  # a tracked disc keeps its own
    assert fresh.tolist() == [True, False]


# -- first sights left undecided: the walks a planner with ``samples`` draws (Arrivals.weights) -----------


def test_weights_spread_the_motion_model_over_the_walks_no_column_saw_through():
    f = MOVING.world.moving_fraction
    arrivals = Arrivals(MOVING, images=1)
    h, disc = arrivals.hypotheses, np.array([[3.0, 0.0, 0.25]])
    prior = np.where(h == 0, 1 - f, f / (len(h) - 1))
    assert arrivals.weights(disc, f)[0] == pytest.approx(prior)  # no image yet: the motion model
    arrivals.remember(np.where(arrivals.u > 0.15, np.inf, 1.0))  # the left seen free, the rest hidden
    assert np.isnan(arrivals.evidence(disc)[0]) and arrivals.read(disc)[0] == 0  # undecided
    (w,) = arrivals.weights(disc, f)
    out = arrivals.columns(disc)[0][0] > 0  # the walks from the left: seen through
    assert out.any() and not out.all() and not out[h == 0].any()
    assert w.sum() == pytest.approx(1.0) and np.all(w[out] == 0)
    assert w[~out] == pytest.approx(prior[~out] / prior[~out].sum())
    decided = Arrivals(MOVING, images=1)  # read decides (a walk of 0.4): nothing left to draw
    decided.remember(_seen(decided, [(3.0, -0.4, 0.25)], hidden=0.06))
    assert decided.read(disc)[0] != 0 and not decided.weights(disc, f).any()
    assert not arrivals.weights(disc, 0.0).any()
    assert not Arrivals(SimConfig()).weights(disc, f).any()  # the static course: nothing walks


def test_a_sampling_planner_ranks_first_primitives_by_the_safe_steps_of_the_walks_it_draws(monkeypatch):
    """With ``samples``, each decision draws the undecided first sights' walks from their weights and
    ranks first primitives by the mean safe steps over the draws (ties: the plain ranking). Weights
    that put everything on one walk give exactly the ranking of that walk; the static course draws
    nothing and chooses as the plain tracker."""
    from husky_course.config import get_profile, with_world
    from husky_course.evaluation.episodes import eval_world_seeds, run_episode
    from husky_course.planners.mapping import MappingPlanner
    from husky_course.planners.tracking import TrackingPlanner, _ranked
    from husky_course.sim.fast import FastSimulator

    h = Arrivals(MOVING).hypotheses
    walk = float(h[np.argmin(np.abs(h - 0.4))])
    one_walk = (h == walk).astype(float)
    monkeypatch.setattr(Arrivals, "weights", lambda self, discs, fraction: np.tile(
        one_walk, (len(np.atleast_2d(discs)), 1)) * (fraction > 0))
    checked, differs = [], []

    class Checked(TrackingPlanner):
        def _decide(self, horizon: int) -> tuple[int, np.ndarray]:
            choice, ranked = super()._decide(horizon)
            group, weights = self.map.walk_doubt
            if len(weights):
                keys = MappingPlanner._decide(self, horizon)[1]
                speed = np.where(group >= 0, walk, 0.0)
                expect = _ranked(self._hypothesis(horizon, speed), keys)
                checked.append(choice == expect[0] and np.array_equal(ranked, expect[1]))
                differs.append(not np.array_equal(ranked, _ranked(self._hypothesis(horizon, 0.0), keys)[1]))
            return choice, ranked

    moving = with_world(get_profile("quick"), "moving").sim
    sim = FastSimulator(moving)
    for seed in eval_world_seeds(3, 1):
        run_episode(Checked(moving, samples=2), sim, int(seed))
    assert checked and all(checked) and any(differs)
    static = get_profile("quick").sim
    sim = FastSimulator(static)
    plain, sampled = ([run_episode(TrackingPlanner(static, samples=n), sim, int(s)).actions
                       for s in eval_world_seeds(3, 1)] for n in (0, 4))
    assert plain == sampled
    with pytest.raises(ValueError, match="samples"):
        TrackingPlanner(moving, samples=-1)


def test_the_disc_planner_draws_its_tracked_walkers_speeds_around_their_tracks():
    """With ``samples`` and ``speed_sigma``, every draw gives each walker the tracks follow its track's
    speed plus a normal error of spread ``speed_sigma`` and each undecided first sight a walk from its
    weights; nothing else (standing discs, walls) moves. The choice is the first primitive with the most
    mean safe steps over the draws, its ties broken by the draws' clearance (``ties="draws"``, the
    fewest bins over the draws, then their mean; ``ties="options"``, then the mean over the draws of
    their lattices' options) or by the map's own rank (``ties="map"``); the same seed draws the same walks,
    and ``speed_sigma`` 0 draws no error: the first sights' draws alone."""
    from husky_course.config import get_profile, with_world
    from husky_course.evaluation.episodes import eval_world_seeds, run_episode
    from husky_course.planners.mapping import MappingPlanner
    from husky_course.planners.registry import make_planner
    from husky_course.planners.tracking import _bins, _ranked, _steps, reachable_ends
    from husky_course.sim.fast import FastSimulator

    profile = with_world(get_profile("quick"), "moving")
    sim, samples, seeds = FastSimulator(profile.sim), 6, [int(s) for s in eval_world_seeds(6, 1)]
    errors: list[float] = []
    decisions: list[bool] = []
    alone: list[bool] = []  # a decision that draws though no first sight is in doubt
    broken: list[bool] = []  # a decision whose choice the draws' clearance changed

    def checked(sigma: float, ties: str = "draws"):
        planner = make_planner("discs", config=profile.sim, profile=profile, samples=samples,
                               speed_sigma=sigma, ties=ties)
        decide, keys_if, draws = planner._decide, planner._keys_if, []

        def record(horizon: int, speeds: np.ndarray) -> np.ndarray:
            keys = keys_if(horizon, speeds)
            draws.append((speeds.copy(), keys, reachable_ends(planner._drawn)))
            return keys

        def check(horizon: int) -> tuple[int, np.ndarray]:
            draws.clear()
            choice, ranked = decide(horizon)
            if draws:
                group, _ = planner.map.walk_doubt
                base, tracked = planner.velocity, planner.tracked
                ghosts = len(planner.map.dropped.items)  # each draw's last speeds: the ghosts' slots
                assert all(len(s) == len(base) + ghosts for s, _, _ in draws)
                speeds = np.array([s[: len(base)] for s, _, _ in draws])
                still = ~(tracked | ((group >= 0) & planner.doubtful))
                assert len(draws) == samples and (speeds[:, still] == base[still]).all()
                errors.extend((speeds[:, tracked] - base[tracked]).ravel())
                keys = MappingPlanner._decide(planner, horizon)[1]
                mean = np.mean([_steps(k) for _, k, _ in draws], axis=0)
                bins = np.array([_bins(k) for _, k, _ in draws])
                ends = np.mean([e for _, _, e in draws], axis=0)
                plain = _ranked(mean, keys)
                expect = {"map": plain, "draws": _ranked(mean, keys, (bins.min(0), bins.mean(0))),
                          "options": _ranked(mean, keys, (bins.min(0), bins.mean(0)), ends)}[ties]
                decisions.append(choice == expect[0] and np.array_equal(ranked, expect[1]))
                alone.append(not planner.doubtful.any())
                broken.append(expect[0] != plain[0])
            return choice, ranked

        planner._keys_if, planner._decide = record, check
        return planner

    actions = [run_episode(checked(0.05), sim, s).actions for s in seeds]
    assert decisions and all(decisions) and any(alone) and any(broken)
    decisions.clear()
    for ties in ("map", "options"):
        for s in seeds:
            run_episode(checked(0.05, ties), sim, s)
        assert decisions and all(decisions)
        decisions.clear()
    assert len(errors) > 100 and np.std(errors) == pytest.approx(0.05, rel=0.25)
    assert abs(np.mean(errors)) < 0.02
    again = [run_episode(make_planner("discs", config=profile.sim, profile=profile, samples=samples,
                                      speed_sigma=0.05, ties="draws"), sim, s).actions for s in seeds]
    assert again == actions  # the same draws
    errors.clear()
    for s in seeds:
        run_episode(checked(0.0), sim, s)
    assert not np.any(errors)  # no error drawn: the first sights' draws alone
    with pytest.raises(ValueError, match="speed_sigma"):
        make_planner("discs", config=profile.sim, profile=profile, speed_sigma=-0.1)
    with pytest.raises(ValueError, match="ties"):
        make_planner("discs", config=profile.sim, profile=profile, ties="clearance")


def test_the_draws_of_a_decision_share_the_standing_clearances_and_change_no_bit():
    """Within one decision the draws read the standing points' clearances each state's row computed
    once (``TrackingPlanner._start_check``). Every draw's keys equal, bit for bit, those of the same
    draw with nothing shared, and rows are shared (the cache is used)."""
    from husky_course.config import get_profile, with_world
    from husky_course.evaluation.episodes import eval_world_seeds, run_episode
    from husky_course.planners.registry import make_planner
    from husky_course.sim.fast import FastSimulator

    profile = with_world(get_profile("quick"), "moving")
    sim = FastSimulator(profile.sim)
    planner = make_planner("discs", config=profile.sim, profile=profile, samples=6)
    keys_if, same, shared = planner._keys_if, [], []

    def compared(horizon: int, speeds: np.ndarray) -> np.ndarray:
        keys = keys_if(horizon, speeds)
        rows, planner._standing_rows = planner._standing_rows, None
        try:
            same.append(np.array_equal(keys, keys_if(horizon, speeds)))
        finally:
            planner._standing_rows = rows
        shared.append(sum(len(ys) for by_x in rows.values() for ys, _ in by_x.values()))
        return keys

    planner._keys_if = compared
    for seed in eval_world_seeds(4, 1):
        run_episode(planner, sim, int(seed))
    assert len(same) > 20 and all(same)
    assert max(shared) > 0 and planner._standing_rows is None  # used within a decision, dropped after


def test_ties_of_the_draws_mean_go_to_the_most_clearance_in_the_worst_draw_then_on_average():
    """``_ranked``: the most mean safe steps first, whatever the clearance; among equals, the most
    clearance bins in the worst draw, then the most on average, then the map's own rank, then the
    lowest index; a primitive that touches at once is never chosen over one that does not."""
    from husky_course.planners.tracking import _ranked

    keys = np.array([5_010_000.0, 5_015_000.0, 5_012_000.0, 5_012_000.0, -1e9])
    mean = np.array([4.5, 4.5, 4.5, 4.5, 5.0])
    least, average = np.array([3.0, 2.0, 3.0, 3.0, 9.0]), np.array([6.0, 9.0, 7.0, 7.0, 9.0])
    assert _ranked(mean, keys)[0] == 1  # the map's own rank
    choice, ranked = _ranked(mean, keys, (least, average))
    assert choice == 2 and ranked[4] == keys[4]  # 2 and 3 tie in everything: the lowest index
    assert np.argsort(-ranked[:4], kind="stable").tolist() == [2, 3, 0, 1]
    mean[1] = 4.53125  # one draw of 32 more safe steps outranks any clearance
    assert _ranked(mean, keys, (least, average))[0] == 1


def test_options_count_the_horizon_end_states_each_first_primitive_still_reaches():
    """``reachable_ends``: per first primitive, the states at the lattice's last step that its safe edges
    lead to (0 where it touches at once, or where every way from it is cut); ``_ranked`` with options
    breaks ties of the mean and of the clearance bins by the most options, before the map's own rank."""
    from husky_course.planners.tracking import _ranked, reachable_ends
    from husky_course.sim.lattice import Lattice

    t, f = True, False
    one = Lattice(np.zeros(3), [np.array([0]), np.arange(3)], [np.array([[t, f, t]])],
                  [np.zeros((1, 3))], [np.array([[0, 1, 2]])])
    assert reachable_ends(one).tolist() == [1.0, 0.0, 1.0]
    two = Lattice(np.zeros(3), [np.array([0]), np.arange(3), np.arange(4)],
                  [np.array([[t, t, f]]), np.array([[t, f, t], [f, f, f], [t, t, t]])],
                  [np.zeros((1, 3)), np.zeros((3, 3))],
                  [np.array([[0, 1, 2]]), np.array([[0, 1, 2], [0, 0, 0], [1, 2, 3]])])
    assert reachable_ends(two).tolist() == [2.0, 0.0, 0.0]  # 1 leads to a dead end, 2 touches at once
    cut = Lattice(two.pose, [*two.states[:2], np.zeros(0, int)], [two.feasible[0], np.zeros((3, 3), bool)],
                  two.clear, two.nxt)
    assert reachable_ends(cut).tolist() == [0.0, 0.0, 0.0]  # nothing lasts to the last step
    rng = np.random.default_rng(0)  # random lattices: the same counts as an OR over the primitives
    for _ in range(50):
        sizes = [1, *rng.integers(1, 12, int(rng.integers(1, 6)))]
        feasible = [rng.random((a, 5)) < 0.4 for a in sizes[:-1]]
        nxt = [rng.integers(0, b + 2, (a, 5)) for a, b in zip(sizes[:-1], sizes[1:], strict=True)]
        states = [np.arange(n) for n in sizes]
        lattice = Lattice(np.zeros(3), states, feasible, [0 * f for f in feasible], nxt)
        reach = np.eye(sizes[-1], dtype=bool)
        for k in range(len(feasible) - 1, 0, -1):
            step = np.zeros((sizes[k], sizes[-1]), bool)
            for m in range(5):
                step |= feasible[k][:, m, None] & reach[np.minimum(nxt[k][:, m], len(reach) - 1)]
            reach = step
        loop = np.where(feasible[0][0], reach[np.minimum(nxt[0][0], len(reach) - 1)].sum(1), 0)
        assert reachable_ends(lattice).tolist() == loop.astype(float).tolist()
    keys = np.array([5_010_000.0, 5_015_000.0, 5_012_000.0, 5_012_000.0])
    mean, least, average = np.full(4, 4.5), np.array([3.0, 3.0, 3.0, 2.0]), np.full(4, 7.0)
    assert _ranked(mean, keys, (least, average))[0] == 1  # the map's rank
    assert _ranked(mean, keys, (least, average), np.array([4.0, 2.0, 5.0, 9.0]))[0] == 2  # most options
