"""Ground truth about dataset images, asked of the simulator (used to diagnose and supervise models).

The dataset records what happened to *one* primitive per image. The simulator can tell us more,
because every image carries its world seed and pose:

* :func:`primitive_outcomes` -- whether each of the 25 primitives would collide from there;
* :func:`survival_steps_parallel` -- for each primitive, how many steps the best continuation that
  starts with it stays collision-free (the oracle's own lattice search,
  :mod:`husky_course.sim.lattice`, used to distil it into a network; :func:`survival_at` for any
  states, in chunks on :func:`husky_course.engines.map_tasks`);
* :func:`nearest_obstacle_distance` -- the distance (m) to the nearest obstacle in view.

All three group images by world so each world is loaded once, and ask at each image's time (its
step in the video: on the moving course the cylinders are where they were when it was taken).
"""

from __future__ import annotations

import numpy as np

from ..config import EvalPlan, SimConfig
from ..engines import map_tasks
from ..progress import tqdm
from ..sim.fast import FastSimulator
from ..sim.lattice import expand, survival
from .dataset import Dataset


def _by_world(ds: Dataset, idx: np.ndarray | None) -> tuple[np.ndarray, list[tuple[int, np.ndarray]]]:
    idx = np.arange(len(ds)) if idx is None else np.asarray(idx)
    video = ds.episode[idx]
    groups = []
    for v in np.unique(video):
        groups.append((int(ds.world_seeds[v]), np.flatnonzero(video == v)))
    return idx, groups


def primitive_outcomes(
    ds: Dataset, idx: np.ndarray | None = None, config: SimConfig | None = None, progress: bool = False
) -> np.ndarray:
    """Collision flag of every primitive from every image's pose, ``(len(idx), 25)`` bool."""
    sim = FastSimulator(config)
    idx, groups = _by_world(ds, idx)
    out = np.zeros((len(idx), sim.library.n), bool)
    ks = np.arange(sim.library.n)
    for seed, rows in tqdm(groups, desc="outcomes", disable=not progress, leave=False):
        sim.load(seed)
        poses = np.asarray(ds.poses[idx[rows]], float)
        times = np.repeat(np.asarray(ds.step[idx[rows]], float), len(ks))
        paths = sim.library.paths_from(np.repeat(poses, len(ks), 0), np.tile(ks, len(poses)))
        out[rows] = sim.contacts(paths, times).any(1).reshape(len(poses), len(ks))
    return out


def _survival_job(job: tuple) -> tuple[np.ndarray, np.ndarray]:
    rows, seeds, poses, times, horizon, config = job
    sim = FastSimulator(config)
    out = np.zeros((len(rows), sim.library.n), np.int8)
    for j, (seed, pose, t) in enumerate(zip(seeds, poses, times, strict=True)):
        if sim.world is None or sim.world.seed != seed:
            sim.load(int(seed))
        out[j] = best_continuations(sim, pose, horizon, float(t))
    return rows, out


def survival_at(
    world_seeds: np.ndarray,
    poses: np.ndarray,
    horizon: int,
    config: SimConfig | None = None,
    workers: int = EvalPlan.workers,
    progress: bool = True,
    engine: str | None = None,
    times: np.ndarray | None = None,
) -> np.ndarray:
    """Survival labels ``(n, 25)`` for arbitrary ``(world seed, pose, time)`` states, in parallel.

    ``times`` (steps, default 0) matter on the moving course only.

    Chunks of states (sorted by world, so each task loads a world once) run as tasks on
    ``engine`` (default :func:`husky_course.engines.resolve_engine`: ``--engine``, else
    ``$HUSKY_ENGINE``, else local processes); the labels do not depend on the engine or ``workers``.
    """
    if horizon < 1:
        raise ValueError(f"horizon must be >= 1, got {horizon}")
    world_seeds = np.asarray(world_seeds)
    poses = np.asarray(poses, float)
    times = np.zeros(len(poses)) if times is None else np.asarray(times, float)
    if times.shape != (len(poses),):
        raise ValueError(f"need one time per state: {times.shape} times for {len(poses)} poses")
    order = np.argsort(world_seeds, kind="stable")
    chunks = np.array_split(order, max(1, len(order) // 400))
    jobs = [(c, world_seeds[c], poses[c], times[c], horizon, config) for c in chunks if len(c)]
    out = np.zeros((len(poses), (config or SimConfig()).primitives.n), np.int8)
    parts = map_tasks(
        _survival_job,
        jobs,
        engine=engine,
        workers=max(1, workers),
        desc="survival labels",
        unit="chunk",
        progress=progress,
    )
    for rows, part in parts:
        out[rows] = part
    return out


def survival_steps_parallel(
    ds: Dataset,
    horizon: int,
    idx: np.ndarray | None = None,
    config: SimConfig | None = None,
    workers: int = EvalPlan.workers,
    progress: bool = True,
) -> np.ndarray:
    """Steps (0..``horizon``) the best continuation starting with each primitive survives from each
    image ``idx`` (at its pose and time), ``(n, 25)`` int8: :func:`survival_at` on the images' states,
    by ``workers`` processes (:func:`best_continuations` for each; the same result for any engine
    or number of workers)."""
    idx = np.arange(len(ds)) if idx is None else np.asarray(idx)
    seeds = ds.world_seeds[ds.episode[idx]]
    poses, times = np.asarray(ds.poses[idx], float), np.asarray(ds.step[idx], float)
    return survival_at(seeds, poses, horizon, config, workers, progress, times=times)


def best_continuations(sim: FastSimulator, pose: np.ndarray, horizon: int, t: float = 0.0) -> np.ndarray:
    """For each first primitive, the most steps (<= ``horizon``) a sequence starting with it at time
    ``t`` survives.

    One lattice expansion from ``pose`` (:func:`husky_course.sim.lattice.expand`, clearance not
    needed: ``cap = 0``) read backwards by :func:`husky_course.sim.lattice.survival`.
    """
    world = sim._require_world()
    return survival(expand(world, sim.library, np.asarray(pose, float), horizon, cap=0.0, t0=t))


def nearest_obstacle_distance(
    ds: Dataset, idx: np.ndarray | None = None, config: SimConfig | None = None
) -> np.ndarray:
    """Depth (m, along the view axis) of the nearest obstacle in each image, capped at ``far``."""
    sim = FastSimulator(config)
    far = sim.config.camera.far
    idx, groups = _by_world(ds, idx)
    out = np.full(len(idx), far)
    for seed, rows in groups:
        sim.load(seed)
        poses, times = np.asarray(ds.poses[idx[rows]], float), np.asarray(ds.step[idx[rows]], float)
        t, kind = sim.column_hits(poses, times)
        out[rows] = np.minimum(np.where(kind >= 2, t, np.inf).min(1), far)
    return out
