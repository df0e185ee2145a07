"""The disc planner on the moving course (chapter 10): its learned discs walk, and it plans in space-time.

:class:`WalkingDiscMap` is the disc map (:class:`~husky_course.planners.discs.DiscMap`) whose discs
carry lateral velocities: read off successive scans by the tracker's
:class:`~husky_course.planners.motion.MotionMemory` (its tracks locating each cylinder's piece by
the network's disc centre, not a fitted circle), a first sight's by the earlier images' columns
(:meth:`~husky_course.planners.arrivals.Arrivals.read`), bouncing off the side walls' faces
(:mod:`~husky_course.planners.walls`). :class:`DiscTrackingPlanner` searches it in space-time as the
tracker (:class:`~husky_course.planners.tracking.TrackingPlanner`) searches its walking points, over
draws of what it doubts: the undecided first sights' walks and the tracked walkers' speeds
(:class:`~husky_course.config.ArrivalsConfig`'s ``samples`` and ``speed_sigma``), its ties going to the
plan that keeps the most clearance in the worst draw, then to the first primitive whose safe plans still
reach the most places at the horizon's end (its *options*, ``ties``). With ``ghosts`` its map keeps
the discs it drops where the tracks say no new disc is their cylinder, and its draws stand each at one
of the walks no image has ruled out (:mod:`~husky_course.planners.ghosts`).
The measurements behind each choice are in :mod:`~husky_course.planners.discs`,
:mod:`~husky_course.planners.arrivals` and :class:`~husky_course.config.WallsConfig`.
"""

from __future__ import annotations

import numpy as np

from ..config import ArrivalsConfig, SimConfig, TrackingConfig, WallsConfig
from ..models.discs import DiscNet
from .arrivals import Arrivals
from .cuts import PieceCutter
from .discs import DiscMap, DiscPlanner
from .ghosts import Ghosts
from .motion import MotionMemory
from .tracking import TrackingPlanner, _set_doubt
from .walls import NO_WALLS, walk_on, wall_faces


