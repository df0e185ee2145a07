"""Where is the ceiling of a planner that sees only what the camera has shown? (chapter 8)

:class:`SeenObstaclesPlanner` is an *analysis* tool, privileged on purpose: it replans at every
step with the oracle's exact lattice search, but over only some obstacles, with their true
geometry (perfect perception):

* ``memory=False``: the obstacles the current image renders
  (:meth:`~husky_course.sim.fast.FastSimulator.visible_obstacles`);
* ``memory=True``: every obstacle any image so far has rendered.

The side walls are always known. The gap between the two is what memory can buy; the gap between
``memory=True`` and the oracle (every obstacle, seen or not) is what no camera-based planner can.
"""

from __future__ import annotations

import numpy as np

from ..config import OracleConfig
from ..planners.base import EpisodeStart, Planner
from ..sim.fast import FastSimulator
from ..sim.lattice import disc_check, expand_with, rank_plans


class SeenObstaclesPlanner(Planner):
    """Exact replanning over the obstacles seen now (or ever): perfect perception, no more."""

    privileged = True  # it reads the true geometry of what it has seen: an analysis tool only

    def __init__(self, memory: bool, oracle: OracleConfig | None = None) -> None:
        super().__init__()
        self.memory = bool(memory)
        self.name = "seen so far (perfect perception)" if memory else "seen now (perfect perception)"
        self.oracle = oracle or OracleConfig()
        self._eyes: FastSimulator | None = None
        self._seen: set[int] = set()
        self._remaining = 0

    def reset(self, start: EpisodeStart) -> None:
        super().reset(start)
        if start.sim is None or start.sim.world is None:
            raise RuntimeError("SeenObstaclesPlanner is privileged: run it with run_episode")
        self._eyes = FastSimulator(start.sim.config)
        self._eyes.load(start.sim.world)
        self._seen, self._remaining = set(), start.max_primitives

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        assert self._eyes is not None and self._eyes.world is not None and pose is not None
        world = self._eyes.world
        now = set(self._eyes.visible_obstacles(pose).tolist())
        self._seen = (self._seen | now) if self.memory else now
        obstacles = world.obstacles[sorted(self._seen)] if self._seen else np.empty((0, 3))
        check = disc_check(obstacles, world.wall_y, world.config.robot_radius, self.oracle.cap)
        lattice = expand_with(check, self._eyes.library, np.asarray(pose, float), max(self._remaining, 1))
        lateral = np.abs(self._eyes.library.offsets)
        ranking = rank_plans(lattice, lateral, self.oracle.cap, self.oracle.quantum)
        keys = ranking.keys[0][0]
        self.last_scores = -(keys - keys.max()) / 1e6
        return int(ranking.choice[0][0])

    def observe(self, action: int, obs_next: np.ndarray | None) -> None:
        self._remaining -= 1
