"""The oracle: exact planning on the true simulator (no learning), the ceiling of every planner.

It is *privileged*: :meth:`OraclePlanner.reset` keeps the simulator, and :meth:`OraclePlanner.act`
reads the true pose (the analysis references of :mod:`~husky_course.planners.reference` are too).
Every planner of the course's tables but this one sees depth images.
"""

from __future__ import annotations

import numpy as np

from ..config import OracleConfig
from ..sim.base import Simulator
from ..sim.lattice import LatticeError, Ranking, expand, rank_plans
from .base import EpisodeStart, Planner, PlannerError, check_observation, search_start


class OraclePlanner(Planner):
    """Exact planner on the true simulator: the best any policy can do.

    :meth:`reset` expands the reachable lattice of poses (:func:`husky_course.sim.lattice.expand`,
    every edge checked for contact with the simulator's rule, only obstacles near the step
    tested), then ranks plans (:func:`husky_course.sim.lattice.rank_plans`) lexicographically by

    1. the number of safe primitives (``crossable`` iff all ``horizon`` are possible);
    2. the plan's smallest clearance, capped at ``cap`` and binned to ``quantum`` metres;
    3. the least total lateral motion ``sum |offset|``.

    The chosen plan is then replayed with ``sim.apply``; an edge that the replay finds in contact
    (float drift of the lattice poses, in practice never) is forbidden and the plan recomputed, so
    the oracle never collides on a world it reports crossable.

    On the moving course it plans in space-time: the episode's step ``k`` is time ``k`` (it counts
    its own decisions), and every edge is checked against the cylinders where they are then.
    """

    name = "oracle"
    privileged = True

    def __init__(
        self, cap: float = OracleConfig.cap, quantum: float = OracleConfig.quantum, horizon: int | None = None
    ) -> None:
        super().__init__()
        self.cap, self.quantum, self.horizon = float(cap), float(quantum), horizon
        self.crossable = False
        self.plan: list[int] = []
        self.plan_poses: list[np.ndarray] = []
        self._sim: Simulator | None = None
        self._step = 0
        self._time = 0  #: the episode's step: the time the next primitive starts at
        self._action_scores: list[np.ndarray] = []

    def reset(self, start: EpisodeStart) -> None:
        super().reset(start)
        sim, pose = start.sim, start.pose
        if sim is None or pose is None:
            raise RuntimeError("the oracle is privileged: run it with run_episode, which gives it sim, pose")
        self._sim, self._step, self._time = sim, 0, 0
        horizon = self.horizon if self.horizon is not None else sim.config.max_primitives
        safe_steps = self._solve(np.asarray(pose, float), horizon)
        self.crossable = safe_steps == horizon

    def _solve(self, pose: np.ndarray, horizon: int) -> int:
        """Plan from ``pose`` at the current time; return the safe steps of the chosen plan."""
        sim = self._sim
        if sim is None or sim.world is None:
            raise RuntimeError("OraclePlanner.reset needs a simulator with a loaded world")
        try:
            lattice = expand(sim.world, sim.library, pose, horizon, self.cap, self._time)
        except LatticeError as exc:
            raise PlannerError(
                f"the oracle needs yaw 0 and evenly spaced primitives ending at heading 0 ({exc})"
            ) from exc
        lateral = np.abs(sim.library.offsets)
        for _ in range(50):  # replay the plan; forbid edges that the simulator finds in contact
            ranking = rank_plans(lattice, lateral, self.cap, self.quantum)
            bad = self._replay(pose, lattice.feasible, lattice.nxt, ranking)
            if bad is None:
                return ranking.safe_steps
            k, row, m = bad
            lattice.feasible[k][row, m] = False
        raise RuntimeError("oracle plan could not be verified by replay")  # pragma: no cover

    def _replay(
        self, pose: np.ndarray, feasible: list[np.ndarray], nxt: list[np.ndarray], ranking: Ranking
    ) -> tuple[int, int, int] | None:
        """Follow the plan with ``sim.apply``; return the first safe-by-plan edge in contact."""
        assert self._sim is not None
        self.plan, self.plan_poses, self._action_scores = [], [pose.copy()], []
        row = 0
        horizon = len(ranking.choice)
        for k in range(horizon):
            m = int(ranking.choice[k][row])
            key = ranking.keys[k][row]
            self._action_scores.append(np.clip(1.0 - np.floor(key / 1e6) / (horizon - k), 0.0, 1.0))
            self.plan.append(m)
            if not feasible[k][row, m]:
                return None  # the planned collision of a world that cannot be crossed
            result = self._sim.play(self.plan_poses[-1], m, self._time + k)  # the library's path: its plan
            if result.collided:
                return k, row, m
            self.plan_poses.append(result.pose)
            row = int(nxt[k][row, m])
        return None

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        check_observation(obs)
        if self._sim is None:
            raise RuntimeError("call reset(start) before act()")
        off_plan = self._step >= len(self.plan) or (
            pose is not None and not np.allclose(pose, self.plan_poses[self._step], atol=1e-9)
        )
        if off_plan:  # driven elsewhere, or past the horizon: plan again from here
            if pose is None:
                raise RuntimeError("the oracle needs the true pose to plan again")
            self._solve(search_start(pose, self._sim), self.horizon or self._sim.config.max_primitives)
            self._step = 0
        self.last_scores = self._action_scores[self._step]
        action = self.plan[self._step]
        self._step += 1
        self._time += 1
        return action