class WalkingDiscMap(DiscMap):
    """A :class:`DiscMap` whose discs walk (the moving course, chapter 10).

    Each new disc carries the lateral velocity of its piece, read off successive scans by the
    tracker's :class:`~husky_course.planners.motion.MotionMemory` (the mean over the piece's points;
    with ``centres`` its tracks locate a cylinder's piece by the disc's centre, not a fitted circle;
    a first sight's from the earlier images, :meth:`first_sights`); after every step a
    remembered disc walks on by it. Walls, and the points no disc explains, stand. On the static
    course every velocity is 0 and it is the :class:`DiscMap`. ``faces``: the walls' (:mod:`.walls`).

    Each disc also carries its age (steps since an image made it) and its piece's track's name
    (:class:`~husky_course.planners.motion.Tracks`; -1: none). With ``ghosts`` (the moving course only), a
    disc dropped where the tracks say no new disc is its cylinder is kept as a ghost (:mod:`.ghosts`,
    :attr:`dropped`), kept at most ``ghost_age`` steps after its disc was made; the planner's draws
    stand it at one of its walks (:class:`DiscTrackingPlanner`).
    """

    def __init__(self, model: DiscNet, config: SimConfig | None = None, forget_behind: float = 1.8,
                 unexplained: float = 0.05, widen: float = 0.0, arrivals: bool = True,
                 centres: bool = TrackingConfig.disc_centres, ghosts: bool = ArrivalsConfig.ghosts,
                 ghost_age: int = ArrivalsConfig.ghost_age) -> None:
        super().__init__(model, config, forget_behind, unexplained)
        self.motion = MotionMemory(config or SimConfig())
        self.centres = bool(centres)  #: the tracks locate a cylinder's piece by its disc's centre
        self.arrivals, self.arrive = Arrivals(config or SimConfig()), bool(arrivals)
        self.widen = float(widen)
        self.speeds, self.fresh = np.empty(0), np.zeros(0, bool)
        self.width, self.faces, self.wall_rule = (config or SimConfig()).world.width, NO_WALLS, WallsConfig()
        self.walks = float(getattr((config or SimConfig()).world, "moving_fraction", 0.0))
        self.doubt = np.zeros((0, len(self.arrivals.hypotheses)))
        #: the dropped discs kept as ghosts (None: off, or the static course)
        self.dropped = Ghosts(self.arrivals, self.walks, ghost_age) if ghosts and self.walks > 0 else None
        self.age, self.names = np.zeros(0, int), np.zeros(0, int)

    def reset(self) -> None:
        super().reset()
        self.motion.reset()
        self.speeds, self.fresh, self.faces = np.empty(0), np.zeros(0, bool), NO_WALLS
        self.arrivals.reset()
        self.doubt = np.zeros((0, len(self.arrivals.hypotheses)))
        self.age, self.names = np.zeros(0, int), np.zeros(0, int)
        if getattr(self, "dropped", None) is not None:
            self.dropped.reset()

    @property
    def points(self) -> np.ndarray:
        """Discs, then (with ``widen``) a standing copy of every first-sight disc ``widen`` m to each
        side (where it may have walked by the time the robot passes), then wall points."""
        first = self.discs[self.fresh] if self.widen > 0 else np.empty((0, 3))
        side = [first + (0.0, s * self.widen, 0.0) for s in (-1, 1)]
        return np.concatenate([self.discs, *side, self.walls.points])

    @property
    def velocity(self) -> np.ndarray:
        """Per point of :attr:`points`: the discs' velocities (m per step along ``y``), then 0."""
        return np.r_[self.speeds, np.zeros(len(self.points) - len(self.speeds))]

    @property
    def walk_doubt(self) -> tuple[np.ndarray, np.ndarray]:
        """``(group, weights)``: per point of :attr:`points`, which of ``weights``' rows its walk is drawn
        from (-1: none), and per row the weights over :attr:`arrivals`' hypotheses: the last image's
        first sights that the earlier images leave undecided (:meth:`Arrivals.weights`)."""
        open_ = np.flatnonzero(self.doubt.any(1))
        group = np.full(len(self.points), -1)
        group[open_] = np.arange(len(open_))
        return group, self.doubt[open_]

    def add(self, obs: np.ndarray) -> None:
        d, cols, pts, pieces = self.pieces(obs)
        discs, cyl, other = self.decode(d, cols, pts, pieces)
        centres = np.where(cyl[:, None] & self.centres, discs[:, :2], np.nan)  # the tracks' sightings
        # Each disc is where this image's network puts it. A prototype that put a tracked disc where its
        # track's weighted looks put it (x their mean; y the mean, or the walk's line now for a walker)
        # crossed 0.843 against 0.846 on tuning worlds 1,000-1,999 (won only with / only without: 13 / 16):
        # the discs' places are not what costs (benchmarks/exp_moving_memory.py, rules md / mn)
        self.motion.tracks.faces = self.faces  # its tracks fold a walk that bounced off them
        v = self.motion.update(pts, pieces, centres)
        fresh = self.motion.tracks.fresh if len(pts) else np.zeros(0, bool)
        speed = np.array([v[i].mean() for i in pieces]) if pieces else np.empty(0)
        first = np.array([fresh[i].all() for i in pieces], bool) if pieces else np.zeros(0, bool)
        speed, first = self.first_sights(discs, cyl, speed, first)
        doubt = np.zeros((len(discs), len(self.arrivals.hypotheses)))
        if self.arrive and first.any():
            doubt[first] = self.arrivals.weights(discs[first], self.walks)
        self.arrivals.remember(d)
        # The other pieces' points stand, even where their track reads a walk. A prototype that made them
        # walk (each such piece's points, and those a walking disc leaves unexplained, as small discs at
        # the track's speed; about one piece in three worlds) crossed 0.847 against 0.846 on tuning worlds
        # 1,000-1,999 (won only with / only without: 5 / 4)
        kept = self._merge(obs, d, discs[cyl], other)
        self.speeds = np.r_[speed[cyl], self.speeds[kept]]
        self.fresh = np.r_[first[cyl], self.fresh[kept]]
        self.doubt = np.r_[doubt[cyl], np.zeros((int(kept.sum()), doubt.shape[1]))]

    def decode(self, d: np.ndarray, cols: np.ndarray, pts: np.ndarray,
               pieces: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        out = super().decode(d, cols, pts, pieces)
        self._cylinder = out[1]  # which pieces become discs: the new discs' tracks (:meth:`_merge`)
        return out

    def _aligned(self) -> None:
        """Discs set from outside (a test, a privileged reference's told cylinders): those beyond the ones
        this map made count as made now, by no track."""
        n = len(self.discs)
        if len(self.age) != n:
            keep = min(n, len(self.age))
            self.age = np.r_[self.age[:keep], np.zeros(n - keep, int)]
            self.names = np.r_[self.names[:keep], np.full(n - keep, -1)]

    def _merge(self, obs: np.ndarray, d: np.ndarray, new: np.ndarray, other: np.ndarray) -> np.ndarray:
        """:meth:`DiscMap._merge`, the ghosts told the image first; the new discs' ages and names kept."""
        self._aligned()
        names, strange = np.full(len(new), -1), np.ones(len(new), bool)
        tracks = self.motion.tracks
        if len(new) and self.motion.max_step > 0:  # the moving course: the tracks named this image's pieces
            names, strange = tracks.piece_names[self._cylinder], ~tracks.continued[self._cylinder]
        if self.dropped is not None:
            seen = self.forgotten(d, new)[0]
            self.dropped.update(d, self.discs, self.speeds, self.age, self.names, seen, new, names, strange)
        kept = super()._merge(obs, d, new, other)
        self.age = np.r_[np.zeros(len(new), int), self.age[kept]]
        self.names = np.r_[names, self.names[kept]]
        return kept

    def first_sights(self, discs: np.ndarray, cyl: np.ndarray, speed: np.ndarray,
                     first: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(speed, first)`` per piece of an image, its first sights read (``discs (n, 3)`` its
        discs, ``cyl`` which are cylinders, ``first`` which its tracks see for the first time): with
        ``arrivals``, a first sight's walk as :meth:`~husky_course.planners.arrivals.Arrivals.read`
        reads it off the earlier images. The previous image is still :attr:`arrivals`' (an experiment
        may read first sights its own way here)."""
        if self.arrive:
            speed = np.where(first, self.arrivals.read(discs), speed)
        return speed, first

    def move(self, dx: float, dy: float) -> np.ndarray:
        """Dead reckoning; the walls' faces read again; each disc walks on, bouncing off them."""
        self.arrivals.move(dx, dy)
        self._aligned()
        kept = super().move(dx, dy)
        self.speeds, self.fresh = self.speeds[kept], self.fresh[kept]
        self.doubt = np.zeros((int(kept.sum()), self.doubt.shape[1]))  # the image's doubt is for its decision
        self.faces = wall_faces(self.walls.points, self.width, (self.faces[0] - dy, self.faces[1] - dy),
                                self.wall_rule)
        self.discs[:, 1], self.speeds = walk_on(self.discs, self.speeds, self.faces)
        self.motion.move(dx, dy)
        self.age, self.names = self.age[kept] + 1, self.names[kept]
        if self.dropped is not None:
            self.dropped.move(dx, dy, self.faces, self.forget_behind)
        return kept


class DiscTrackingPlanner(DiscPlanner):
    """The disc planner on the moving course: its discs walk (:class:`WalkingDiscMap`), and it plans
    in space-time exactly as the tracker (:class:`~husky_course.planners.tracking.TrackingPlanner`)
    does over its walking points: standing things on the clearance grid, each walking disc where it
    is at every sample's time; with ``samples``, over draws of its undecided first sights' walks and
    its tracked walkers' speeds (``speed_sigma``; ``TrackingPlanner._decide``). On the static course
    nothing walks or is drawn, and it is the :class:`DiscPlanner`."""

    name = "discs"
    _start_check, _decide = TrackingPlanner._start_check, TrackingPlanner._decide
    _decide_over_draws = TrackingPlanner._decide_over_draws
    _hypothesis, _steps_if = TrackingPlanner._hypothesis, TrackingPlanner._steps_if
    _keys_if = TrackingPlanner._keys_if

    def __init__(self, model: DiscNet, config: SimConfig | None = None, grow: float = 0.0,
                 unexplained: float = 0.05, widen: float = 0.0, arrivals: bool = True,
                 doubt_steps: float = ArrivalsConfig.doubt_steps,
                 doubt_hard: bool = ArrivalsConfig.doubt_hard, hedge: bool = ArrivalsConfig.hedge,
                 first_samples: int = ArrivalsConfig.first_samples, samples: int = ArrivalsConfig.samples,
                 speed_sigma: float = ArrivalsConfig.speed_sigma, centres: bool = TrackingConfig.disc_centres,
                 cutter: PieceCutter | None = None, ties: str = ArrivalsConfig.ties,
                 ghosts: bool = ArrivalsConfig.ghosts, ghost_age: int = ArrivalsConfig.ghost_age,
                 **kwargs: float) -> None:
        super().__init__(model, config, grow, unexplained, **kwargs)
        self.map = WalkingDiscMap(  # type: ignore[assignment]
            model, self.config, self.map.forget_behind, unexplained, widen, arrivals, centres, ghosts,
            ghost_age)
        self.map.cutter = cutter
        _set_doubt(self, doubt_steps, doubt_hard, hedge, first_samples, samples, speed_sigma, ties)

    @property
    def doubtful(self) -> np.ndarray:
        """Per point: a first-sight disc the arrivals rule left standing (it may yet walk either way)."""
        m = self.map
        discs = m.fresh & (m.speeds == 0)  # type: ignore[attr-defined]
        return np.r_[discs, np.zeros(len(self.points) - len(discs), bool)]

    @property
    def tracked(self) -> np.ndarray:
        """Per point: a disc walking at the speed its track reads (seen before, not a first sight)."""
        m = self.map
        walking = ~m.fresh & (m.speeds != 0)  # type: ignore[attr-defined]
        return np.r_[walking, np.zeros(len(self.points) - len(walking), bool)]

    @property
    def points(self) -> np.ndarray:
        """The map's points (:meth:`DiscPlanner.points`), then, within one of :meth:`_decide`'s draws, one
        slot per ghost of the map (:mod:`.ghosts`) where the draw stands it."""
        return np.concatenate([super().points, self._ghost_slots()[0]])

    @property
    def velocity(self) -> np.ndarray:
        """Each point's lateral velocity (m per step): the discs' estimates, 0 for walls, then the
        ghosts' slots' walks."""
        return np.r_[self.map.velocity, self._ghost_slots()[1]]  # type: ignore[attr-defined]

    def _ghost_slots(self) -> tuple[np.ndarray, np.ndarray]:
        ghosts = getattr(self.map, "dropped", None)
        return ghosts.slots() if ghosts is not None else (np.empty((0, 3)), np.empty(0))
