"""Ghosts: discs the moving disc planner's map dropped, kept as beliefs over the walks no image ruled out.

The disc map (:class:`~husky_course.planners.discs.DiscMap`) drops a remembered disc when an image sees
its place again or through it: a new disc stands for it, or nothing is there. On the moving course the
second is often wrong. Along the planner's runs three drops in four are *first sights*: one image placed
the walker within centimetres, the walker left view before the next image, and that image saw through
the spot it had left; its disc was half a metre off after a single unseen step
(``benchmarks/exp_moving_drift.py``). Given each such cylinder back exactly (privileged), the planner
gains about a point.

A :class:`Ghost` keeps the dropped disc as one hypothesis per walk of the course's motion model
(:class:`~husky_course.planners.arrivals.Arrivals`' ``hypotheses``: standing, or walking either way at a
speed of ``speed_range``), each from where its disc was last made: the walk that kept its own speed
replaced by each of them. Every later image rules out the hypotheses one of its columns sees through.
In each of the planner's draws (:class:`~husky_course.config.ArrivalsConfig`'s ``samples``) every ghost
stands at one open hypothesis drawn from the course's motion model, walking at it
(:meth:`~husky_course.planners.tracking.TrackingPlanner._decide`); the map's own ranking leaves ghosts
out.

What makes them pay is *identity*: which new disc is the dropped cylinder's. A ghost told that
(privileged) gains all of the point; a ghost ended by any new disc over one of its walks gains none
(``benchmarks/exp_moving_identity.py``). The camera's own answer is the tracks
(:class:`~husky_course.planners.motion.Tracks`): a piece of surface joins the track whose line predicts
it, and keeps its name. So each disc carries its piece's track's name, and

* a ghost is made for a disc an image saw again or through unless the tracks say its cylinder was found:
  a new disc continues its track, or a new disc that continues no earlier track (a first sight, or a
  piece too long to track) lands on it (centres closer than the larger radius; any new disc lands, for a
  disc without a track);
* a ghost ends when a new disc continues its track, or a new disc that continues no earlier track
  overlaps one of its open walks (any new disc, for a ghost without a track); when no walk is left open;
  when it falls behind the map's ``forget_behind``; or ``ghost_age`` steps after its disc was made.

The measurements behind the rule are in :class:`~husky_course.config.ArrivalsConfig` (``ghosts``).
Nothing here is privileged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .arrivals import Arrivals
from .walls import walk_on

TINY = 1e-9  #: m per step: a ghost's slot always walks, so the draws share the standing points' clearances


@dataclass
class Ghost:
    """A dropped disc at ``x`` of radius ``r``: per hypothesis its lateral place ``ys`` and velocity ``vs``
    now, whether it is still ``open``; ``life``, steps since its disc was made; ``name``, its disc's track's
    name (-1: none)."""

    x: float
    r: float
    ys: np.ndarray
    vs: np.ndarray
    open: np.ndarray
    life: int
    name: int


class Ghosts:
    """The ghosts of one map (module docstring): :meth:`update` with each image before the map drops what it
    sees through, :meth:`move` after each step; :meth:`slots` and :meth:`weights` for the planner's draws.

    Parameters
    ----------
    arrivals : Arrivals
        The map's: its ``hypotheses`` are the walks, its :meth:`~Arrivals.front` and ``tolerance`` say
        which a column sees through.
    fraction : float
        The course's share of walking cylinders (its motion model's prior: standing ``1 - fraction``).
    age : int
        Steps after its disc was made that a ghost is kept.
    """

    def __init__(self, arrivals: Arrivals, fraction: float, age: int) -> None:
        if int(age) != age or age < 1:
            raise ValueError(f"a ghost's age must be a whole number >= 1, got {age!r}")
        h = arrivals.hypotheses
        self.arrivals, self.age = arrivals, int(age)
        self.prior = np.r_[1.0 - fraction, np.full(len(h) - 1, fraction / max(len(h) - 1, 1))]
        self.reset()

    def reset(self) -> None:
        """Forget every ghost (a new episode)."""
        self.items: list[Ghost] = []
        self.draw: list[int] | None = None  #: a draw's hypothesis per ghost (None: the ghosts left out)

    def __len__(self) -> int:
        return len(self.items)

    def update(self, d: np.ndarray, discs: np.ndarray, speeds: np.ndarray, ages: np.ndarray,
               names: np.ndarray, seen: np.ndarray, new: np.ndarray, new_names: np.ndarray,
               strange: np.ndarray) -> None:
        """One image, before the map merges it: per-column depth ``d``; the remembered ``discs (n, 3)``,
        their ``speeds``, ``ages`` (steps since made), track ``names`` and which the image ``seen`` again or
        through (:meth:`~husky_course.planners.discs.DiscMap.forgotten`); the image's ``new (k, 3)`` discs,
        their track names ``new_names`` and which continue no earlier track (``strange``). Rules out the
        walks the image sees through, ends the ghosts whose cylinder it found, and makes one for each disc
        seen whose cylinder the tracks say it did not find."""
        for g in self.items:
            g.open &= ~self.seen_through(g, d)
        self.items = [g for g in self.items if not self._ended(g, new, new_names, strange)]
        made = seen & (self.found(discs, names, new, new_names, strange) == 0)
        h = self.arrivals.hypotheses
        for k in np.flatnonzero(made):
            (x, y, r), life = discs[k], max(int(ages[k]), 1)
            g = Ghost(float(x), float(r), y + (h - speeds[k]) * life, h.copy(), np.ones(len(h), bool), life,
                      int(names[k]))
            g.open &= ~self.seen_through(g, d)
            if g.life <= self.age and not self._ended(g, new, new_names, strange):
                self.items.append(g)

    def move(self, dx: float, dy: float, faces: tuple[float, float], behind: float) -> None:
        """Dead reckoning after a step that moved the robot by ``(dx, dy)``, then one step of each
        hypothesis's walk, bouncing off the side walls' ``faces``; a ghost further than ``behind`` m
        behind, or older than :attr:`age`, ends."""
        for g in self.items:
            g.x, g.life = g.x - dx, g.life + 1
            n = len(g.ys)
            g.ys, g.vs = walk_on(np.c_[np.full(n, g.x), g.ys - dy, np.full(n, g.r)], g.vs, faces)
        self.items = [g for g in self.items if g.x > -behind and g.life <= self.age]

    def seen_through(self, g: Ghost, d: np.ndarray) -> np.ndarray:
        """Per hypothesis of ``g``: a column of the image of per-column depth ``d`` saw through its circle
        (reached more than the arrivals' ``tolerance`` past its front, the front within the camera's
        range)."""
        a = self.arrivals
        front = a.front(g.x, g.ys, g.r)
        with np.errstate(invalid="ignore"):  # inf - inf off the circle: masked
            return ((front < a.camera.far - a.tolerance) & (d[None] > front + a.tolerance)).any(1)

    def slots(self) -> tuple[np.ndarray, np.ndarray]:
        """``(points (ghosts, 3), velocity (ghosts,))``: each ghost at :attr:`draw`'s hypothesis, walking at
        it; none without a draw (the map's own ranking leaves the ghosts out)."""
        if not self.items or self.draw is None:
            return np.empty((0, 3)), np.empty(0)
        v = np.array([g.vs[i] for g, i in zip(self.items, self.draw, strict=True)])
        points = np.array([(g.x, g.ys[i], g.r) for g, i in zip(self.items, self.draw, strict=True)])
        return points, np.where(v == 0, TINY, v)

    def weights(self) -> list[np.ndarray]:
        """Per ghost, the course's motion model over its open hypotheses (what each draw is drawn from)."""
        return [self.prior * g.open / (self.prior * g.open).sum() for g in self.items]

    @staticmethod
    def found(discs: np.ndarray, names: np.ndarray, new: np.ndarray, new_names: np.ndarray,
              strange: np.ndarray) -> np.ndarray:
        """Per remembered disc, whether the image found its cylinder (:func:`found`; an experiment may
        replace the rule here)."""
        return found(discs, names, new, new_names, strange)

    @staticmethod
    def _ended(g: Ghost, new: np.ndarray, new_names: np.ndarray, strange: np.ndarray) -> bool:
        if not g.open.any():
            return True
        if g.name >= 0:
            return bool((new_names == g.name).any()) or overlaps(g, new[strange])
        return overlaps(g, new)


def overlaps(g: Ghost, new: np.ndarray) -> bool:
    """Whether a disc of ``new (k, 3)`` overlaps an open hypothesis of ghost ``g``."""
    if not len(new):
        return False
    ys = g.ys[g.open]
    gap = np.hypot(g.x - new[None, :, 0], ys[:, None] - new[None, :, 1])
    return bool((gap < g.r + new[None, :, 2]).any())


def found(discs: np.ndarray, names: np.ndarray, new: np.ndarray, new_names: np.ndarray,
          strange: np.ndarray) -> np.ndarray:
    """Per remembered disc of ``discs (n, 3)`` (track ``names``), whether the tracks say the new image found
    its cylinder again, and how: 1, a disc of ``new (k, 3)`` (track names ``new_names``) continues its
    track; 2, a new disc that continues no earlier track (``strange``) lands on it (centres closer than the
    larger radius; any new disc lands, for a disc without a track); 0, neither."""
    if not len(new):
        return np.zeros(len(discs), int)
    gap = np.hypot(discs[:, None, 0] - new[None, :, 0], discs[:, None, 1] - new[None, :, 1])
    lands = gap < np.maximum(discs[:, None, 2], new[None, :, 2])
    mine = names[:, None] >= 0
    track = (mine & (names[:, None] == new_names[None])).any(1)
    return np.where(track, 1, np.where((lands & (strange[None] | ~mine)).any(1), 2, 0))
