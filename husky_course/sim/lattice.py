"""The exact search over primitive sequences that both the oracle and the survival labels use.

Every primitive advances the same distance and ends at the heading it started with, and the
lateral offsets are evenly spaced (spacing ``h``). So from a start pose with yaw 0 the pose after
``k`` primitives is ``(x0 + k advance, y0 + k o_0 + J h, 0)`` for an integer ``J``: the reachable
states form a lattice in ``(k, J)``, at most ``k (n - 1) + 1`` wide at depth ``k`` instead of
``n**k`` sequences.

:func:`expand` walks that lattice forward once, checking every edge (a primitive from a state)
for contact with the simulator's rule (robot disc against obstacle discs and side walls, at the
primitive's recorded samples) and measuring its clearance. Two backward passes read it:

* :func:`survival` -- for each first primitive, the most steps (``<= horizon``) a sequence that
  starts with it stays collision-free: the labels the distilled planner learns;
* :func:`rank_plans` -- the oracle's lexicographic ranking of whole plans (safe steps, then the
  plan's smallest clearance binned to ``quantum``, then the least lateral motion).

**Space-time.** The robot cannot wait: every primitive takes one step of time, so every state at
depth ``k`` is reached at time ``t0 + k``, and the lattice in ``(k, J)`` is already a lattice in
space-time. On the moving course each edge of level ``k`` is checked against the cylinders where
they are at its samples' times ``t0 + k + s / (S - 1)``; nothing else changes.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .primitives import PrimitiveLibrary
from .world import World, sample_times


class LatticeError(ValueError):
    """A start pose or primitive library the lattice search cannot handle."""


@dataclass
class Lattice:
    """The reachable lattice from one start pose, expanded ``horizon`` steps.

    Attributes
    ----------
    pose : ndarray, shape (3,)
        The start pose.
    states : list of ndarray
        ``states[k]`` holds the lattice indices ``J`` reachable after ``k`` safe primitives
        (``horizon + 1`` entries; ``states[0] == [0]``).
    feasible : list of ndarray
        ``feasible[k][row, m]``: primitive ``m`` from state ``states[k][row]`` is collision-free.
    clear : list of ndarray
        The edge's clearance (m): smallest gap between the robot disc and any obstacle or wall
        along it (obstacles further than ``cap`` beyond contact are not measured).
    nxt : list of ndarray
        ``nxt[k][row, m]``: the row in ``states[k + 1]`` that the edge leads to (clipped where
        the edge is infeasible).
    """

    pose: np.ndarray
    states: list[np.ndarray]
    feasible: list[np.ndarray]
    clear: list[np.ndarray]
    nxt: list[np.ndarray]

    @property
    def horizon(self) -> int:
        """Number of expanded steps."""
        return len(self.feasible)


def lattice_step(library: PrimitiveLibrary) -> tuple[float, float]:
    """``(advance, h)``: the library's common advance and offset spacing, or :class:`LatticeError`."""
    local, offsets, n = library.local_paths, library.offsets, library.n
    h = float(offsets[1] - offsets[0]) if n > 1 else 1.0
    ends = local[:, -1]
    # np.allclose's tests written out (it costs more than the rest of a mapping planner's search step)
    evenly = n == 1 or bool(np.all(np.abs(np.diff(offsets) - h) <= 1e-9))
    level = bool(np.all(np.abs(ends[:, 2]) <= 1e-9))
    same = bool(np.all(np.abs(ends[:, 0] - ends[0, 0]) <= 1e-12 + 1e-5 * abs(ends[0, 0])))
    if not (evenly and level and same):
        raise LatticeError("the lattice search needs evenly spaced primitives that end at heading 0")
    return float(ends[0, 0]), h


#: ``check(X, Y, T) -> (hit, clear)``: for the sample positions of every edge of one lattice level,
#: ``X (n, S)`` (the same for every state) and ``Y (states, n, S)``, and the samples' times
#: ``T (S,)``, whether each edge touches something and its clearance (m), both ``(states, n)``
EdgeCheck = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


