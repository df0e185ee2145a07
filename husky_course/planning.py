"""Planners: choose the next motion primitive from the onboard depth image.

Every planner follows one protocol, used by :func:`husky_course.evaluation.run_episode`:
``reset(sim, pose)`` at the start of an episode, then per step ``act(obs, pose) -> index`` and
``observe(action, next_obs)`` (``next_obs`` is ``None`` after a collision). ``act`` leaves the
per-primitive scores it used in ``last_scores`` (shape ``(n,)``, *lower is better*) for plots.

Only :class:`OraclePlanner` may use the simulator or the true pose; the others see depth images.
The learned planners (``"lookahead"``, ``"rnn"``) live in ``husky_course.learned_planners`` and are
imported lazily by :func:`make_planner`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .camera import denormalize_depth, pixel_tangents
from .config import SimConfig
from .sim import Simulator

PLANNERS = ("random", "heuristic", "lookahead", "rnn", "distilled", "oracle")
LEARNED_PLANNERS = ("lookahead", "rnn", "distilled")


class PlannerError(ValueError):
    """An unknown planner, a bad planner argument, or a planner that cannot be built."""


def check_observation(obs: object, size: int = 50) -> np.ndarray:
    """Return ``obs`` as a float32 ``(size, size)`` depth image in [0, 1], or raise ``ValueError``."""
    if not isinstance(obs, np.ndarray):
        raise ValueError(f"observation must be a numpy array, got {type(obs).__name__}")
    if obs.shape != (size, size):
        raise ValueError(f"observation must have shape ({size}, {size}), got {obs.shape}")
    if not np.issubdtype(obs.dtype, np.floating):
        raise ValueError(f"observation must be a float depth image (float32), got dtype {obs.dtype}")
    if not np.isfinite(obs).all():
        raise ValueError("observation contains NaN or inf values")
    if obs.min() < 0.0 or obs.max() > 1.0:
        raise ValueError(f"observation must be normalised depth in [0, 1], got [{obs.min()}, {obs.max()}]")
    return obs.astype(np.float32, copy=False)


def check_look_ahead(k: object) -> int:
    """Return the look-ahead ``k`` as an int >= 0, or raise :class:`PlannerError`."""
    if isinstance(k, (bool, np.bool_)) or not isinstance(k, (int, np.integer)) or k < 0:
        raise PlannerError(f"look_ahead must be a non-negative integer, got {k!r}")
    return int(k)


class Planner:
    """Base class. Subclasses implement :meth:`act` and may override :meth:`reset`/:meth:`observe`."""

    name: str = "base"

    def __init__(self) -> None:
        self.last_scores: np.ndarray | None = None

    def reset(self, sim: Simulator, pose: np.ndarray) -> None:
        """Start an episode in ``sim``'s loaded world at ``pose`` (only the oracle may keep ``sim``)."""
        self.last_scores = None

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        """The primitive index to apply, given the depth image ``obs`` (and, for the oracle, ``pose``)."""
        raise NotImplementedError

    def observe(self, action: int, obs_next: np.ndarray | None) -> None:
        """Hook called after each step with the next image (``None`` after a collision)."""


class RandomPlanner(Planner):
    """Uniform over the library: the data-collection policy.

    The generator is reseeded at every :meth:`reset` from ``(seed, world seed)``, so an episode
    depends only on the planner's seed and the world, whatever the evaluation order.
    """

    name = "random"

    def __init__(self, seed: int = 0, n: int = 25) -> None:
        super().__init__()
        self.seed, self.n = int(seed), int(n)
        self.rng = np.random.default_rng([self.seed, 0])

    def reset(self, sim: Simulator, pose: np.ndarray) -> None:
        super().reset(sim, pose)
        self.n = sim.library.n
        self.rng = np.random.default_rng([self.seed, sim.world.seed if sim.world is not None else 0])

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        check_observation(obs)
        self.last_scores = np.full(self.n, 1.0 / self.n)
        return int(self.rng.integers(self.n))


