"""Training the memory student from a privileged teacher, on its own states (DAgger).

The teacher is the oracle's lattice search on the true world; the student
(:class:`~husky_course.planners.memory.MemoryPlanner`) sees only images and its own motion. Each
round:

1. **roll out** in fresh *training* worlds (collection seed ``MemoryConfig.collection_seed``, never
   an evaluation world): round 0 follows the teacher's actions, later rounds the student's own, so
   the data covers the states the student actually reaches, mistakes included;
2. **record** at every visited state the student's inputs (the depth image and its map raster) and,
   for the labels only, the true world and pose;
3. **label** every state with the simulator's survival of each primitive over
   ``MemoryConfig.label_horizon`` steps (:func:`husky_course.data.labels.survival_at`);
4. **aggregate** with every earlier round and **retrain** the network from its seeded start.

Every round's data (``round_<r>.npz``) and network (``round_<r>/model.pt``, resumable per epoch)
are artifacts under ``artifacts/<profile>/models/memory-<hash>/``; a killed run resumes at the
first missing piece and ends with the same bytes. ``model.pt`` there is the last round's network.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from ..config import Profile, world_flag
from ..data.collect import world_seed_for
from ..data.io import atomic_save_npz, load_npz
from ..data.labels import survival_at
from ..data.store import runs_dir
from ..engines import map_tasks
from ..models.memory import MemoryNet
from ..planners.base import episode_start
from ..planners.memory import MemoryPlanner
from ..planners.oracle import OraclePlanner
from ..progress import announce_build
from ..sim.fast import FastSimulator
from ..training.memory import final_fingerprint, memory_dir, memory_fingerprint, new_memory_net
from ..training.trainer import History, fit, save_model

ROLLOUT_KEYS = ("image", "map", "world_seed", "pose")
ROLLOUT_CHUNK = 25  #: worlds per rollout task (the result does not depend on it)


@dataclass
class Student:
    """The trained memory student, its history and where it is stored."""

    model: MemoryNet
    history: History
    path: str
    fingerprint: dict
    rounds: list[dict]  #: per round: states added, teacher or student, student's success in its worlds


def round_worlds(profile: Profile, r: int) -> np.ndarray:
    """World seeds of round ``r``: videos ``r * n + [0, n)`` of the seed, ``n`` the worlds per round on
    the profile's course (:meth:`~husky_course.config.MemoryConfig.worlds_on`)."""
    mem = profile.memory
    n = mem.worlds_on(profile.sim)
    videos = range(r * n, (r + 1) * n)
    return np.array([world_seed_for(mem.collection_seed, v) for v in videos])


def episode_steps(world_seed: np.ndarray) -> np.ndarray:
    """Each rollout state's step in its episode (= its time): rollouts store one world's states
    consecutively, one per step from 0, so it is the state's position in its run of equal seeds."""
    world_seed = np.asarray(world_seed)
    if not len(world_seed):
        return np.zeros(0)
    starts = np.flatnonzero(np.r_[True, world_seed[1:] != world_seed[:-1]])
    run = np.repeat(starts, np.diff(np.r_[starts, len(world_seed)]))
    return (np.arange(len(world_seed)) - run).astype(float)