def disc_check(
    obstacles: np.ndarray, wall_y: float, robot_radius: float, cap: float, world: World | None = None
) -> EdgeCheck:
    """The simulator's own contact rule as an :data:`EdgeCheck`: the robot disc against obstacle
    discs ``(x, y, r)`` and two side walls at ``|y| = wall_y``.

    ``cap`` (m) bounds the clearance that is measured: obstacles further than ``cap`` beyond
    contact are skipped, so clearances above ``cap`` are lower bounds, which is all a ranking
    that caps clearance needs. With ``world`` (whose ``obstacles`` these are) its moving cylinders
    are placed where they are at each sample's time.
    """
    obs = np.asarray(obstacles, float).reshape(-1, 3)
    reach = robot_radius + obs[:, 2]
    movers = set() if world is None else set(world.moving.tolist())

    def check(X: np.ndarray, Y: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        absy = np.abs(Y)
        hit = (absy + robot_radius > wall_y).any(-1)
        c = wall_y - robot_radius - absy.max(-1)
        near = np.flatnonzero((obs[:, 0] + reach > X.min() - cap) & (obs[:, 0] - reach < X.max() + cap))
        for i in near:
            ox, oy, _ = obs[i]
            dx2 = (X - ox) ** 2
            cols = np.flatnonzero((dx2 < (reach[i] + cap) ** 2).any(0))
            if not cols.size:  # inside the x window but no sample within reach + cap
                continue
            if i in movers:  # where it is at each of these samples' times
                oy = world.obstacle_y(np.array([i]), T[None, cols])[0]  # type: ignore[union-attr]
            d2 = Y[..., cols] - oy  # squared and summed in place: the same numbers (a sum is exact either
            np.square(d2, out=d2)  # way round), fewer arrays made
            d2 += dx2[None][..., cols]
            hit |= (d2 < reach[i] ** 2).any(-1)
            c = np.minimum(c, np.sqrt(d2.min(-1)) - reach[i])
        return hit, c

    return check


def expand(
    world: World, library: PrimitiveLibrary, pose: np.ndarray, horizon: int, cap: float, t0: float = 0.0
) -> Lattice:
    """Expand the lattice from ``pose`` at time ``t0`` in ``world`` for ``horizon`` steps (the
    simulator's geometry, in space-time on the moving course)."""
    check = disc_check(world.obstacles, world.wall_y, world.config.robot_radius, cap, world)
    return expand_with(check, library, pose, horizon, t0)


def expand_with(
    check: EdgeCheck, library: PrimitiveLibrary, pose: np.ndarray, horizon: int, t0: float = 0.0,
    every: int = 1,
) -> Lattice:
    """Expand the lattice from ``pose`` at time ``t0`` for ``horizon`` steps, each edge judged by ``check``.

    The one search routine: the oracle and the survival labels judge edges with the simulator's
    geometry (:func:`disc_check`), the mapping planner with its map. ``check`` sees every
    ``every``-th sample of each edge (the mapping planners judge 21 of the 101).
    """
    local = library.local_paths

    def judge(k: int, x0: float, y0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        X = x0 + local[:, ::every, 0]  # (n, S)
        Y = y0[:, None, None] + local[None, :, ::every, 1]  # (nJ, n, S)
        return check(X, Y, sample_times(t0 + k, local.shape[1])[::every])

    return _expand(judge, library, pose, horizon)


#: ``check(x0, y0, t0) -> (hit, clear)``: every edge of one lattice level judged from its states'
#: start positions, ``x0`` (the same for every state) and ``y0 (states,)``, at time ``t0``; both
#: outputs ``(states, n)`` as an :data:`EdgeCheck`'s (for checks that know each primitive's path)
StartCheck = Callable[[float, np.ndarray, float], tuple[np.ndarray, np.ndarray]]


def expand_from_starts(
    check: StartCheck, library: PrimitiveLibrary, pose: np.ndarray, horizon: int, t0: float = 0.0
) -> Lattice:
    """:func:`expand_with` for a :data:`StartCheck` (the static mapping planners' path tables)."""
    return _expand(lambda k, x0, y0: check(x0, y0, t0 + k), library, pose, horizon)


def _expand(
    judge: Callable[[int, float, np.ndarray], tuple[np.ndarray, np.ndarray]], library: PrimitiveLibrary,
    pose: np.ndarray, horizon: int,
) -> Lattice:
    """The search's loop: ``judge(k, x0, y0)`` gives level ``k``'s edges' ``(hit, clear)``."""
    pose = np.asarray(pose, float)
    if abs(pose[2]) >= 1e-9:
        raise LatticeError(f"the lattice search needs a start heading of 0, got yaw {pose[2]} (slipping "
                           "wheels, --sensing realistic, leave headings off the library's: teachers and "
                           "labels that search the lattice from visited poses need ideal wheels)")
    adv, h = lattice_step(library)
    offsets, n = library.offsets, library.n
    states = [np.array([0])]
    feasible, clear, nxt = [], [], []
    for k in range(horizon):
        J = states[k]
        hit, c = judge(k, pose[0] + k * adv, pose[1] + k * offsets[0] + J * h)
        feasible.append(~hit)
        clear.append(c)
        targets = J[:, None] + np.arange(n)[None]
        # the states reached (sorted, distinct: np.unique) and each target's place among them
        # (np.searchsorted), read off a table over the few lateral indices a depth can hold
        reached = np.zeros(int(targets.max(initial=0)) + 2, bool)
        reached[targets[~hit]] = True
        states.append(np.flatnonzero(reached))
        before = np.cumsum(reached) - reached  # states below each index
        nxt.append(np.minimum(before[targets], max(len(states[k + 1]) - 1, 0)))  # before >= 0
    return Lattice(pose, states, feasible, clear, nxt)


def lattice_poses(lattice: Lattice, library: PrimitiveLibrary, k: int) -> np.ndarray:
    """Poses ``(len(states[k]), 3)`` of the lattice states at depth ``k``."""
    adv, h = lattice_step(library)
    J = lattice.states[k]
    x = np.full(len(J), lattice.pose[0] + k * adv)
    y = lattice.pose[1] + k * library.offsets[0] + J * h
    return np.stack([x, y, np.zeros(len(J))], axis=1)


def survival(lattice: Lattice) -> np.ndarray:
    """Steps (``0..horizon``) the best sequence starting with each primitive survives, ``(n,)`` int8."""
    steps = np.zeros(len(lattice.states[lattice.horizon]), np.int64)
    for k in range(lattice.horizon - 1, -1, -1):
        f, idx = lattice.feasible[k], lattice.nxt[k]
        edge = np.where(f, 1 + (steps[idx] if len(steps) else 0), 0)
        if k == 0:
            return edge[0].astype(np.int8)
        steps = edge.max(1)
    return np.zeros(lattice.feasible[0].shape[1] if lattice.feasible else 0, np.int8)


@dataclass
class Ranking:
    """The oracle's best plan from every lattice state (see :func:`rank_plans`).

    ``choice[k][row]`` is the best primitive from ``states[k][row]``, ``keys[k][row, m]`` the
    rank of each edge (higher is better), ``safe_steps`` the safe steps of the best plan from the
    start.
    """

    choice: list[np.ndarray]
    keys: list[np.ndarray]
    safe_steps: int


def rank_plans(lattice: Lattice, lateral_cost: np.ndarray, cap: float, quantum: float) -> Ranking:
    """Rank plans lexicographically: safe steps, bottleneck clearance (binned), least lateral cost.

    Parameters
    ----------
    lateral_cost : ndarray, shape (n,)
        Cost of each primitive (the oracle uses ``|offset|``).
    cap, quantum : float
        Clearance is capped at ``cap`` and binned to ``quantum`` metres before it is compared.
    """
    horizon = lattice.horizon
    n_end = len(lattice.states[horizon])
    steps = np.zeros(n_end)
    bott = np.full(n_end, np.floor(cap / quantum))
    cost = np.zeros(n_end)
    choice: list[np.ndarray] = [np.empty(0, int)] * horizon
    keys: list[np.ndarray] = [np.empty(0)] * horizon
    for k in range(horizon - 1, -1, -1):
        f, idx, clear = lattice.feasible[k], lattice.nxt[k], lattice.clear[k]
        cq = np.floor(np.minimum(np.maximum(clear, 0.0), cap) / quantum)  # np.clip, without its overhead
        if len(steps):
            s_e, b_e, c_e = 1 + steps[idx], np.minimum(cq, bott[idx]), lateral_cost[None] + cost[idx]
        else:
            s_e, b_e, c_e = np.ones_like(cq), cq, lateral_cost[None] + 0 * cq
        key = np.where(f, s_e * 1e6 + b_e * 1e3 - c_e, -1e9 + clear)
        best = np.argmax(key, axis=1)
        rows = np.arange(len(best))
        ok = f[rows, best]
        steps = np.where(ok, s_e[rows, best], 0.0)
        bott = np.where(ok, b_e[rows, best], 0.0)
        cost = np.where(ok, c_e[rows, best], 0.0)
        choice[k], keys[k] = best, key
    return Ranking(choice, keys, int(steps[0]) if len(steps) else 0)
