"""Ground truth about dataset images, asked of the simulator (used to diagnose and supervise models).

The dataset records what happened to *one* primitive per image. The simulator can tell us more,
because every image carries its world seed and pose:

* :func:`primitive_outcomes` -- whether each of the 25 primitives would collide from there;
* :func:`survival_steps` -- for each primitive, how many steps the best continuation that starts
  with it stays collision-free (the oracle's own look-ahead, used to distil it into a network);
* :func:`nearest_obstacle_distance` -- the distance (m) to the nearest obstacle in view.

All three group images by world so each world is loaded once.
"""

from __future__ import annotations

import numpy as np

from .config import SimConfig
from .dataset import Dataset
from .fast_sim import FastSimulator
from .progress import tqdm


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
        paths = sim.library.paths_from(np.repeat(poses, len(ks), 0), np.tile(ks, len(poses)))
        out[rows] = sim.contacts(paths).any(1).reshape(len(poses), len(ks))
    return out


def survival_steps(
    ds: Dataset,
    horizon: int,
    idx: np.ndarray | None = None,
    config: SimConfig | None = None,
    progress: bool = False,
) -> np.ndarray:
    """Steps (0..``horizon``) the best continuation starting with each primitive survives, ``(n, 25)``.

    Every primitive ends at the start heading and advances the same distance, so after ``k``
    steps the robot's lateral position lies on a lattice of the library's offset spacing; the
    search below is an exact dynamic programme over ``(step, lattice position)``.
    """
    if horizon < 1:
        raise ValueError(f"horizon must be >= 1, got {horizon}")
    sim = FastSimulator(config)
    lib = sim.library
    idx, groups = _by_world(ds, idx)
    out = np.zeros((len(idx), lib.n), np.int8)
    for seed, rows in tqdm(groups, desc="survival", disable=not progress, leave=False):
        sim.load(seed)
        for r in rows:
            out[r] = best_continuations(sim, np.asarray(ds.poses[idx[r]], float), horizon)
    return out


def _survival_job(job: tuple) -> tuple[np.ndarray, np.ndarray]:
    rows, seeds, poses, horizon, config = job
    sim = FastSimulator(config)
    out = np.zeros((len(rows), sim.library.n), np.int8)
    for j, (seed, pose) in enumerate(zip(seeds, poses, strict=True)):
        if sim.world is None or sim.world.seed != seed:
            sim.load(int(seed))
        out[j] = best_continuations(sim, pose, horizon)
    return rows, out


def survival_at(
    world_seeds: np.ndarray,
    poses: np.ndarray,
    horizon: int,
    config: SimConfig | None = None,
    workers: int = 2,
    progress: bool = True,
) -> np.ndarray:
    """Survival labels ``(n, 25)`` for arbitrary ``(world seed, pose)`` states, in parallel."""
    import multiprocessing as mp

    if horizon < 1:
        raise ValueError(f"horizon must be >= 1, got {horizon}")
    world_seeds = np.asarray(world_seeds)
    poses = np.asarray(poses, float)
    order = np.argsort(world_seeds, kind="stable")
    chunks = np.array_split(order, max(1, len(order) // 400))
    jobs = [(c, world_seeds[c], poses[c], horizon, config) for c in chunks if len(c)]
    out = np.zeros((len(poses), 25), np.int8)
    ctx = mp.get_context("fork")
    with ctx.Pool(max(1, workers)) as pool:
        for rows, part in tqdm(
            pool.imap_unordered(_survival_job, jobs),
            total=len(jobs),
            desc="survival labels",
            disable=not progress,
        ):
            out[rows] = part
    return out


def survival_steps_parallel(
    ds: Dataset,
    horizon: int,
    idx: np.ndarray | None = None,
    config: SimConfig | None = None,
    workers: int = 2,
    progress: bool = True,
) -> np.ndarray:
    """:func:`survival_steps` computed by ``workers`` processes (same result, in chunks)."""
    idx = np.arange(len(ds)) if idx is None else np.asarray(idx)
    seeds = ds.world_seeds[ds.episode[idx]]
    return survival_at(seeds, np.asarray(ds.poses[idx], float), horizon, config, workers, progress)


def best_continuations(sim: FastSimulator, pose: np.ndarray, horizon: int) -> np.ndarray:
    """For each first primitive, the most steps (<= ``horizon``) a sequence starting with it survives."""
    lib = sim.library
    n = lib.n
    ks = np.arange(n)
    # value[s][state] = max further safe steps from lattice state at depth s (computed backwards)
    # states at depth s are poses reached after s safe steps; enumerate them forwards first.
    levels: list[np.ndarray] = [pose[None].copy()]
    safe_children: list[np.ndarray] = []
    child_index: list[np.ndarray] = []
    for _ in range(horizon):
        poses = levels[-1]
        paths = lib.paths_from(np.repeat(poses, n, 0), np.tile(ks, len(poses)))
        safe = ~sim.contacts(paths).any(1).reshape(len(poses), n)
        ends = paths[:, -1].reshape(len(poses), n, 3)
        keys = np.round(ends[..., 1] * 1e4).astype(np.int64)  # the lattice makes y exact to 0.1 mm
        uniq, inverse = np.unique(keys[safe], return_inverse=True)
        nxt = np.zeros((len(uniq), 3))
        nxt[inverse] = ends[safe]
        ci = np.full((len(poses), n), -1)
        ci[safe] = inverse
        safe_children.append(safe)
        child_index.append(ci)
        levels.append(nxt)
        if len(uniq) == 0:
            break
    value = np.zeros(len(levels[-1]), np.int64)  # at the last level no further steps are counted
    for depth in range(len(safe_children) - 1, -1, -1):
        safe, ci = safe_children[depth], child_index[depth]
        child_val = np.where(safe, 1 + value[np.maximum(ci, 0)] if value.size else 1, 0)
        if depth == 0:
            return child_val[0].astype(np.int8)
        value = child_val.max(1)
    return np.zeros(n, np.int8)


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
        t, kind = sim.column_hits(np.asarray(ds.poses[idx[rows]], float))
        out[rows] = np.minimum(np.where(kind >= 2, t, np.inf).min(1), far)
    return out
