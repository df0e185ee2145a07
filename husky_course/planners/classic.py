"""The non-learned planners: the random policy and the depth-scan heuristic (with optional memory).

Both see only the depth image (and, for the heuristic's memory, the primitives it applied).
"""

from __future__ import annotations

import numpy as np

from ..config import HeuristicConfig, SimConfig
from ..sim.primitives import primitive_offsets, s_curve
from .base import EpisodeStart, Planner, PlannerError, check_observation
from .perception import DepthScan


class RandomPlanner(Planner):
    """Uniform over the library: the data-collection policy.

    The generator is reseeded at every :meth:`reset` from ``(seed, episode key)`` (the key is an
    opaque hash of the world, :func:`~husky_course.planners.base.episode_key`), so an episode
    depends only on the planner's seed and the world, whatever the evaluation order.
    """

    name = "random"

    def __init__(self, seed: int = 0, n: int = SimConfig().primitives.n) -> None:
        super().__init__()
        self.seed, self.n = int(seed), int(n)
        self.rng = np.random.default_rng([self.seed, 0])

    def reset(self, start: EpisodeStart) -> None:
        super().reset(start)
        self.n = start.library.n
        self.rng = np.random.default_rng([self.seed, start.key])

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        check_observation(obs)
        self.last_scores = np.full(self.n, 1.0 / self.n)
        return int(self.rng.integers(self.n))


class HeuristicPlanner(Planner):
    """Non-learned: pick the primitive whose swept body stays farthest from what the camera sees.

    The depth image is turned into a laser scan (:class:`~husky_course.planners.perception.DepthScan`):
    one robot-frame point per column that sees a vertical surface within ``far``. The *clearance*
    of a path is the smallest distance from these points to it minus the robot radius, capped at
    ``cap``.

    With ``depth = 2`` the planner also looks one primitive further: a first primitive is worth
    ``min(its clearance, best clearance of any second primitive after it)``, so it does not drive
    into a gap that closes just beyond one metre. With ``memory`` it also keeps the points seen
    before (moved by the primitives it applied, which it knows), so obstacles that have left the
    field of view beside the robot still count. Score (lower is better)::

        -worth + lateral_weight * |offset|

    so the robot keeps up to ``cap`` metres from what it sees and otherwise moves sideways as
    little as possible (without the penalty, ties at ``cap`` send it to the library's extremes).
    """

    name = "heuristic"

    def __init__(
        self,
        config: SimConfig | None = None,
        cap: float = HeuristicConfig.cap,
        lateral_weight: float = HeuristicConfig.lateral_weight,
        depth: int = HeuristicConfig.depth,
        memory: bool = False,
        path_samples: int = HeuristicConfig.path_samples,
    ) -> None:
        super().__init__()
        if depth not in (1, 2):
            raise PlannerError(f"heuristic depth must be 1 or 2, got {depth!r}")
        cfg = config or SimConfig()
        self.config, self.cap, self.lateral_weight, self.depth = cfg, float(cap), float(lateral_weight), depth
        self.radius = cfg.world.robot_radius
        prim = cfg.primitives
        self.scan = DepthScan(cfg)  #: image -> robot-frame points of the surfaces it sees
        # robot-frame points along each primitive and along every two-primitive sequence
        self.offsets = primitive_offsets(prim)
        s = np.linspace(0.0, 1.0, path_samples)
        self.first = s_curve(self.offsets, prim.advance, s)[..., :2]  # (n, S, 2)
        self.second = (
            self.first[None] + np.stack([np.full(prim.n, prim.advance), self.offsets], -1)[:, None, None, :]
        )  # (n, n, S, 2)
        self.reach = depth * prim.advance + self.radius + self.cap
        self.advance, self.memory = prim.advance, bool(memory)
        self._points = np.empty((0, 2))

    def reset(self, start: EpisodeStart) -> None:
        super().reset(start)
        self._points = np.empty((0, 2))

    def _clear(self, paths: np.ndarray, pts: np.ndarray) -> np.ndarray:
        if not len(pts):
            return np.full(paths.shape[:-2], self.cap)
        d2 = ((paths[..., :, None, :] - pts) ** 2).sum(-1).min(axis=(-1, -2))
        return np.minimum(np.sqrt(d2) - self.radius, self.cap)

    def worth(self, obs: np.ndarray, remembered: np.ndarray | None = None) -> np.ndarray:
        """Capped clearance (m) of every primitive, looking ``depth`` primitives ahead."""
        pts = self.scan(obs) if remembered is None else np.concatenate([self.scan(obs), remembered])
        pts = pts[pts[:, 0] < self.reach]
        if self.memory:
            self._points = pts
        worth = self._clear(self.first, pts)
        if self.depth == 2:
            worth = np.minimum(worth, self._clear(self.second, pts).max(axis=1))
        return worth

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        worth = self.worth(obs, self._points if self.memory else None)
        self.last_scores = -worth + self.lateral_weight * np.abs(self.offsets)
        return int(np.argmin(self.last_scores))

    def observe(self, action: int, obs_next: np.ndarray | None) -> None:
        """With ``memory``, move the points seen so far into the frame after ``action``."""
        moved = self._points - np.array([self.advance, self.offsets[action]])
        self._points = moved[moved[:, 0] > -(self.radius + self.cap)]
