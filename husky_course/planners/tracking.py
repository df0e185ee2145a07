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
  and a point seen again is replaced by the new scan's.
* **Space-time search.** The oracle's lattice search over the map: a standing point is judged on
  the mapping planner's clearance grid, a walking point exactly, where it is at each sample's time
  (level ``k`` of the lattice is the step from ``k`` to ``k + 1`` steps after now).

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

from ..config import ArrivalsConfig, MappingConfig, SimConfig
from ..sim.lattice import EdgeCheck
from .mapping import MappingPlanner
from .motion import WalkingMap


class TrackingPlanner(MappingPlanner):
    """:class:`MappingPlanner` whose map points carry estimated lateral velocities (module docstring)."""

    name = "tracking"  #: the mapping planner, with motion

    def __init__(self, config: SimConfig | None = None, horizon: int = MappingConfig.horizon,
                 arrivals: bool = True, doubt_steps: float = ArrivalsConfig.doubt_steps,
                 doubt_hard: bool = ArrivalsConfig.doubt_hard, **kwargs: float) -> None:
        super().__init__(config, horizon, **kwargs)
        self.map = WalkingMap(self.config, self.map.forget_behind, arrivals)  # type: ignore[assignment]
        self.doubt_steps, self.doubt_hard = float(doubt_steps), bool(doubt_hard)
        self.max_walk = float(getattr(self.config.world, "speed_range", (0.0, 0.0))[1])

    @property
    def velocity(self) -> np.ndarray:
        """Each map point's estimated lateral velocity (m per step)."""
        return self.map.velocity

    @property
    def doubtful(self) -> np.ndarray:
        """Per map point: a first sight the arrivals rule left standing (it may yet walk either way)."""
        return self.map.fresh & (self.map.velocity == 0)

    def _edge_check(self, horizon: int) -> EdgeCheck:
        """Standing points on the mapping planner's clearance grid; each walking point exactly, where
        it is at every sample's time. With ``doubt_steps``, each doubtful point (:attr:`doubtful`)
        also stands for the band it could have walked to by a sample's time (up to ``doubt_steps``
        steps, at the course's fastest walk): the band counts in the clearance a plan is ranked by,
        and with ``doubt_hard`` an edge that enters it is infeasible."""
        walking = self.velocity != 0
        reach = self.radius + self.margin + self.cap
        grid = self._grid(self.points[~walking], horizon)
        movers, speeds = self.points[walking], self.velocity[walking]
        doubt = self.points[self.doubtful] if self.doubt_steps > 0 and self.max_walk > 0 else np.empty((0, 3))

        def check(x: np.ndarray, y: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            gap = grid(x, y)
            near = np.flatnonzero((movers[:, 0] > x.min() - reach) & (movers[:, 0] < x.max() + reach))
            for (px, py, r), v in zip(movers[near], speeds[near], strict=True):  # where it is at each sample
                np.minimum(gap, np.hypot(x - px, y - (py + v * t)) - r, out=gap)
            clear = gap.min(-1) - self.radius
            near = np.flatnonzero((doubt[:, 0] > x.min() - reach) & (doubt[:, 0] < x.max() + reach))
            if not len(near):
                return clear < self.margin, clear - self.margin
            band = self.max_walk * np.minimum(t, self.doubt_steps)
            for px, py, r in doubt[near]:  # the nearest place it could be, standing or walking
                np.minimum(gap, np.hypot(x - px, np.maximum(0.0, np.abs(y - py) - band)) - r, out=gap)
            doubted = gap.min(-1) - self.radius
            return (doubted if self.doubt_hard else clear) < self.margin, doubted - self.margin

        return check