class HeuristicPlanner(Planner):
    """Non-learned: pick the primitive whose swept body stays farthest from what the camera sees.

    The depth image is turned into a laser scan: obstacles and walls are vertical, so in the rows
    that can see neither the ground nor an obstacle's top within ``far``, each column's depth is
    the distance to the nearest vertical surface, i.e. one point ``(mount_forward + D, D u_j)`` in
    the robot frame per column (columns at ``far`` see nothing). The *clearance* of a path is the
    smallest distance from these points to it minus the robot radius, capped at ``cap``.

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
        cap: float = 0.35,
        lateral_weight: float = 0.1,
        depth: int = 2,
        memory: bool = False,
        path_samples: int = 11,
    ) -> None:
        super().__init__()
        if depth not in (1, 2):
            raise PlannerError(f"heuristic depth must be 1 or 2, got {depth!r}")
        cfg = config or SimConfig()
        self.config, self.cap, self.lateral_weight, self.depth = cfg, float(cap), float(lateral_weight), depth
        self.radius = cfg.world.robot_radius
        cam, prim = cfg.camera, cfg.primitives
        self.u, v = pixel_tangents(cam)
        height = cfg.world.obstacle_height - cam.mount_height
        with np.errstate(divide="ignore"):
            ground = np.where(v < 0, cam.mount_height / -v, np.inf)
            top = np.where(v > 0, height / v, np.inf)
        rows = np.flatnonzero((ground >= cam.far) & (top >= cam.far))
        self.rows = rows if rows.size else np.array([cam.size // 2])
        # robot-frame points along each primitive and along every two-primitive sequence
        s = np.linspace(0.0, 1.0, path_samples)
        self.offsets = np.linspace(-prim.lateral_spread, prim.lateral_spread, prim.n)
        y = self.offsets[:, None] * (1.0 - np.cos(np.pi * s))[None] / 2.0
        self.first = np.stack([np.broadcast_to(prim.advance * s, y.shape), y], -1)  # (n, S, 2)
        self.second = (
            self.first[None] + np.stack([np.full(prim.n, prim.advance), self.offsets], -1)[:, None, None, :]
        )  # (n, n, S, 2)
        self.reach = depth * prim.advance + self.radius + self.cap
        self.advance, self.memory = prim.advance, bool(memory)
        self._points = np.empty((0, 2))

    def reset(self, sim: Simulator, pose: np.ndarray) -> None:
        super().reset(sim, pose)
        self._points = np.empty((0, 2))

    def scan(self, obs: np.ndarray) -> np.ndarray:
        """Robot-frame points ``(m, 2)`` of the vertical surfaces that ``obs`` sees within ``far``."""
        cam = self.config.camera
        col = np.median(check_observation(obs, cam.size)[self.rows], axis=0)
        seen = col < 0.999
        d = denormalize_depth(col[seen], cam)
        return np.stack([cam.mount_forward + d, d * self.u[seen]], axis=1)

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


class OraclePlanner(Planner):
    """Exact planner on the true simulator (no learning): the best any policy can do.

    With yaw 0 at the start and primitives that end at their initial heading after ``advance``
    metres, the pose after ``k`` primitives is ``(x0 + k advance, y0 + k o_0 + J h, 0)`` with
    ``h`` the offset spacing and ``J`` an integer, so the state space is a lattice in ``(k, J)``.
    :meth:`reset` expands the reachable lattice forward, checking every edge (primitive from a
    state) for contact with the same rule as the simulator (robot disc vs. obstacle discs and
    walls, at the recorded samples; only obstacles near the step are tested), then runs a
    backward dynamic programme. Plans are ranked lexicographically by

    1. the number of safe primitives (``crossable`` iff all ``horizon`` are possible);
    2. the plan's smallest clearance, capped at ``cap`` and binned to ``quantum`` metres;
    3. the least total lateral motion ``sum |offset|``.

    The chosen plan is then replayed with ``sim.apply``; an edge that the replay finds in contact
    (float drift of the lattice poses, in practice never) is forbidden and the plan recomputed, so
    the oracle never collides on a world it reports crossable.
    """

    name = "oracle"

    def __init__(self, cap: float = 0.3, quantum: float = 0.02, horizon: int | None = None) -> None:
        super().__init__()
        self.cap, self.quantum, self.horizon = float(cap), float(quantum), horizon
        self.crossable = False
        self.plan: list[int] = []
        self.plan_poses: list[np.ndarray] = []
        self._sim: Simulator | None = None
        self._step = 0
        self._action_scores: list[np.ndarray] = []

    def reset(self, sim: Simulator, pose: np.ndarray) -> None:
        super().reset(sim, pose)
        self._sim, self._step = sim, 0
        horizon = self.horizon if self.horizon is not None else sim.config.max_primitives
        self._solve(np.asarray(pose, float), horizon)
        self.crossable = self._safe_steps == horizon

    def _solve(self, pose: np.ndarray, horizon: int) -> None:
        sim = self._sim
        if sim is None or sim.world is None:
            raise RuntimeError("OraclePlanner.reset(sim, pose) must be called with a loaded world")
        lib, world = sim.library, sim.world
        local, offsets = lib.local_paths, lib.offsets
        n = lib.n
        h = float(offsets[1] - offsets[0]) if n > 1 else 1.0
        ends = local[:, -1]
        lattice = n == 1 or np.allclose(np.diff(offsets), h, rtol=0, atol=1e-9)
        if not (
            lattice
            and abs(pose[2]) < 1e-9
            and np.allclose(ends[:, 2], 0, atol=1e-9)
            and np.allclose(ends[:, 0], ends[0, 0], atol=1e-12)
        ):
            raise PlannerError("the oracle needs yaw 0 and evenly spaced primitives ending at heading 0")
        adv, radius, wall = float(ends[0, 0]), world.config.robot_radius, world.wall_y
        obs = np.asarray(world.obstacles, float)
        reach = radius + obs[:, 2]
        states = [np.array([0])]
        feasible, clear, nxt = [], [], []
        for k in range(horizon):
            J = states[k]
            y0 = pose[1] + k * offsets[0] + J * h
            X = pose[0] + k * adv + local[:, :, 0]  # (n, S)
            Y = y0[:, None, None] + local[None, :, :, 1]  # (nJ, n, S)
            absy = np.abs(Y)
            hit = (absy + radius > wall).any(-1)
            c = wall - radius - absy.max(-1)
            near = np.flatnonzero(
                (obs[:, 0] + reach > X.min() - self.cap) & (obs[:, 0] - reach < X.max() + self.cap)
            )
            for i in near:
                ox, oy, _ = obs[i]
                dx2 = (X - ox) ** 2
                cols = np.flatnonzero((dx2 < (reach[i] + self.cap) ** 2).any(0))
                d2 = dx2[None][..., cols] + (Y[..., cols] - oy) ** 2
                hit |= (d2 < reach[i] ** 2).any(-1)
                c = np.minimum(c, np.sqrt(d2.min(-1)) - reach[i])
            feasible.append(~hit)
            clear.append(c)
            targets = J[:, None] + np.arange(n)[None]
            states.append(np.unique(targets[~hit]) if (~hit).any() else np.array([], int))
            nxt.append(np.searchsorted(states[k + 1], targets).clip(0, max(len(states[k + 1]) - 1, 0)))
        self._lattice = (states, feasible, clear, nxt)
        for _ in range(50):  # replay the plan; forbid edges that the simulator finds in contact
            self._backward(horizon, np.abs(offsets))
            bad = self._replay(pose)
            if bad is None:
                return
            k, row, m = bad
            feasible[k][row, m] = False
        raise RuntimeError("oracle plan could not be verified by replay")  # pragma: no cover

    def _backward(self, horizon: int, cost_m: np.ndarray) -> None:
        states, feasible, clear, nxt = self._lattice
        steps = np.zeros(len(states[horizon]))
        bott = np.full(len(states[horizon]), np.floor(self.cap / self.quantum))
        cost = np.zeros(len(states[horizon]))
        choice: list[np.ndarray] = [np.empty(0, int)] * horizon
        keys: list[np.ndarray] = [np.empty(0)] * horizon
        for k in range(horizon - 1, -1, -1):
            f, idx = feasible[k], nxt[k]
            cq = np.floor(np.clip(clear[k], 0.0, self.cap) / self.quantum)
            if len(steps):
                s_e, b_e, c_e = 1 + steps[idx], np.minimum(cq, bott[idx]), cost_m[None] + cost[idx]
            else:
                s_e, b_e, c_e = np.ones_like(cq), cq, cost_m[None] + 0 * cq
            key = np.where(f, s_e * 1e6 + b_e * 1e3 - c_e, -1e9 + clear[k])
            best = np.argmax(key, axis=1)
            rows = np.arange(len(best))
            ok = f[rows, best]
            steps = np.where(ok, s_e[rows, best], 0.0)
            bott = np.where(ok, b_e[rows, best], 0.0)
            cost = np.where(ok, c_e[rows, best], 0.0)
            choice[k], keys[k] = best, key
        self._choice, self._keys, self._safe_steps = choice, keys, int(steps[0]) if len(steps) else 0

    def _replay(self, pose: np.ndarray) -> tuple[int, int, int] | None:
        """Follow the plan with ``sim.apply``; return the first safe-by-plan edge in contact."""
        assert self._sim is not None
        states, feasible, _, nxt = self._lattice
        self.plan, self.plan_poses, self._action_scores = [], [pose.copy()], []
        row = 0
        for k in range(len(self._choice)):
            m = int(self._choice[k][row])
            key = self._keys[k][row]
            remaining = len(self._choice) - k
            self._action_scores.append(np.clip(1.0 - np.floor(key / 1e6) / remaining, 0.0, 1.0))
            self.plan.append(m)
            if not feasible[k][row, m]:
                return None  # the planned collision of a world that cannot be crossed
            result = self._sim.apply(self.plan_poses[-1], m)
            if result.collided:
                return k, row, m
            self.plan_poses.append(result.pose)
            row = int(nxt[k][row, m])
        return None

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        check_observation(obs)
        if self._sim is None:
            raise RuntimeError("call reset(sim, pose) before act()")
        off_plan = self._step >= len(self.plan) or (
            pose is not None and not np.allclose(pose, self.plan_poses[self._step], atol=1e-9)
        )
        if off_plan:  # driven elsewhere, or past the horizon: plan again from here
            if pose is None:
                raise RuntimeError("the oracle needs the true pose to plan again")
            self._solve(np.asarray(pose, float), self.horizon or self._sim.config.max_primitives)
            self._step = 0
        self.last_scores = self._action_scores[self._step]
        action = self.plan[self._step]
        self._step += 1
        return action


def make_planner(name: str, **kwargs: Any) -> Planner:
    """Build the planner ``name`` (one of :data:`PLANNERS`) with keyword arguments ``kwargs``.

    The learned planners are imported lazily from ``husky_course.learned_planners``; they need that
    module and trained checkpoints, and :class:`PlannerError` says so when either is missing.
    """
    if name in LEARNED_PLANNERS:
        try:
            from .learned_planners import make_learned_planner
        except ImportError as exc:
            raise PlannerError(
                f"planner {name!r} is learned: it needs husky_course.learned_planners and trained "
                f"checkpoints, which are not available ({exc})"
            ) from exc
        return make_learned_planner(name, **kwargs)
    classes = {"random": RandomPlanner, "heuristic": HeuristicPlanner, "oracle": OraclePlanner}
    if name not in classes:
        raise PlannerError(f"unknown planner {name!r}: choose one of {', '.join(PLANNERS)}")
    try:
        return classes[name](**kwargs)
    except TypeError as exc:
        raise PlannerError(f"bad arguments for planner {name!r}: {exc}") from exc
