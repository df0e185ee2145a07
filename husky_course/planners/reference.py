"""Reference planners: perfect perception of what the camera has shown (chapters 8 and 10).

Every planner here is privileged on purpose (``privileged = True``: it is handed the simulator and
the true pose) and is an *analysis* tool, never a candidate: the book measures gaps with them and
ranks none of them. :func:`~husky_course.planners.registry.make_planner` builds them by the names in
:data:`~husky_course.planners.registry.REFERENCE_PLANNERS`, apart from the planners a student picks.

:class:`SeenObstaclesPlanner` replans at every step with the oracle's exact lattice search, but
over only some obstacles, with their true geometry (perfect perception):

* ``memory=False``: the obstacles the current image renders
  (:meth:`~husky_course.sim.fast.FastSimulator.visible_obstacles`);
* ``memory=True``: every obstacle any image so far has rendered.

The side walls are always known. The gap between the two is what memory buys a planner that
perceives perfectly; the gap between ``memory=True`` and the oracle (every obstacle, seen or not)
is what the unseen costs a planner that takes unseen space as free. They are references, not
bounds: a camera-based planner that is cautious about unseen space is bounded by neither (only
the oracle bounds every planner). Both read the course as it stands at time 0 (the static course).

:class:`SnapshotPlanner` is chapter 10's counterpart on the moving course: every cylinder where it
is now, none of its motion; :class:`SecondLookPlanner` knows a cylinder's motion only from its
second image on, as a planner reading motion off images must.

:class:`TrueDiscsPlanner` is the disc planner (:mod:`~husky_course.planners.discs`) with its
network replaced by the truth: each piece of a scan read as the cylinder most of its columns hit,
exactly (walls stay scan points). Against the disc planner it measures what the network's errors
cost; against "seen so far", what the disc map's own rules cost (chapter 8's ladder).

:class:`ToldDiscsPlanner` is the moving course's disc planner (its network, its map, its search)
whose walking map is *told* the truth, as much as its ``rule`` gives away (chapter 10's ladder,
:data:`TOLD_RULES`): the true velocity of its first sights, of every disc, or every cylinder any
image has rendered so far, exactly. Against the disc planner it measures what its motion estimates
and its memory cost. Told the first sights' motion, it still draws its tracked walkers' speeds as the
disc planner does (``ArrivalsConfig.speed_sigma``); told every disc's, it doubts none.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..config import ArrivalsConfig, OracleConfig
from ..sim.base import Simulator
from ..sim.fast import FastSimulator
from ..sim.lattice import disc_check, expand, expand_with, rank_plans
from ..sim.world import World
from .base import EpisodeStart, Planner, search_start
from .discs import DiscMap, DiscPlanner, majority_cylinder
from .moving_discs import DiscTrackingPlanner, WalkingDiscMap

#: What :class:`ToldDiscsPlanner`'s map is told: the true velocity of the discs its tracks call a first
#: sight; of every disc; or, every step, every cylinder an image has rendered so far, exactly, with
#: its true velocity (the knowledge of :class:`SeenMotionPlanner`, planned by the disc planner's search).
TOLD_RULES = ("first sights' motion", "every disc's motion", "every cylinder seen, exactly")
ON_CYLINDER = 0.3  #: a disc within this of a cylinder's surface is on it (m)


class _Reference(Planner):
    """What the reference planners share: privileged, replanning at every step with the oracle's exact
    lattice search (its cap and quantum), counting steps; subclasses choose which obstacles it sees."""

    privileged = True  # they read the true geometry of the world: analysis tools only

    def __init__(self, oracle: OracleConfig | None = None) -> None:
        super().__init__()
        self.oracle = oracle or OracleConfig()
        self._sim: Simulator | None = None
        self._time = self._remaining = 0

    def reset(self, start: EpisodeStart) -> None:
        super().reset(start)
        if start.sim is None or start.sim.world is None:
            raise RuntimeError(f"{type(self).__name__} is privileged: run it with run_episode")
        self._sim, self._time, self._remaining = start.sim, 0, start.max_primitives

    def _choose(self, lattice) -> int:
        """The oracle's choice on ``lattice`` (its best plan's first primitive); scores kept."""
        assert self._sim is not None
        ranking = rank_plans(lattice, np.abs(self._sim.library.offsets), self.oracle.cap, self.oracle.quantum)
        keys = ranking.keys[0][0]
        self.last_scores = -(keys - keys.max()) / 1e6
        return int(ranking.choice[0][0])

    def _choose_frozen(self, check, pose: np.ndarray) -> int:
        """:meth:`_choose` on the lattice of the remaining steps under a frozen (time-free) ``check``."""
        assert self._sim is not None
        start = search_start(pose, self._sim)
        lattice = expand_with(check, self._sim.library, start, max(self._remaining, 1))
        return self._choose(lattice)

    def observe(self, action: int, obs_next: np.ndarray | None) -> None:
        self._time += 1
        self._remaining -= 1


class _Seeing(_Reference):
    """A reference with eyes of its own: a private simulator of the same world, which tells it which
    cylinders the camera renders, and the set of those it has seen."""

    def __init__(self, oracle: OracleConfig | None = None) -> None:
        super().__init__(oracle)
        self._eyes: FastSimulator | None = None
        self._seen: set[int] = set()

    def reset(self, start: EpisodeStart) -> None:
        super().reset(start)
        self._eyes = FastSimulator(start.sim.config)
        self._eyes.load(start.sim.world)
        self._seen = set()


class SeenObstaclesPlanner(_Seeing):
    """Exact replanning over the obstacles seen now (or ever): perfect perception, no more."""

    def __init__(self, memory: bool, oracle: OracleConfig | None = None) -> None:
        super().__init__(oracle)
        self.memory = bool(memory)
        self.name = "seen so far (perfect perception)" if memory else "seen now (perfect perception)"

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        assert self._eyes is not None and self._eyes.world is not None and pose is not None
        world = self._eyes.world
        now = set(self._eyes.visible_obstacles(pose).tolist())
        self._seen = (self._seen | now) if self.memory else now
        obstacles = world.obstacles[sorted(self._seen)] if self._seen else np.empty((0, 3))
        check = disc_check(obstacles, world.wall_y, world.config.robot_radius, self.oracle.cap)
        return self._choose_frozen(check, pose)


class SeenMotionPlanner(_Seeing):
    """Exact space-time replanning over the cylinders seen so far, with their true motion (chapter 10).

    Privileged, an analysis tool: a reference for a camera-based planner on the moving course (not a
    bound: it takes unseen space, and a first sight's future, as known or free). Every
    cylinder any image so far has rendered (at its time) is known exactly, position *and* velocity,
    from then on; the others are unknown. Against the oracle, it measures what the camera never
    shows; against :class:`SnapshotPlanner`, what perceiving motion is worth.
    """

    name = "seen so far, with motion (perfect perception)"

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        assert self._eyes is not None and self._eyes.world is not None and pose is not None
        world = self._eyes.world
        new = set(self._eyes.visible_obstacles(pose, float(self._time)).tolist()) - self._seen
        self._seen |= new
        known = np.array(sorted(self._seen), int)
        sub = self._known_world(world, known, np.isin(known, sorted(new)))
        steps, pose = max(self._remaining, 1), search_start(pose, self._sim)
        return self._choose(expand(sub, self._eyes.library, pose, steps, self.oracle.cap, self._time))

    def _known_world(self, world: World, known: np.ndarray, first: np.ndarray) -> World:
        """The world it plans in: cylinders ``known`` (``first``: seen for the first time now), exactly."""
        speeds = None if world.speeds is None else world.speeds[known]
        return replace(world, obstacles=world.obstacles[known], speeds=speeds)


class SecondLookPlanner(SeenMotionPlanner):
    """:class:`SeenMotionPlanner`, except that a cylinder's motion is known only from its second image on.

    Privileged, an analysis tool: perception stays perfect (every cylinder seen, exactly where it
    is), but at first sight a cylinder is taken as standing where it is, as a planner that reads
    motion off successive images must (one image shows where, not whither). With ``widen`` it is
    also taken to stand at ``widen`` more places either side, half the fastest walk apart (a
    cautious reading of a first sight). Against :class:`SeenMotionPlanner` it measures what the
    first sight's missing motion costs, the part of the gap to the oracle no estimator closes.
    """

    def __init__(self, widen: int = 0, oracle: OracleConfig | None = None) -> None:
        super().__init__(oracle)
        self.widen = int(widen)
        self.name = "seen so far, motion from its second look" + (
            f" (first sight widened {widen}x)" if widen else ""
        )

    def _known_world(self, world: World, known: np.ndarray, first: np.ndarray) -> World:
        """As :class:`SeenMotionPlanner`'s, but a first sight stands where it is now (and, with
        ``widen``, beside it)."""
        obstacles = world.obstacles[known].copy()
        obstacles[first] = world.obstacles_at(float(self._time))[known[first]]  # where it is now, standing
        speeds = np.zeros(len(known)) if world.speeds is None else np.where(first, 0.0, world.speeds[known])
        if self.widen and first.any():  # a row of standing discs along where it may walk
            shifts = np.arange(-self.widen, self.widen + 1) * world.max_speed / 2
            rows = np.repeat(obstacles[first][:, None], len(shifts), axis=1)
            rows[..., 1] += shifts
            obstacles = np.concatenate([obstacles[~first], rows.reshape(-1, 3)])
            speeds = np.concatenate([speeds[~first], np.zeros(len(rows) * len(shifts))])
        return replace(world, obstacles=obstacles, speeds=speeds)


class SnapshotPlanner(_Reference):
    """Exact replanning over every cylinder where it stands *now*, as if it stood still (chapter 10).

    Privileged like :class:`SeenObstaclesPlanner`, an analysis tool: at step ``k`` it knows every
    cylinder's true position at time ``k`` (perfect perception of the present, unlimited field of
    view) but not where a cylinder is going. Against the space-time oracle, which knows both, it
    measures what knowing the motion is worth.
    """

    name = "snapshot (every position now, no motion)"

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        assert self._sim is not None and self._sim.world is not None and pose is not None
        world = self._sim.world
        now = world.obstacles_at(float(self._time))  # a frozen copy: positions at this step, no speeds
        check = disc_check(now, world.wall_y, world.config.robot_radius, self.oracle.cap)
        return self._choose_frozen(check, pose)


class _TrueReading(DiscMap):
    """A :class:`~husky_course.planners.discs.DiscMap` whose pieces are read from the truth."""

    eyes: FastSimulator
    pose: np.ndarray

    def read(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        d, cols, pts, pieces = self.reader.pieces(obs)
        kind = self.eyes.column_hits(self.pose[None])[1][0]
        other, discs = np.zeros(len(d), bool), []
        for idx in pieces:
            hit = majority_cylinder(kind[cols[idx]])
            if hit >= 0:  # the cylinder most of its columns hit
                ox, oy, r = self.eyes.world.obstacles[hit]  # type: ignore[union-attr]
                c, s = np.cos(self.pose[2]), np.sin(self.pose[2])
                dx, dy = ox - self.pose[0], oy - self.pose[1]
                discs.append([c * dx + s * dy, -s * dx + c * dy, r])
            else:
                other[cols[idx]] = True
        return d, np.array(discs, float).reshape(-1, 3), other


class TrueDiscsPlanner(DiscPlanner):
    """The disc planner reading every piece from the truth (module docstring). Privileged, static
    course only: an analysis tool, never a candidate."""

    privileged = True
    name = "discs, read from the truth (privileged)"

    def __init__(self, config=None, **kwargs) -> None:
        from ..models.discs import DiscNet  # an untrained net: the map's reader is replaced

        cfg = config or FastSimulator().config
        super().__init__(DiscNet(cfg.world.radius_range), cfg, unexplained=np.inf, **kwargs)
        self.map.__class__ = _TrueReading

    def reset(self, start: EpisodeStart) -> None:
        super().reset(start)
        if start.sim is None or start.sim.world is None:
            raise RuntimeError("TrueDiscsPlanner is privileged: run it with run_episode")
        self.map.eyes = FastSimulator(start.sim.config)  # type: ignore[attr-defined]
        self.map.eyes.load(start.sim.world)  # type: ignore[attr-defined]

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        self.map.pose = np.asarray(pose, float)  # type: ignore[attr-defined]
        return super().act(obs, pose)


def truth_in_frame(world: World, pose: np.ndarray, time: float) -> tuple[np.ndarray, np.ndarray]:
    """``(cylinders (n, 3), velocity (n,))``: every cylinder's ``(x, y, r)`` in the robot's frame at
    ``pose`` and ``time``, and its lateral velocity in that frame over the next step (m per step)."""
    now, later = world.obstacles_at(time), world.obstacles_at(time + 1.0)
    c, s = np.cos(pose[2]), np.sin(pose[2])
    rx = c * (now[:, 0] - pose[0]) + s * (now[:, 1] - pose[1])
    ry = -s * (now[:, 0] - pose[0]) + c * (now[:, 1] - pose[1])
    vy = -s * (later[:, 0] - now[:, 0]) + c * (later[:, 1] - now[:, 1])
    return np.c_[rx, ry, now[:, 2]], vy


class _ToldMap(WalkingDiscMap):
    """A :class:`~husky_course.planners.moving_discs.WalkingDiscMap` told the truth as ``rule`` allows."""

    rule: str
    eyes: FastSimulator
    pose: np.ndarray
    time: float
    seen: np.ndarray  #: the cylinders any image so far (this one included) has rendered

    def add(self, obs: np.ndarray) -> None:
        super().add(obs)
        assert self.eyes.world is not None
        cyl, vy = truth_in_frame(self.eyes.world, self.pose, self.time)
        if self.rule == TOLD_RULES[2]:
            self.discs, self.speeds = cyl[self.seen], vy[self.seen]
            self.fresh = np.zeros(len(self.seen), bool)
        self.doubt = np.zeros((len(self.discs), self.doubt.shape[1]))  # every rule tells first sights
        if self.rule == TOLD_RULES[2] or not len(self.discs):
            return
        gap = np.hypot(self.discs[:, :1] - cyl[:, 0], self.discs[:, 1:2] - cyl[:, 1]) - cyl[:, 2]
        j = np.argmin(gap, axis=1)
        truth = np.where(gap[np.arange(len(j)), j] < ON_CYLINDER, vy[j], 0.0)
        self.speeds = np.where(self.fresh | (self.rule == TOLD_RULES[1]), truth, self.speeds)


class ToldDiscsPlanner(DiscTrackingPlanner):
    """The moving disc planner whose map is told the truth by ``rule`` (:data:`TOLD_RULES`; module
    docstring). Privileged, the moving course: an analysis tool, never a candidate. ``profile``
    (default: :func:`~husky_course.config.get_profile`'s) gives its trained network (loaded, never
    trained) and settings; ``config``, the course (default: that profile's moving course)."""

    privileged = True

    def __init__(self, profile=None, rule: str = TOLD_RULES[0], config=None) -> None:
        from ..config import get_profile, with_world
        from ..training.discs import load_discs  # the trained network (torch)
        from .learned import disc_cutter

        if rule not in TOLD_RULES:
            raise ValueError(f"rule must be one of {TOLD_RULES}, got {rule!r}")
        profile = profile or get_profile()
        d = profile.discs
        sigma = ArrivalsConfig.speed_sigma if rule == TOLD_RULES[0] else 0.0  # every speed told: no doubt
        super().__init__(load_discs(profile)[0], config or with_world(profile, "moving").sim, grow=d.grow,
                         unexplained=d.unexplained, margin=d.margin, speed_sigma=sigma,
                         cutter=disc_cutter(profile, moving=True))
        self.map.__class__ = _ToldMap
        self.map.rule = rule  # type: ignore[attr-defined]
        if rule == TOLD_RULES[2]:  # every cylinder seen, exactly: nothing dropped to doubt
            self.map.dropped = None
        self.name = f"discs, told {rule} (privileged)"

    def reset(self, start: EpisodeStart) -> None:
        super().reset(start)
        if start.sim is None or start.sim.world is None:
            raise RuntimeError("ToldDiscsPlanner is privileged: run it with run_episode")
        m = self.map
        m.eyes = FastSimulator(start.sim.config)  # type: ignore[attr-defined]
        m.eyes.load(start.sim.world)  # type: ignore[attr-defined]
        m.time, m.seen = 0.0, np.zeros(0, int)  # type: ignore[attr-defined]

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        m = self.map
        m.pose = np.asarray(pose, float)  # type: ignore[attr-defined]
        now = m.eyes.visible_obstacles(m.pose, m.time)  # type: ignore[attr-defined]
        m.seen = np.union1d(m.seen, now).astype(int)  # type: ignore[attr-defined]
        return super().act(obs, pose)

    def observe(self, action: int, obs_next: np.ndarray | None) -> None:
        super().observe(action, obs_next)
        self.map.time += 1.0  # type: ignore[attr-defined]
