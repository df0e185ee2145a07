"""The mapping planner on the moving course: its map's points walk, and it plans in space-time.

No learning and no privileged input: the classical counterpart of the moving-trained memory
student (chapter 10), reading the same two things the student's memory gives it.

* **Motion from successive images.** Each scan's pieces of surface are located (a fitted circle)
  and followed from image to image (:class:`~husky_course.planners.motion.Tracks`): every point of
  the current scan gets the lateral displacement per step of its piece's track, the weighted line
  through its last looks (0 for a piece seen for the first time: assumed standing until the next
  image says otherwise), unless it stands where the previous image saw free space: then it walked
  in (:mod:`~husky_course.planners.arrivals`; 0.723 without, 0.740 with, on 300 moving tuning
  worlds, full profile).
* **A map that walks** (:class:`~husky_course.planners.motion.WalkingMap`). The points of
  :class:`~husky_course.planners.mapping.MappingPlanner`'s map each carry that velocity; after
  every step a remembered point moves by it (dead reckoning of the robot *and* of the obstacle),
  and a point seen again is replaced by the new scan's. A walking point bounces off the side walls'
  faces, read off its wall points as the disc planner reads them (:mod:`~husky_course.planners.walls`).
* **Space-time search.** The oracle's lattice search over the map: a standing point is judged on
  the mapping planner's path tables, a walking point exactly, where it is at each of 21 samples'
  times (level ``k`` of the lattice is the step from ``k`` to ``k + 1`` steps after now).

On the static course every velocity is 0 and it is the mapping planner. Its ``horizon`` is the
mapping planner's, 5, which keeps that equivalence; on evaluation set 1, the tuning set, it is
within one world in fifty of the best: success on 200 moving worlds 0.665 / 0.700 / 0.680 / 0.680 /
0.680 for horizons 3 / 4 / 5 / 6 / 8, full profile, with the tracks of
:class:`~husky_course.planners.motion.Tracks` (``benchmarks/exp_moving_tracker.py``; with the
course's earlier two-image estimate it was 0.625 / 0.655 / 0.675 / 0.670 / 0.670).

Against the privileged "seen, with motion" planner (every cylinder the camera has shown, its
true position and velocity) it measures what estimating motion from depth images costs; against
the mapping planner, what estimating it is worth.
"""

from __future__ import annotations

import numpy as np

from ..config import ArrivalsConfig, MappingConfig, SimConfig, WallsConfig
from ..sim.lattice import Lattice, StartCheck
from ..sim.world import sample_times
from .mapping import MappingPlanner
from .motion import WalkingMap
from .walls import NO_WALLS, bounced


