"""Experiment: what the moving disc planner takes as certain that it could doubt instead.

Run: ``python benchmarks/exp_moving_doubt_memory.py [--profile full] [--worlds 2000] [--start 1000]
[--variants remembered evidence posterior promote aged in-view ghosts told] [--workers 2] [--check]
[--base B.npz]``
(the disc planner needs its network: ``python -m husky_course train discs``; ``--base``: the planner's own
episodes kept for the next run, as ``exp_moving_variants.py`` keeps them).

The disc planner draws, at every decision, walks for the last image's undecided first sights and speeds
for its tracked walkers (``ArrivalsConfig.samples``); everything else in its map it takes as it reads it.
Following the cylinders that hit the robot after its fatal choices (a throwaway run from
``exp_moving_ties.py``'s states with ties ``"draws"`` driving, full profile, tuning worlds 0-1,999: 275
fatal choices in 17,889 winnable decisions; in 60 of them the chosen primitive itself hits a cylinder)
showed three beliefs held as certain that were wrong:

* a first sight that walked out of view before a second image saw it stays where it was seen, standing:
  its doubt was for one decision only;
* a track read as standing (:meth:`~husky_course.planners.motion.Tracks.judged`) is certain, though its
  line's slope may be within its error of a walk (two looks of a far cylinder, a walker that bounced off a
  wall between looks, a piece cut by the edge of the view);
* a small piece the network reads as no cylinder stays standing scan points, though its track reads a
  walk (walls do not walk).

Each variant here doubts one of them. ``remembered``: every remembered first sight still standing
undecided is drawn as well, from the weights it was born with (:meth:`~husky_course.planners.arrivals.
Arrivals.weights`), put where that walk has taken it since (bouncing off the faces read); ``evidence``:
the same, its walks that an image taken since would have seen through ruled out; ``posterior``: a disc
whose track reads standing is drawn from the track's posterior over the same hypotheses (the course's
prior, the slope's normal error of :meth:`~husky_course.planners.motion.Tracks.judged`) where that gives a
walk more than 1%; ``promote``: a piece of at most 1 m that the network reads as no cylinder but whose
track (two looks or more) reads a walk becomes the network's disc for it, walking. Two more variants ask
whether the tracked walkers' drawn speeds (``ArrivalsConfig.speed_sigma``) should spread a remembered
walker more, or less: ``aged``: in each draw a tracked walker's speed error has moved it since the image
that made its disc (its disc shifted by the error times the steps since), not only from now; ``in-view``:
only the walkers this image made a disc for are drawn, the remembered ones walk at their track's speed in
every draw. One more doubts what the map forgets: ``ghosts``: a disc that the map drops because an image sees
through its place (:meth:`~husky_course.planners.discs.DiscMap.forgotten`, no new disc landing on it) is kept
as a *ghost*, one hypothesis per walk of the course's motion model (:class:`~husky_course.planners.arrivals.
Arrivals`' hypotheses) from where its disc was last made; every later image rules out the hypotheses whose
circle one of its columns sees through; the ghost ends when a new disc overlaps a hypothesis still open, when
none is left open, when it falls behind, or :data:`GHOST_AGE` steps after its disc was made. In each draw
every ghost stands at one open hypothesis drawn from the course's prior, walking at it (the map's own
ranking leaves it out). ``told`` (privileged: :class:`ToldPlanner` has eyes of its own on the world) is
``ghosts`` with each ghost whose disc belonged to a cylinder put, in every draw, at its open hypothesis
nearest where that cylinder is now: what a sharp belief over the ghosts' hypotheses could give at most.
Variants join with ``+``. Each runs as a planner on the same worlds as the planner as it is; printed:
success with its exact interval, and the worlds won only with / only without it, with an exact sign test.
``--check`` adds the variant with nothing doubted, which must win exactly the planner's worlds.

Measured (full profile, tuning worlds 1,000-2,999, where the planner as it is crossed 0.858; about 9
minutes per variant on 2 cores), success and the worlds won only with / only without the variant:

=============================  =======  ===================
variant                        success  only with / without
=============================  =======  ===================
the planner as it is           0.858
``remembered``                 0.853    47 / 56, p = 0.43
``evidence``                   0.861    32 / 25, p = 0.43
``posterior``                  0.854    35 / 43, p = 0.43
``promote``                    0.858    10 / 10, p = 1.00
=============================  =======  ===================

None is a gain that can be shown: each doubt moves about as many worlds one way as the other. The runs
were throwaway prototypes of these variants; this script gives each prototype's success on worlds
1,000-1,099 (``--worlds 100``: 0.720 as it is; 0.760 / 0.760 / 0.740 / 0.730), and with ``--check`` the
map doubting nothing wins exactly the planner's worlds.

The tracked walkers' spread, both ways (this script, ``--worlds 1000 --start 1000 --variants aged in-view``,
1,001 s on 2 cores; tuning worlds 1,000-1,999, where the planner as it is crossed 0.846): ``aged`` 0.836
(won only with / only without: 3 / 13, p = 0.021), ``in-view`` 0.840 (2 / 8, p = 0.11). A throwaway
prototype of each gave the same figures to the last digit. More spread for a walker out of sight costs
success, as a 0.15 m error of its place drawn besides did (``ArrivalsConfig.speed_sigma``); less spread
crossed fewer worlds too, by a margin 1,000 worlds cannot show. A throwaway prototype of ``aged`` that
shifted only the walkers whose disc lay within 2.5 m ahead won and lost exactly the same worlds as
``aged`` (0 of 1,000 differ): its cost is the walkers beside and just ahead of the robot.
The figures above were measured before the planner broke the last ties by its draws' options
(``ArrivalsConfig.ties`` "options"); the script runs the planner as it is now.

``ghosts``, with the options' tie-break (fingerprint ``28e5ef29ec515817``; a throwaway prototype run under the
names ``ghost:4`` / ``ghost:8``, :data:`GHOST_AGE` 4 / 8; this script's ``ghosts`` took the same action at
every step of 40 episodes on tuning worlds 8,000-8,039 and won the same 300 worlds 8,000-8,299). The rule was
written down before the runs: choose the age on tuning worlds 7,000-8,999, test the chosen one on 9,000-12,999
only if it wins more worlds than it loses there. On 7,000-7,999 / 8,000-8,999 (the planner as it is 0.838 /
0.862) both ages crossed 0.838 / 0.865, on the same worlds (3 / 3 and 7 / 4; together 10 / 7): a tie, taken by
4. The test, 9,000-12,999 (``--start S --worlds 1000 --variants ghosts``, about 6.5 minutes a slice; as it is
0.844 / 0.837 / 0.855 / 0.852): 0.845 (5 / 4), 0.843 (8 / 2), 0.851 (4 / 8), 0.851 (4 / 5); together 21 / 19,
p = 0.87: nothing. The ghosts are rarely decisive: on worlds 8,000-8,039, 34 were made and 69 of 381
decisions had one, yet the actions of only 1 of the 40 episodes changed. A drawn belief spread over the
walks no image has ruled out moves the draws' mean little; told exactly where such cylinders are, the planner
gains (``exp_moving_lost.py``'s ``S``, 14 / 3).

``told``, named before it ran as a size on tuning worlds 7,000-8,999 beside the planner as it is (a throwaway
prototype, ``told:4``, fingerprint ``28e5ef29ec515817``; this script's ``told`` won the same tuning worlds
8,000-8,039): 0.836 against 0.838 (won only with / only without: 1 / 3) and 0.864 against 0.862 (5 / 3);
together 6 / 6. The reading first given here (``S`` gains the *place*, which the walks miss) was wrong:
``exp_moving_drift.py`` finds the told ghosts a median 5 cm from their cylinder, and gets all of ``S`` (12 / 2
on 7,000-7,999) from ghosts that end only when a new disc is their own cylinder's and are made where a new
disc landed on the dropped one too. The ghosts lack identity (which new disc is which cylinder), not place.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import exp_moving_variants as variants
import numpy as np
from exp_moving_memory import belonging

from husky_course.config import Profile, get_profile, with_world
from husky_course.planners.arrivals import Arrivals
from husky_course.planners.base import EpisodeStart
from husky_course.planners.ghosts import TINY  # a ghost's slot always walks, as the library's do
from husky_course.planners.moving_discs import DiscTrackingPlanner, WalkingDiscMap
from husky_course.planners.reference import truth_in_frame
from husky_course.planners.registry import make_planner
from husky_course.planners.tracking import Tally
from husky_course.planners.walls import bounced, walk_on
from husky_course.sim.fast import FastSimulator

DOUBTS = ("remembered", "evidence", "posterior", "promote", "aged", "in-view", "ghosts", "told")
NOTHING = "nothing doubted"  #: the variant that must be the planner as it is (``--check``)
WALK_SHARE = 0.01  #: ``posterior`` draws a track read as standing when its posterior walks more often
GHOST_AGE = 4  #: ``ghosts``: steps after its disc was last made that a ghost is kept


class DoubtingMap(WalkingDiscMap):
    """:class:`WalkingDiscMap` that keeps, per disc, the weights it was born with and its age, and doubts
    what :attr:`doubts` names (module docstring). With nothing named it is the map, number for number."""

    doubts: frozenset[str] = frozenset()

    def reset(self) -> None:
        super().reset()
        self.birth = np.zeros((0, len(self.arrivals.hypotheses)))  # its age: the library map's ``age``
        self.ghosts: list[dict] = []  #: ``ghosts``: per dropped disc, ``x, r``, hypotheses ``ys, vs, open``
        self.draw: list[int] | None = None  #: a draw's hypothesis per ghost (None: the ghosts left out)
        self.ids = np.zeros(0, int)  #: ``told``: per disc, the cylinder it belongs to (-1: none)
        #: ``told``: every cylinder and its velocity in the robot's frame now (:func:`truth_in_frame`)
        self.truth: tuple[np.ndarray, np.ndarray] = (np.empty((0, 3)), np.empty(0))

    def add(self, obs: np.ndarray) -> None:  # WalkingDiscMap.add, with the doubts' hooks
        d, cols, pts, pieces = self.pieces(obs)
        discs, cyl, other = self.decode(d, cols, pts, pieces)
        centres = np.where(cyl[:, None] & self.centres, discs[:, :2], np.nan)
        self.motion.tracks.faces = self.faces
        v = self.motion.update(pts, pieces, centres)
        fresh = self.motion.tracks.fresh if len(pts) else np.zeros(0, bool)
        speed = np.array([v[i].mean() for i in pieces]) if pieces else np.empty(0)
        first = np.array([fresh[i].all() for i in pieces], bool) if pieces else np.zeros(0, bool)
        speed, first = self.first_sights(discs, cyl, speed, first)
        small = [np.ptp(pts[i, :2], axis=0).max() <= 1.0 for i in pieces]  # the pieces Tracks follows
        if "promote" in self.doubts:
            for j, idx in enumerate(pieces):
                if not cyl[j] and not first[j] and speed[j] != 0 and small[j]:
                    cyl[j], other[cols[idx]] = True, False
        doubt = np.zeros((len(discs), len(self.arrivals.hypotheses)))
        if self.arrive and first.any():
            doubt[first] = self.arrivals.weights(discs[first], self.walks)
        born = doubt.copy()
        if "posterior" in self.doubts:
            tracks = self.motion.tracks
            order = np.cumsum(small) - 1  # each small piece's track in tracks.tracks
            for j in np.flatnonzero(~first & (speed == 0) & np.array(small, bool)):
                row = posterior(tracks, tracks.tracks[order[j]], self.arrivals.hypotheses)
                doubt[j] = row if 1.0 - row[0] > WALK_SHARE else 0.0
        self.arrivals.remember(d)
        kept = self._merge(obs, d, discs[cyl], other)
        self.speeds = np.r_[speed[cyl], self.speeds[kept]]
        self.fresh = np.r_[first[cyl], self.fresh[kept]]
        self.doubt = np.r_[doubt[cyl], np.zeros((int(kept.sum()), doubt.shape[1]))]
        self.birth = np.r_[born[cyl], self.birth[kept]]

    def move(self, dx: float, dy: float) -> np.ndarray:
        kept = super().move(dx, dy)
        self.birth = self.birth[kept]
        if "told" in self.doubts:
            self.ids = self.ids[kept]
        for g in self.ghosts:  # dead reckoning, then one step of each hypothesis's walk (bouncing)
            g["x"], g["life"] = g["x"] - dx, g["life"] + 1
            n = len(g["ys"])
            g["ys"], g["vs"] = walk_on(np.c_[np.full(n, g["x"]), g["ys"] - dy, np.full(n, g["r"])], g["vs"],
                                       self.faces)
        self.ghosts = [g for g in self.ghosts if g["x"] > -self.forget_behind and g["life"] <= GHOST_AGE]
        return kept

    def _merge(self, obs: np.ndarray, d: np.ndarray, new: np.ndarray, other: np.ndarray) -> np.ndarray:
        if "ghosts" in self.doubts:  # before the map drops what this image sees through
            for g in self.ghosts:
                g["open"] &= ~self.seen_through(g, d)
            self.ghosts = [g for g in self.ghosts if g["open"].any() and not found(g, new)]
            seen, landed = self.forgotten(d, new)
            for k in np.flatnonzero(seen & ~landed):
                g = self.ghost(k, d)
                if g["life"] <= GHOST_AGE and g["open"].any() and not found(g, new):
                    self.ghosts.append(g)
        kept = super()._merge(obs, d, new, other)
        if "told" in self.doubts:  # new discs first, as the map keeps them
            self.ids = np.r_[belonging(new, self.truth[0]) if len(new) else np.zeros(0, int), self.ids[kept]]
        return kept

    def ghost(self, k: int, d: np.ndarray) -> dict:
        """A ghost of remembered disc ``k``: ``x, r``, one hypothesis per walk from where its disc was made
        (``ys, vs``), those the image of per-column depth ``d`` saw through closed (``open``), its ``life``
        (the disc's age, at least 1) and, with ``told``, its cylinder (``id``; -1 otherwise)."""
        h, (x, y, r), age = self.arrivals.hypotheses, self.discs[k], max(int(self.age[k]), 1)
        told = int(self.ids[k]) if "told" in self.doubts else -1
        g = {"x": x, "r": r, "ys": y + (h - self.speeds[k]) * age, "vs": h.copy(),
             "open": np.ones(len(h), bool), "life": age, "id": told}
        g["open"] &= ~self.seen_through(g, d)
        return g

    def seen_through(self, ghost: dict, d: np.ndarray) -> np.ndarray:
        """Per hypothesis of ``ghost``: a column of the image of per-column depth ``d`` saw through its circle
        (reached more than the arrivals' ``tolerance`` past its front)."""
        return through(self.arrivals, self.arrivals.front(ghost["x"], ghost["ys"], ghost["r"]), d)

    def _slots(self) -> tuple[np.ndarray, np.ndarray]:
        """``(points (ghosts, 3), velocity (ghosts,))`` of the ghosts' slots: each at :attr:`draw`'s
        hypothesis, walking at it; with no draw, far behind the robot (left out)."""
        if not self.ghosts:
            return np.empty((0, 3)), np.empty(0)
        if self.draw is None:
            return np.array([(-1e3, 0.0, g["r"]) for g in self.ghosts]), np.full(len(self.ghosts), TINY)
        chosen = list(zip(self.ghosts, self.draw, strict=True))
        v = np.array([g["vs"][i] for g, i in chosen])
        return np.array([(g["x"], g["ys"][i], g["r"]) for g, i in chosen]), np.where(v == 0, TINY, v)

    @property
    def points(self) -> np.ndarray:
        """The map's points, then one slot per ghost (``ghosts``; none otherwise)."""
        return np.concatenate([super().points, self._slots()[0]])

    @property
    def velocity(self) -> np.ndarray:
        """The map's velocities, then the ghosts' slots'."""
        return np.r_[self.speeds, np.zeros(len(super().points) - len(self.speeds)), self._slots()[1]]

    def remembered(self) -> tuple[np.ndarray, np.ndarray]:
        """``(index, weights)`` of the remembered first sights still standing undecided (with
        ``evidence``, their walks an image taken since their birth saw through ruled out)."""
        if not {"remembered", "evidence"} & self.doubts:
            return np.zeros(0, int), np.zeros((0, self.birth.shape[1]))
        index = np.flatnonzero(self.fresh & (self.speeds == 0) & (self.age > 0) & self.birth.any(1))
        w = self.birth[index].copy()
        if "evidence" in self.doubts:
            a, h = self.arrivals, self.arrivals.hypotheses
            for n, k in enumerate(index):
                x, y, r = self.discs[k]
                seen = np.zeros(len(h), bool)
                for j, (depth, shift) in enumerate(a.history[: self.age[k]]):  # j steps ago, newest first
                    seen |= through(a, a.front(x + shift[0], y + shift[1] + h * (self.age[k] - j), r), depth)
                left = w[n] * ~seen
                if left.sum() > 0:
                    w[n] = left / left.sum()
        return index, w


def through(a: Arrivals, front: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """Per hypothesis (row of ``front``, :meth:`~husky_course.planners.arrivals.Arrivals.front`): a column of
    the image of per-column depth ``depth`` saw through its circle (reached more than ``a``'s ``tolerance``
    past its front, where the front lies within the camera's range)."""
    with np.errstate(invalid="ignore"):  # inf - inf off the circle: masked
        return ((front < a.camera.far - a.tolerance) & (depth[None] > front + a.tolerance)).any(1)


def course_prior(fraction: float, n: int) -> np.ndarray:
    """The course's motion model over ``n`` hypotheses, standing first: standing ``1 - fraction``, each of
    the ``n - 1`` walks an equal share of ``fraction``."""
    return np.r_[1.0 - fraction, np.full(n - 1, fraction / (n - 1))]


def found(ghost: dict, new: np.ndarray) -> bool:
    """Whether a disc of ``new (k, 3)`` overlaps an open hypothesis of ``ghost`` (its cylinder seen again)."""
    if not len(new):
        return False
    ys = ghost["ys"][ghost["open"]]
    gap = np.hypot(ghost["x"] - new[None, :, 0], ys[:, None] - new[None, :, 1])
    return bool((gap < ghost["r"] + new[None, :, 2]).any())


def posterior(tracks, track: np.ndarray, hypotheses: np.ndarray) -> np.ndarray:
    """A track's posterior over ``hypotheses`` (velocities, standing first): the course's prior (standing
    ``1 - fraction``, each walk an equal share), its line's slope normal about each with the standard
    error :meth:`~husky_course.planners.motion.Tracks.judged` gives it."""
    fraction = tracks.prior[0]
    w, s = 1.0 / track[:, 3] ** 2, -track[:, 0]
    se = tracks.error_scale / np.sqrt(np.sum(w * (s - np.average(s, weights=w)) ** 2))
    log = -0.5 * ((tracks.line(track)[1] - hypotheses) / se) ** 2
    p = course_prior(fraction, len(hypotheses)) * np.exp(log - log.max())
    return p / p.sum()


def decide(planner, horizon: int) -> tuple[int, np.ndarray]:
    """``TrackingPlanner._decide``'s draws, with the map's remembered first sights drawn too, each put where
    its drawn walk has taken it since its birth."""
    lattice, ranking = planner._ranking(horizon)
    choice, keys = int(ranking.choice[0][0]), ranking.keys[0][0]
    m, h = planner.map, planner.map.arrivals.hypotheses
    group, weights = m.walk_doubt
    tracked = planner.tracked if planner.speed_sigma > 0 else np.zeros(0, bool)
    index, born = m.remembered()
    prior = course_prior(m.walks, len(h))
    ghosts = [prior * g["open"] / (prior * g["open"]).sum() for g in m.ghosts] if m.ghosts else []
    y_true = [None if g["id"] < 0 else m.truth[0][g["id"], 1] for g in m.ghosts]  # ``told``'s truth
    told = [None if y is None else int(np.argmin(np.where(g["open"], np.abs(g["ys"] - y), np.inf)))
            for g, y in zip(m.ghosts, y_true, strict=True)]  # the open hypothesis nearest its cylinder now
    lib = m.dropped.weights() if m.dropped is not None else []  # the library's ghosts, drawn as it draws them
    if not (len(weights) or tracked.any() or len(index) or ghosts or lib):
        return Tally.undrawn(planner.ties, choice, keys, lattice)
    rng = np.random.default_rng((planner._key, planner._remaining))
    later = np.random.default_rng((planner._key, planner._remaining, 7))  # the driver's draws unchanged
    tally, base, k = Tally(planner.ties, keys), planner.velocity, int(tracked.sum())
    drawn_ones = (group >= 0) & (base == 0) if len(weights) else None
    y0, slots = m.discs[:, 1].copy(), len(base) - len(ghosts)
    for _ in range(planner.samples):
        speeds = base.copy()
        if drawn_ones is not None:
            drawn = h[[rng.choice(len(h), p=w) for w in weights]]
            speeds = np.where(drawn_ones, drawn[np.maximum(group, 0)], speeds)
        if k:
            speeds[tracked] += rng.normal(0.0, planner.speed_sigma, k)
            walkers = np.flatnonzero(tracked[: len(y0)])
            if "aged" in m.doubts:  # the drawn error has moved it since its last sighting
                m.discs[walkers, 1] += (speeds - base)[walkers] * m.age[walkers]
            if "in-view" in m.doubts:  # only the walkers this image shows are drawn
                old = walkers[m.age[walkers] > 0]
                speeds[old] = base[old]
        if len(index):
            v, r, age = h[[later.choice(len(h), p=w) for w in born]], m.discs[index, 2], m.age[index]
            m.discs[index, 1] = bounced(y0[index], v, age, r, m.faces)
            turned = bounced(y0[index], v, age + 1e-3, r, m.faces) - m.discs[index, 1]
            speeds[index] = np.sign(turned) * np.abs(v)
        if ghosts:  # each ghost at a hypothesis drawn from the course's prior over its open ones
            m.draw = [int(later.choice(len(h), p=w)) for w in ghosts]
            if "told" in m.doubts:  # or at the open one nearest its cylinder now, in every draw
                m.draw = [d if t is None else t for t, d in zip(told, m.draw, strict=True)]
            speeds[slots:] = m._slots()[1]
        if lib:  # the planner's points end with the library's ghosts' slots (DiscTrackingPlanner.points)
            m.dropped.draw = [int(later.choice(len(h), p=w)) for w in lib]
            speeds = np.r_[speeds, m.dropped.slots()[1]]
        try:
            tally.add(planner._keys_if(horizon, speeds), planner._drawn)
        finally:
            m.discs[:, 1], m.draw = y0, None
            if m.dropped is not None:
                m.dropped.draw = None
    return tally.ranked()


class ToldPlanner(DiscTrackingPlanner):
    """``told``: the disc planner with eyes of its own on the world (privileged), so that its map can tell
    each ghost where its cylinder is (:class:`~husky_course.planners.reference.SeenMotionPlanner`'s way)."""

    privileged = True

    def reset(self, start: EpisodeStart) -> None:
        super().reset(start)
        self.eyes = FastSimulator(start.sim.config)
        self.eyes.load(start.sim.world)
        self.time = 0.0

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        self.map.truth = truth_in_frame(self.eyes.world, np.asarray(pose, float), self.time)
        return super().act(obs, pose)

    def observe(self, action: int, obs_next: np.ndarray | None) -> None:
        super().observe(action, obs_next)
        self.time += 1.0


def doubting_planner(profile: Profile, variant: str):
    """The disc planner doubting what ``variant`` names (``+``-joined :data:`DOUBTS`; :data:`NOTHING`:
    none); the planner as it is for ``"as it is"``."""
    planner = make_planner("discs", config=profile.sim, profile=profile)
    if variant == "as it is":
        return planner
    doubts = frozenset() if variant == NOTHING else frozenset(variant.split("+"))
    if not doubts <= set(DOUBTS):
        raise SystemExit(f"a variant joins {DOUBTS} with '+'; got {variant!r}")
    if "told" in doubts:  # ghosts, each told its open hypothesis nearest the truth (privileged)
        planner.__class__, doubts = ToldPlanner, doubts | {"ghosts"}
    planner.map.__class__ = DoubtingMap
    planner.map.doubts = doubts
    if "ghosts" in doubts:  # these ghosts in place of the library's (ArrivalsConfig.ghosts)
        planner.map.dropped = None
    planner.map.reset()
    planner._decide = lambda horizon: decide(planner, horizon)
    return planner


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=2000)
    parser.add_argument("--start", type=int, default=1000, help="first world of the tuning set's sequence")
    parser.add_argument("--seed", type=int, default=1, help="evaluation set (1: the tuning set)")
    parser.add_argument("--variants", nargs="+", default=list(DOUBTS))
    parser.add_argument("--check", action="store_true", help="add the variant with nothing doubted")
    parser.add_argument("--base", type=Path, help=variants.BASE_HELP)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    profile = with_world(get_profile(args.profile), "moving")
    names = [*args.variants, *([NOTHING] if args.check else [])]
    for variant in names:
        doubting_planner(profile, variant)  # a bad name fails before any world runs
    worlds = variants.tuning_worlds(args.start, args.worlds, args.profile, args.seed)
    variants.paired_episodes(doubting_planner, names, profile, worlds, args.workers, args.base)


if __name__ == "__main__":
    main()