def rollouts(
    student: MemoryPlanner, seeds: np.ndarray, teacher: bool, profile: Profile, progress: bool = False,
    workers: int | None = None,
) -> tuple[dict[str, np.ndarray], float]:
    """Roll out in each world of ``seeds``; return every visited state and the success rate.

    With ``teacher`` the oracle's actions are applied (the student only builds its map along the
    way); otherwise the student's own. Step ``k`` is time ``k`` (:func:`episode_steps`). Chunks of
    worlds run on ``workers`` processes (default ``EvalPlan.workers``) with
    :func:`husky_course.engines.map_tasks`; the states come back in the order of ``seeds``, the same
    for any number of workers.
    """
    seeds = np.asarray(seeds, np.int64)
    workers = profile.eval.workers if workers is None else workers
    chunks = [c for c in np.array_split(seeds, max(1, -(-len(seeds) // ROLLOUT_CHUNK))) if len(c)]
    parts = map_tasks(
        _rollout_chunk, chunks, workers=workers, shared=(student, teacher, profile),
        desc="rollouts (teacher)" if teacher else "rollouts (student)", unit="world",
        sizes=[len(c) for c in chunks], progress=progress,
    )
    arrays = {k: np.concatenate([p[k] for p, _ in parts]) if parts else np.zeros(0) for k in ROLLOUT_KEYS}
    return arrays, sum(n for _, n in parts) / max(len(seeds), 1)


def _rollout_chunk(
    shared: tuple[MemoryPlanner, bool, Profile], seeds: np.ndarray
) -> tuple[dict[str, np.ndarray], int]:
    """:func:`rollouts` in the worlds ``seeds`` (one task): their states and how many succeeded."""
    student, teacher, profile = shared
    sim = FastSimulator(profile.sim)
    limit = profile.sim.max_primitives
    oracle = OraclePlanner()
    out: dict[str, list] = {k: [] for k in ROLLOUT_KEYS}
    successes = 0
    for seed in seeds:
        world = sim.load(int(seed))
        pose = world.start.copy()
        student.reset(episode_start(student, sim, int(seed), pose, limit))
        if teacher:
            oracle.reset(episode_start(oracle, sim, int(seed), pose, limit))
        obs = sim.depth(pose[None])[0]
        collided = False
        for step in range(limit):
            image, grid = student.prepare(obs)
            out["image"].append(image.astype(np.float16))
            out["map"].append(grid.astype(np.uint8))
            out["world_seed"].append(int(seed))
            out["pose"].append(pose.copy())
            action = oracle.act(obs, pose.copy()) if teacher else student.choose(image, grid)
            result = sim.apply(pose, action, step)
            student.observe(action, None)
            pose = result.pose
            if result.collided:
                collided = True
                break
            obs = sim.depth(pose[None], step + 1)[0]
        successes += not collided
    arrays = {
        "image": np.asarray(out["image"], np.float16),
        "map": np.asarray(out["map"], np.uint8),
        "world_seed": np.asarray(out["world_seed"], np.int64),
        "pose": np.asarray(out["pose"], np.float64),
    }
    return arrays, successes


def _tensors(data: dict[str, np.ndarray], rows: np.ndarray) -> dict[str, torch.Tensor]:
    t = torch.from_numpy(rows)
    return {
        "image": torch.from_numpy(data["image"])[t],
        "map": torch.from_numpy(data["map"])[t],
        "survival": torch.from_numpy(data["survival"])[t],
    }


def get_memory(profile: Profile, progress: bool = True) -> Student:
    """The memory student, trained by DAgger (or loaded); every round is a resumable artifact."""
    mem = profile.memory
    fp = memory_fingerprint(profile)
    run = memory_dir(profile)
    if not (run / "model.pt").is_file():
        announce_build("memory", profile.name, f"train memory{world_flag(profile.sim)}")
    run.mkdir(parents=True, exist_ok=True)
    rounds: list[dict] = []
    parts: list[dict[str, np.ndarray]] = []
    model: MemoryNet | None = None
    history = History()
    for r in range(mem.rounds):
        path = run / f"round_{r}.npz"
        if not path.is_file():
            student = MemoryPlanner(model, profile.sim, mem)
            data, success = rollouts(student, round_worlds(profile, r), r == 0, profile, progress)
            data["survival"] = survival_at(
                data["world_seed"], data["pose"], mem.label_horizon, profile.sim, progress=progress,
                times=episode_steps(data["world_seed"]),
            )
            data["success"] = np.array([success])
            atomic_save_npz(path, data)
        data = load_npz(path)
        rounds.append(
            {"round": r, "acting": "teacher" if r == 0 else "student", "states": len(data["pose"]),
             "success_in_its_worlds": float(data["success"][0])}
        )
        parts.append(data)
        agg = {k: np.concatenate([p[k] for p in parts]) for k in ("image", "map", "survival", "world_seed")}
        in_val = agg["world_seed"] % 10 == 0  # one world in ten validates, whatever the round
        model = new_memory_net(profile)
        round_fp = {**fp, "round": r}
        history = fit(
            model,
            _tensors(agg, np.flatnonzero(~in_val)),
            _tensors(agg, np.flatnonzero(in_val)),
            mem.train,
            run_dir=run / f"round_{r}",
            fingerprint=round_fp,
            log_dir=runs_dir(f"memory-round{r}", round_fp, profile),
            progress=progress,
            desc=f"memory round {r}",
        )
    assert model is not None, "MemoryConfig.rounds must be >= 1"
    final = run / "model.pt"
    if not final.is_file():
        save_model(final, model, final_fingerprint(profile), history)
    return Student(model, history, str(final), fp, rounds)
