"""Evaluate a planner on held-out worlds: success rate, primitives survived, exact error bars.

Evaluation worlds have seeds at or above :data:`~husky_course.config.EVAL_SEED_BASE` (``2**31``);
data collection only produces seeds below it and refuses any other
(:func:`husky_course.data.collect.world_seed_for`), so no training world is ever an evaluation world.
Evaluation set ``s`` of size ``n`` is the worlds ``EVAL_SEED_BASE + s * 1_000_000 + [0, n)``.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..checks import check_int, is_int
from ..config import EVAL_SEED_BASE, SimConfig
from ..engines import ENGINE, map_tasks, resolve_engine
from ..planners.base import Planner
from ..sim.backends import check_backend, make_simulator
from ..sim.base import Simulator
from ..sim.fast import FastSimulator
from .rollout import Rollout
from .statistics import clopper_pearson

EVAL_SET_STRIDE = 1_000_000
#: Evaluation set seeds are ``0 .. EVAL_SET_MAX`` (so every evaluation world seed is below 2**32).
EVAL_SET_MAX = EVAL_SEED_BASE // EVAL_SET_STRIDE - 1


def eval_world_seeds(n: int, seed: int = 0) -> np.ndarray:
    """World seeds ``(n,)`` int64 of evaluation set ``seed``: ``EVAL_SEED_BASE + seed * 10**6 + [0, n)``."""
    n = check_int(n, "the number of evaluation worlds", 1, EVAL_SET_STRIDE)
    seed = check_int(seed, "the evaluation seed", 0, EVAL_SET_MAX)
    return EVAL_SEED_BASE + seed * EVAL_SET_STRIDE + np.arange(n, dtype=np.int64)


def is_eval_seed(world_seed: object) -> bool:
    """Whether ``world_seed`` is reserved for evaluation (an integer >= ``EVAL_SEED_BASE``)."""
    if not is_int(world_seed):
        return False
    return int(world_seed) >= EVAL_SEED_BASE


@dataclass
class Episode:
    """One planner run in one world.

    Attributes
    ----------
    actions : list of int
        Primitives applied, the colliding one included.
    poses : ndarray, shape (len(actions) + 1, 3)
        Pose before each primitive, then the final pose (last safe pose before contact if collided).
    path : ndarray, shape (m, 3)
        Every recorded pose played back, concatenated.
    n_prims : int
        ``len(actions)``, the colliding primitive counted (the dataset's convention).
    success : bool
        ``max_primitives`` primitives applied without collision (10 cross the course).
    decision_times : list of float
        Seconds spent in ``planner.act`` per step.
    reset_time : float
        Seconds spent in ``planner.reset`` (where the oracle plans).
    observations, scores : list
        Filled only by ``run_episode(..., record=True)``.
    """

    world_seed: int
    actions: list[int]
    poses: np.ndarray
    path: np.ndarray
    collided: bool
    n_prims: int
    success: bool
    decision_times: list[float]
    reset_time: float = 0.0
    observations: list[np.ndarray] = field(default_factory=list)  #: with ``record=True``: image per step
    scores: list[np.ndarray | None] = field(default_factory=list)  #: with ``record=True``: planner scores


def run_episode(
    planner: Planner, sim: Simulator, world_seed: int, max_primitives: int = SimConfig.max_primitives,
    record: bool = False,
) -> Episode:
    """Run ``planner`` in world ``world_seed`` until a collision or ``max_primitives`` primitives.

    Step ``k`` is time ``k``: the ``k``-th image is rendered at time ``k`` and the ``k``-th
    primitive is played back from time ``k`` (what makes moving cylinders move).

    With ``record`` the episode also keeps every observation and the planner's ``last_scores``
    (for step-by-step figures and widgets).
    """
    rollout = Rollout(planner, sim, world_seed, max_primitives)
    made = list(rollout)  # every decision, each with the primitive it played back
    results = [d.result for d in made if d.result is not None]
    return Episode(
        world_seed=int(world_seed),
        actions=[d.action for d in made],
        poses=np.asarray([rollout.start, *(r.pose for r in results)]),
        path=np.concatenate([rollout.start[None], *(r.path for r in results)]),
        collided=bool(results[-1].collided),
        n_prims=len(made),
        success=not results[-1].collided and len(made) == rollout.max_primitives,
        decision_times=[d.seconds for d in made],
        reset_time=rollout.reset_seconds,
        observations=[d.obs for d in made] if record else [],
        scores=[d.scores for d in made] if record else [],
    )


@dataclass
class EvalResult:
    """Summary of :func:`evaluate` (``episodes`` is kept for plots but left out of :meth:`to_json`).

    Attributes
    ----------
    success_rate, collision_rate : float
        Fractions of worlds crossed (``max_primitives`` safe primitives) and ended by a collision.
    mean_prims : float
        Mean primitives applied per world, the colliding one counted (random policy: about 4.4).
    collision_rate_upper95 : float
        Exact one-sided 95% upper bound on the collision probability (Clopper-Pearson).
    success_ci95 : (float, float)
        Exact two-sided 95% interval on the success probability.
    ms_per_decision, ms_per_reset : float
        Mean wall time of ``planner.act`` and of ``planner.reset`` (the oracle plans in ``reset``).
    crossable_rate : float or None
        Fraction of worlds the planner reported crossable (the oracle), else ``None``.
    """

    planner: str
    worlds: int
    seed: int
    max_primitives: int
    success_rate: float
    mean_prims: float
    collision_rate: float
    collision_rate_upper95: float
    success_ci95: tuple[float, float]
    ms_per_decision: float
    ms_per_reset: float
    crossable_rate: float | None = None
    episodes: list[Episode] = field(default_factory=list, repr=False)

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict of every field but ``episodes`` (``crossable_rate`` only when known)."""
        out = {
            "planner": self.planner,
            "worlds": self.worlds,
            "seed": self.seed,
            "max_primitives": self.max_primitives,
            "success_rate": self.success_rate,
            "mean_prims": self.mean_prims,
            "collision_rate": self.collision_rate,
            "collision_rate_upper95": self.collision_rate_upper95,
            "success_ci95": list(self.success_ci95),
            "ms_per_decision": self.ms_per_decision,
            "ms_per_reset": self.ms_per_reset,
        }
        if self.crossable_rate is not None:
            out["crossable_rate"] = self.crossable_rate
        return out


def _backend_of(sim: Simulator) -> str:
    """The backend name that rebuilds ``sim`` in a worker (only the course's own two can be)."""
    if type(sim) is FastSimulator:
        return "fast"
    if type(sim).__name__ == "PyBulletSimulator":
        return "pybullet"
    raise ValueError(
        f"a {type(sim).__name__} cannot be rebuilt in a worker: evaluate it with workers=1 and the local "
        "engine, or pass backend='fast' or 'pybullet' instead of sim"
    )


def _slim(episode: Episode, keep_path: bool) -> Episode:
    """``episode``, or a copy without its played-back ``path`` (most of its bytes)."""
    return episode if keep_path else replace(episode, path=episode.path[:0])


def _world_chunk(planner: Planner, job: tuple) -> tuple[list[Episode], list[bool]]:
    """A task: episodes of ``planner`` in a chunk of worlds.

    ``job`` is ``(sim, config, world_seeds, limit, keep_paths)``: ``sim`` is a live simulator (serial
    work in this process, left open) or a backend name (a worker builds it here from ``config``).
    """
    source, config, world_seeds, limit, keep_paths = job
    episodes: list[Episode] = []
    crossable: list[bool] = []
    live = not isinstance(source, str)
    with contextlib.nullcontext(source) if live else make_simulator(source, config) as sim:
        for world_seed in world_seeds:
            episodes.append(_slim(run_episode(planner, sim, int(world_seed), limit), keep_paths))
            if hasattr(planner, "crossable"):
                crossable.append(bool(planner.crossable))
    return episodes, crossable


def evaluate(
    planner: Planner,
    worlds: int,
    seed: int = 0,
    sim: Simulator | None = None,
    progress: bool = True,
    max_primitives: int | None = None,
    engine: str | None = None,
    workers: int = 1,
    backend: str = "fast",
    config: SimConfig | None = None,
    worlds_per_task: int | None = None,
    keep_paths: bool = True,
) -> EvalResult:
    """Run ``planner`` on evaluation set ``seed`` (``worlds`` worlds) and summarise.

    ``sim`` defaults to a new simulator of ``backend`` with ``config`` (closed afterwards);
    ``max_primitives`` to the simulator's config (10). ``crossable_rate`` is filled in when the
    planner reports ``crossable`` (the oracle).

    The worlds run as tasks of :func:`husky_course.engines.map_tasks`. With the local
    engine and one worker (the defaults) they run here, one after the other, in ``sim`` (a world a
    task). Otherwise (``engine="ray"``, or ``workers > 1``) a task is ``worlds_per_task`` worlds
    (default :class:`~husky_course.engines.EngineConfig`): the planner is pickled to the workers and
    each task builds its own simulator from the backend's name and config (those of ``sim`` when
    given).
    Every planner starts each episode afresh (``reset``), so every field but the timings
    (``ms_per_decision``, ``ms_per_reset``) is the same number on any engine. ``keep_paths=False``
    drops each episode's played-back ``path`` (about 20 kB a world, more than all the rest): what a
    summary of 100,000 worlds, which never plots them, should ask for.
    """
    seeds = eval_world_seeds(worlds, seed)
    engine = resolve_engine(engine)
    workers = check_int(workers, "workers", 1)
    own = False
    if engine == "local" and workers == 1:  # here, in ``sim``, a world a task (the bar moves per world)
        own = sim is None
        sim = make_simulator(backend, config) if sim is None else sim
        limit = sim.config.max_primitives if max_primitives is None else max_primitives
        jobs = [(sim, None, [world_seed], limit, bool(keep_paths)) for world_seed in seeds]
        sizes, desc = None, f"evaluate {planner.name}"
    else:
        if sim is not None:
            backend, config = _backend_of(sim), sim.config
        config = config or SimConfig()
        limit = config.max_primitives if max_primitives is None else max_primitives
        size = check_int(worlds_per_task or ENGINE.worlds_per_task, "worlds_per_task", 1, EVAL_SET_STRIDE)
        chunks = [seeds[i : i + size] for i in range(0, len(seeds), size)]
        jobs = [(check_backend(backend), config, chunk, limit, bool(keep_paths)) for chunk in chunks]
        sizes, desc = [len(c) for c in chunks], f"evaluate {planner.name} ({engine})"
    try:
        parts = map_tasks(
            _world_chunk, jobs, engine=engine, workers=workers, shared=planner, desc=desc, unit="world",
            sizes=sizes, progress=progress,
        )
    finally:
        if own and sim is not None:
            sim.close()
    episodes = [e for part, _ in parts for e in part]
    crossable = [c for _, part in parts for c in part]
    n = len(episodes)
    successes = sum(e.success for e in episodes)
    collisions = sum(e.collided for e in episodes)
    times = [t for e in episodes for t in e.decision_times]
    return EvalResult(
        planner=planner.name,
        worlds=n,
        seed=int(seed),
        max_primitives=int(limit),
        success_rate=successes / n,
        mean_prims=float(np.mean([e.n_prims for e in episodes])),
        collision_rate=collisions / n,
        collision_rate_upper95=clopper_pearson(collisions, n, 0.95, "upper")[1],
        success_ci95=clopper_pearson(successes, n, 0.95),
        ms_per_decision=1e3 * float(np.mean(times)) if times else 0.0,
        ms_per_reset=1e3 * float(np.mean([e.reset_time for e in episodes])),
        crossable_rate=float(np.mean(crossable)) if crossable else None,
        episodes=episodes,
    )
