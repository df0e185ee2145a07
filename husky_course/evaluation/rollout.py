"""One episode, decision by decision: what :func:`~husky_course.evaluation.episodes.run_episode` plays,
open to a look at every step.

:class:`Rollout` runs a planner in one world as the course's evaluation does (step ``k`` is time
``k``: the ``k``-th image is rendered at time ``k`` and the ``k``-th primitive is played back from
time ``k``, which is what makes moving cylinders move). Iterating it yields a :class:`Decision`
after the planner has chosen and before the primitive is played: an experiment reads the planner's
state at the moment it chose (its map, its tracks), or perturbs it and puts it back. Breaking out of
the loop ends the episode there. The planner is reset when the rollout is made, so an experiment may
also prepare its memory before the first decision.

:func:`~husky_course.evaluation.episodes.run_episode` and the benchmarks that follow a planner step by
step (``benchmarks/exp_moving_*.py``) share it, so that they all play the same episode.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from ..checks import check_int
from ..config import SimConfig
from ..planners.base import Planner, episode_start
from ..sim.base import Simulator, StepResult


@dataclass
class Decision:
    """One decision of a :class:`Rollout`.

    Attributes
    ----------
    step : int
        Its place in the episode (0 first), also the time at which ``obs`` was rendered.
    pose : ndarray, shape (3,)
        The robot's true pose when it chose (a planner sees it only if it is privileged).
    obs : ndarray
        The depth image it chose from.
    action : int
        The primitive it chose.
    seconds : float
        Time spent in ``planner.act``.
    scores : ndarray or None
        A copy of the planner's ``last_scores`` after it chose.
    result : StepResult or None
        The primitive played back: ``None`` while the decision is being looked at, filled when the
        rollout moves on.
    """

    step: int
    pose: np.ndarray
    obs: np.ndarray
    action: int
    seconds: float
    scores: np.ndarray | None
    result: StepResult | None = None


class Rollout:
    """``planner`` in world ``world_seed`` until a collision or ``max_primitives`` primitives, one
    :class:`Decision` at a time (module docstring).

    Making it loads the world (:attr:`world`, starting at :attr:`start`) and resets the planner
    (:attr:`reset_seconds`: the time that took; the oracle plans there). It plays its episode once.
    """

    def __init__(self, planner: Planner, sim: Simulator, world_seed: int,
                 max_primitives: int = SimConfig.max_primitives) -> None:
        self.max_primitives = check_int(max_primitives, "max_primitives", 1, 10**6)
        self.planner, self.sim, self.world_seed = planner, sim, int(world_seed)
        self.world = sim.load(self.world_seed)
        self.start = self.world.start.copy()
        t0 = time.perf_counter()
        planner.reset(episode_start(planner, sim, self.world_seed, self.start, self.max_primitives))
        self.reset_seconds = time.perf_counter() - t0
        self._played = False

    def __iter__(self) -> Iterator[Decision]:
        if self._played:
            raise RuntimeError("a Rollout plays its episode once: make a new one to play it again")
        self._played = True
        planner, sim, pose = self.planner, self.sim, self.start
        obs = sim.depth(pose[None], 0.0)[0]
        for step in range(self.max_primitives):
            t0 = time.perf_counter()
            action = planner.act(obs, pose.copy() if planner.privileged else None)
            seconds = time.perf_counter() - t0
            scores = None if planner.last_scores is None else np.array(planner.last_scores)
            decision = Decision(step, pose, obs, sim.library.check_index(action), seconds, scores)
            yield decision
            result = decision.result = sim.apply(pose, decision.action, step)
            pose = result.pose
            obs = None if result.collided else sim.depth(pose[None], step + 1)[0]
            planner.observe(decision.action, obs)
            if result.collided:
                return