class TrackingPlanner(MappingPlanner):
    """:class:`MappingPlanner` whose map points carry estimated lateral velocities (module docstring)."""

    name = "tracking"  #: the mapping planner, with motion

    def __init__(self, config: SimConfig | None = None, horizon: int = MappingConfig.horizon,
                 arrivals: bool = True, doubt_steps: float = ArrivalsConfig.doubt_steps,
                 doubt_hard: bool = ArrivalsConfig.doubt_hard, hedge: bool = ArrivalsConfig.hedge,
                 first_samples: int = ArrivalsConfig.first_samples,
                 evidence_images: int = ArrivalsConfig.tracker_images, bounce: bool = WallsConfig.tracker,
                 samples: int = ArrivalsConfig.tracker_samples,
                 speed_sigma: float = ArrivalsConfig.tracker_speed_sigma, **kwargs: float) -> None:
        super().__init__(config, horizon, **kwargs)
        self.map = WalkingMap(  # type: ignore[assignment]
            self.config, self.map.forget_behind, arrivals, evidence_images, bounce)
        _set_doubt(self, doubt_steps, doubt_hard, hedge, first_samples, samples, speed_sigma)

    @property
    def velocity(self) -> np.ndarray:
        """Each map point's estimated lateral velocity (m per step)."""
        return self.map.velocity

    @property
    def doubtful(self) -> np.ndarray:
        """Per map point: a first sight the arrivals rule left standing (it may yet walk either way)."""
        return self.map.fresh & (self.map.velocity == 0)

    @property
    def tracked(self) -> np.ndarray:
        """Per map point: walking, at the speed its track reads (seen before, not a first sight)."""
        return ~self.map.fresh & (self.map.velocity != 0)

    def _start_check(self) -> StartCheck:
        """Standing points read off the path tables as the mapping planner reads them; each walking
        point exactly, where it is at the time of each of every ``path_samples``-th sample of an
        edge. With ``doubt_steps``, each doubtful point (:attr:`doubtful`) also stands for the band
        it could have walked to by a sample's time (up to ``doubt_steps`` steps, at the course's
        fastest walk): the band counts in the clearance a plan is ranked by, and with
        ``doubt_hard`` an edge that enters it is infeasible. With nothing walking or doubtful this
        is the mapping planner's check, number for number."""
        speeds = self.velocity if self._speeds is None else self._speeds  # or a hypothesis of :meth:`_decide`
        walking = speeds != 0
        points, reach = self.points, self._reach
        standing = points[~walking]
        table = self._table_for(standing)
        rows = getattr(self, "_standing_rows", None)  # within one decision: its draws share these
        cached = None if rows is None else rows.setdefault(walking.tobytes(), {})
        movers = np.column_stack([points[walking], speeds[walking]])  # rows (x, y, r, v)
        doubt = points[self.doubtful] if self.doubt_steps > 0 and self.max_walk > 0 else np.empty((0, 3))
        local = self._library.local_paths  # type: ignore[union-attr]
        every = max(1, (local.shape[1] - 1) // (self.path_samples - 1))
        x, t = local[:, ::every, 0], sample_times(0.0, local.shape[1])[::every]  # relative to an edge's start
        ahead = (x.min() - reach, x.max() + reach)
        side = (local[:, ::every, 1].min(), local[:, ::every, 1].max())  # the samples' lateral extent
        faces = getattr(self.map, "faces", NO_WALLS)  # the walls' faces as its map reads them

        def near(p: np.ndarray, x0: float) -> np.ndarray:
            return p[(p[:, 0] > x0 + ahead[0]) & (p[:, 0] < x0 + ahead[1])]

        def standing_gap(x0: float, y0: np.ndarray) -> np.ndarray:
            """``table.clearance`` of the standing points, each state's row computed once per decision
            (a row depends on its own start alone: the same numbers as computing them all)."""
            if cached is None or not len(y0):
                return table.clearance(standing, x0, y0, reach)
            known = cached.get(x0)
            if known is None or not len(known[0]):
                gap = table.clearance(standing, x0, y0, reach)
                order = np.argsort(y0)
                cached[x0] = (y0[order], gap[order])
                return gap
            ys, gaps = known
            at = np.minimum(np.searchsorted(ys, y0), len(ys) - 1)
            found = ys[at] == y0
            if found.all():
                return gaps[at]
            gap = np.empty((len(y0), gaps.shape[1]))
            gap[found] = gaps[at[found]]
            gap[~found] = table.clearance(standing, x0, y0[~found], reach)
            ys, gaps = np.r_[ys, y0[~found]], np.r_[gaps, gap[~found]]
            order = np.argsort(ys)
            cached[x0] = (ys[order], gaps[order])
            return gap

        def check(x0: float, y0: np.ndarray, t0: float) -> tuple[np.ndarray, np.ndarray]:
            gap = standing_gap(x0, y0)  # (states, n), capped at reach
            moving, doubted = near(movers, x0), near(doubt, x0)
            if len(moving) or len(doubted):
                X, Y, T = x0 + x, y0[:, None, None] + local[None, :, ::every, 1], t0 + t
            if len(moving):  # the lateral band each state's samples sweep: a walker that stays more
                # than a reach and its radius beside it lowers no gap (capped at reach), so that state
                # skips it (the same numbers, bit for bit); y0 + the paths' least (greatest) lateral
                # offset is the least (greatest) of y0 + each (a sum is monotone)
                walked = bounced(moving[:, 1:2], moving[:, 3:4], T[None], moving[:, 2:3], faces)  # (movers,
                spare = moving[:, 2:3] + reach + 1e-6  # samples): where each is at each sample's time
                near_rows = ((walked.min(1)[:, None] - (y0 + side[1])[None] <= spare)
                             & ((y0 + side[0])[None] - walked.max(1)[:, None] <= spare))  # (movers, states)
                for (px, _, r, _), wy, rows in zip(moving, walked, near_rows, strict=True):
                    if not rows.any():
                        continue
                    # the root of the least squared distance over the samples (a root is monotone), as
                    # the oracle's check computes it: np.hypot at every sample took four times as long
                    every_row = bool(rows.all())
                    dy = Y - wy if every_row else Y[rows] - wy
                    d2 = np.multiply(dy, dy, out=dy)
                    d2 += np.square(X - px)
                    nearest = np.sqrt(d2.min(-1)) - r
                    if every_row:
                        np.minimum(gap, nearest, out=gap)
                    else:
                        gap[rows] = np.minimum(gap[rows], nearest)
            clear = gap - self.radius
            if not len(doubted):
                return clear < self.margin, clear - self.margin
            band = self.max_walk * np.minimum(T, self.doubt_steps)
            for px, py, r in doubted:  # the nearest place it could be, standing or walking
                off = np.maximum(0.0, np.abs(Y - py) - band)
                np.minimum(gap, (np.hypot(X - px, off) - r).min(-1), out=gap)
            wide = gap - self.radius
            return (wide if self.doubt_hard else clear) < self.margin, wide - self.margin

        return check

    def _decide(self, horizon: int) -> tuple[int, np.ndarray]:
        """The mapping planner's choice, but where first sights are in doubt (with ``samples``, or
        ``first_samples`` at the episode's first decision, or ``hedge``) the first primitive is chosen
        over hypotheses for them.

        * ``samples`` (every decision): the map's :attr:`~.moving_discs.WalkingDiscMap.walk_doubt` gives
          the last image's first sights that the earlier images leave undecided, each with weights over
          the hypotheses of :class:`~husky_course.planners.arrivals.Arrivals` (the course's motion
          model over the walks no earlier column saw through). Each of ``samples`` draws gives every
          one of them a walk, and every walker its track follows (:attr:`tracked`) its track's speed
          plus a normal error of spread ``speed_sigma``; the first primitive whose plans survive the
          most steps on average over the draws wins, ties broken as ``ties`` says (:class:`Tally`: by
          the rank of the map's own velocities; or by the draws' clearance first; or by that and then
          the draws' options, :func:`reachable_ends`). Drawn from the episode's number and the
          decision's; with neither kind of doubt present, the map's own choice (with ``ties``
          "options", ties of its safe steps and clearance go to its options). The disc map's ghosts
          (:mod:`~husky_course.planners.ghosts`; its ``dropped``) are drawn too: in each draw every ghost
          stands at one of its open walks, drawn from the course's motion model (from a generator of its
          own, so that the other draws stay as they were), and walks at it.
        * ``first_samples``: the first decision has one image, so every cylinder in view is a first
          sight the arrivals rule cannot judge. Each of ``first_samples`` samples draws, for every
          doubtful piece on its own (points closer than 0.3 m to one another: one disc, or one
          cylinder's scan points), the course's motion model (it walks with the course's share of
          walking cylinders, either way, at a speed uniform in ``speed_range``); ranked as above.
        * ``hedge`` (every decision): the expectation over three hypotheses for all doubtful points
          at once (all standing, all walking left, all walking right at the course's mean speed),
          weighted by the course's share of walking cylinders.
        """
        self._standing_rows: dict | None = {}  # the standing points' clearances, shared by its draws
        try:
            return self._decide_over_draws(horizon)
        finally:
            self._standing_rows = None

    def _decide_over_draws(self, horizon: int) -> tuple[int, np.ndarray]:
        """:meth:`_decide`'s work."""
        lattice, ranking = self._ranking(horizon)
        choice, keys = int(ranking.choice[0][0]), ranking.keys[0][0]
        walks = float(getattr(self.config.world, "moving_fraction", 0.0))
        if not walks:
            return choice, keys
        group, weights = self.map.walk_doubt if self.samples else (None, ())
        tracked = self.tracked if self.samples and self.speed_sigma > 0 else np.zeros(0, bool)
        ghosts = getattr(self.map, "dropped", None) if self.samples else None  # the disc map's (.ghosts)
        ghost_weights = ghosts.weights() if ghosts is not None else []
        if len(weights) or tracked.any() or ghost_weights:
            rng, h = np.random.default_rng((self._key, self._remaining)), self.map.arrivals.hypotheses
            later = np.random.default_rng((self._key, self._remaining, 7))  # the ghosts' draws
            tally, base, k = Tally(self.ties, keys), self.velocity, int(tracked.sum())
            drawn_ones = (group >= 0) & self.doubtful if len(weights) else None
            for _ in range(self.samples):
                speeds = base.copy()
                if drawn_ones is not None:  # the undecided first sights
                    drawn = h[[rng.choice(len(h), p=w) for w in weights]]
                    speeds = np.where(drawn_ones, drawn[np.maximum(group, 0)], speeds)
                if k:
                    speeds[tracked] += rng.normal(0.0, self.speed_sigma, k)
                if ghost_weights:  # each ghost at an open walk, its slot joining the points for this draw
                    ghosts.draw = [int(later.choice(len(h), p=w)) for w in ghost_weights]
                    speeds = np.r_[speeds, ghosts.slots()[1]]
                try:
                    tally.add(self._keys_if(horizon, speeds), self._drawn)
                finally:
                    if ghosts is not None:
                        ghosts.draw = None
            return tally.ranked()
        doubtful = self.doubtful
        if not doubtful.any():
            return Tally.undrawn(self.ties, choice, keys, lattice)
        lo, hi = self.config.world.speed_range  # type: ignore[attr-defined]
        if self.first_samples and self._remaining == self._length:
            rng, piece = np.random.default_rng(self._key), _pieces(self.points[doubtful])
            total, n = np.zeros(len(keys)), int(piece.max()) + 1
            for _ in range(self.first_samples):
                speed = np.zeros(len(doubtful))
                walking = rng.random(n) < walks
                speed[doubtful] = (walking * rng.choice((-1.0, 1.0), n) * rng.uniform(lo, hi, n))[piece]
                total += self._hypothesis(horizon, speed)
            return _ranked(total / self.first_samples, keys)
        if not self.hedge:
            return Tally.undrawn(self.ties, choice, keys, lattice)
        expected = (1 - walks) * _steps(keys)
        for speed in (-(lo + hi) / 2, (lo + hi) / 2):
            expected = expected + walks / 2 * self._hypothesis(horizon, speed)
        hedged = np.where(keys > -1e8, expected * 1e6 + (keys - _steps(keys) * 1e6), keys)
        return int(np.argmax(hedged)), hedged

    def _hypothesis(self, horizon: int, speed: float | np.ndarray) -> np.ndarray:
        """Safe steps of each first primitive's best plan if the doubtful points walk at ``speed``
        (one number, or one per map point)."""
        return self._steps_if(horizon, np.where(self.doubtful, speed, self.velocity))

    def _steps_if(self, horizon: int, speeds: np.ndarray) -> np.ndarray:
        """Safe steps of each first primitive's best plan if the map's points walk at ``speeds``
        (one per point of :attr:`points`)."""
        return _steps(self._keys_if(horizon, speeds))

    def _keys_if(self, horizon: int, speeds: np.ndarray) -> np.ndarray:
        """Each first primitive's rank (:func:`~husky_course.sim.lattice.rank_plans`' keys) if the
        map's points walk at ``speeds`` (one per point of :attr:`points`); the lattice they rank is
        kept in ``_drawn`` (for the draws' options, :class:`Tally`)."""
        self._speeds = speeds
        try:
            self._drawn, ranking = self._ranking(horizon)
            return ranking.keys[0][0]
        finally:
            self._speeds = None


class Tally:
    """What :meth:`TrackingPlanner._decide`'s draws add up, per first primitive: the safe steps of its best
    plan, its clearance bins (the fewest over the draws and their sum) and, with ``ties`` "options", its
    options (:func:`reachable_ends`); :meth:`ranked` ranks by them as ``ties`` says (:func:`_ranked`)."""

    def __init__(self, ties: str, keys: np.ndarray) -> None:
        self.ties, self.keys, self.n = ties, keys, 0
        self.steps, self.clear, self.ends = np.zeros(len(keys)), np.zeros(len(keys)), np.zeros(len(keys))
        self.least = np.full(len(keys), np.inf)

    def add(self, keys: np.ndarray, lattice: Lattice) -> None:
        """One draw's keys (:meth:`TrackingPlanner._keys_if`) and the lattice they rank (its ``_drawn``)."""
        bins = _bins(keys)
        self.n, self.steps, self.clear = self.n + 1, self.steps + _steps(keys), self.clear + bins
        self.least = np.minimum(self.least, bins)
        if self.ties == "options":
            self.ends += reachable_ends(lattice)

    def ranked(self) -> tuple[int, np.ndarray]:
        """The choice and every first primitive's rank over the draws added."""
        if self.ties == "map":
            return _ranked(self.steps / self.n, self.keys)
        return _ranked(self.steps / self.n, self.keys, (self.least, self.clear / self.n),
                       self.ends / self.n if self.ties == "options" else None)

    @staticmethod
    def undrawn(ties: str, choice: int, keys: np.ndarray, lattice: Lattice) -> tuple[int, np.ndarray]:
        """Nothing drawn: the map's own ``choice`` and ``keys``; with ``ties`` "options", its plans' safe
        steps and bins, then the lattice's options, then the keys."""
        if ties != "options":
            return choice, keys
        bins = _bins(keys)
        return _ranked(_steps(keys), keys, (bins, bins), reachable_ends(lattice))


def reachable_ends(lattice: Lattice) -> np.ndarray:
    """Per first primitive from the lattice's start: how many of its states at the last step the safe
    edges still lead to after it (its *options*; 0 where it touches at once, or nothing lasts).

    Backwards, step by step: a state reaches the last step's states that a safe edge from it leads to
    a state reaching; one product of the step's edges (0 / 1) with the next step's reach (0 / 1), its
    sums capped at 1 (integers, so exact), in place of an OR over the 25 primitives (three times as
    fast, the same counts: tests/test_arrivals.py checks it against that loop)."""
    last = len(lattice.feasible)
    first, after = lattice.feasible[0][0], lattice.nxt[0][0]
    if last == 0 or not len(lattice.states[last]):
        return np.zeros(len(first))
    reach = np.eye(len(lattice.states[last]))  # (states at step k, states at the last): 1 where reached
    for k in range(last - 1, 0, -1):  # back to the states after the first primitive
        feasible, nxt = lattice.feasible[k], np.minimum(lattice.nxt[k], len(reach) - 1)
        edges = np.zeros((len(feasible), len(reach)))
        edges[np.nonzero(feasible)[0], nxt[feasible]] = 1.0
        reach = np.minimum(edges @ reach, 1.0)
    if not len(reach):
        return np.zeros(len(first))
    return np.where(first, (reach[np.minimum(after, len(reach) - 1)] > 0).sum(1), 0).astype(float)


def _steps(keys: np.ndarray) -> np.ndarray:
    """Safe steps of each first primitive's best plan, read off :func:`~husky_course.sim.lattice.rank_plans`'s
    keys (``steps * 1e6 + clearance bins * 1e3 - lateral cost``; below ``-1e8``: it touches at once)."""
    return np.where(keys > -1e8, np.floor((keys + 5e5) / 1e6), 0.0)


def _bins(keys: np.ndarray) -> np.ndarray:
    """The clearance bins of each first primitive's best plan, read off ``keys`` as :func:`_steps` reads
    its safe steps (the lateral cost is below 1e3 / 2); -1 where it touches at once."""
    return np.where(keys > -1e8, np.round((keys - _steps(keys) * 1e6) / 1e3), -1.0)


def _ranked(mean: np.ndarray, keys: np.ndarray, clearance: tuple[np.ndarray, np.ndarray] | None = None,
            options: np.ndarray | None = None) -> tuple[int, np.ndarray]:
    """The first primitive with the most mean safe steps ``mean`` over draws, ties to ``keys``' rank;
    with ``clearance`` ``(least, mean)`` (the draws' clearance bins: the fewest and the mean over the
    draws), ties to the most of the fewest, then of the mean, then (with ``options``, the mean over the
    draws of :func:`reachable_ends`) to the most options, then to ``keys``' rank."""
    mean, within = np.round(mean, 6), keys
    if clearance is not None:  # each primitive's place in that order, below 100 (1e-6 of a mean step)
        last = -np.arange(len(keys))  # full ties to the lowest index, as argmax breaks them
        more = np.round(options, 6) if options is not None else np.zeros(len(keys))
        order = np.lexsort((last, keys, more, np.round(clearance[1], 6), clearance[0], mean))  # last first
        within = np.empty(len(keys))
        within[order] = np.arange(len(keys)) * (100.0 / len(keys))
    ranked = np.where(keys > -1e8, mean * 1e8 + within, keys)
    return int(np.argmax(ranked)), ranked


def _pieces(points: np.ndarray, gap: float = 0.3) -> np.ndarray:
    """Which piece ``(m,)`` (numbered from 0) each of ``points (m, 2+)`` belongs to: chains of points
    closer than ``gap`` to one another."""
    p = np.asarray(points, float)[:, :2]
    close = np.hypot(p[:, None, 0] - p[None, :, 0], p[:, None, 1] - p[None, :, 1]) < gap
    label = np.arange(len(p))
    while True:  # each point takes the smallest label among its neighbours until none changes
        new = np.where(close, label[None, :], len(p)).min(1)
        if (new == label).all():
            return np.unique(label, return_inverse=True)[1]
        label = new


def _set_doubt(planner: TrackingPlanner, doubt_steps: float, doubt_hard: bool, hedge: bool,
               first_samples: int, samples: int, speed_sigma: float, ties: str = "map") -> None:
    """The settings for what a planner doubts of its map's motion (:class:`ArrivalsConfig`)."""
    if ties not in ("map", "draws", "options"):
        raise ValueError(f"ties must be 'map', 'draws' or 'options', got {ties!r}")
    planner.ties = ties
    planner.doubt_steps, planner.doubt_hard, planner.hedge = float(doubt_steps), bool(doubt_hard), bool(hedge)
    for name, value in (("first_samples", first_samples), ("samples", samples)):
        if int(value) != value or value < 0:
            raise ValueError(f"{name} must be a whole number >= 0, got {value!r}")
    if not np.isfinite(speed_sigma) or speed_sigma < 0:
        raise ValueError(f"speed_sigma must be a finite number >= 0, got {speed_sigma!r}")
    planner.first_samples, planner.samples = int(first_samples), int(samples)
    planner.speed_sigma = float(speed_sigma)
    planner.max_walk = float(getattr(planner.config.world, "speed_range", (0.0, 0.0))[1])
    planner._speeds: np.ndarray | None = None
    planner._drawn: Lattice | None = None  #: the lattice of the last draw (:meth:`TrackingPlanner._keys_if`)
