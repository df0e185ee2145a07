"""Random-policy data collection (paper, Section 3.2), resumable and reproducible.

Video ``v`` of a collection with seed ``s`` is played in world ``s * 1_000_000 + v`` and its
primitives are drawn from ``numpy.random.default_rng([s, v])``, uniformly over the library. So a
video depends on ``(s, v)`` alone: the result is the same for any number of workers and any
order of work. Videos are written in shards (``shards/shard_00012.npz``), each written atomically;
a run that is killed and started again skips finished shards and ends with the same bytes.
"""

from __future__ import annotations

import io
import json
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np

from .. import __version__
from ..checks import check_int, is_int
from ..config import EVAL_SEED_BASE, Profile, SimConfig, check_profile, to_dict
from ..engines import map_tasks, resolve_engine
from ..sim.backends import check_backend, make_simulator
from ..sim.base import Simulator
from ..sim.fast import FastSimulator
from .dataset import DTYPES, FORMAT_VERSION, STEP_ARRAYS, VIDEO_ARRAYS
from .io import DatasetError, atomic_save_npy, atomic_write_bytes, sha256_file

VIDEO_STRIDE = 1_000_000


def world_seed_for(seed: int, video: int) -> int:
    """World seed of video ``video`` in a collection with seed ``seed`` (below EVAL_SEED_BASE)."""
    if not 0 <= video < VIDEO_STRIDE:
        raise ValueError(f"video index {video} out of range 0..{VIDEO_STRIDE - 1}")
    world_seed = seed * VIDEO_STRIDE + video
    if not 0 <= world_seed < EVAL_SEED_BASE:
        raise ValueError(f"collection seed {seed} is out of range 0..{EVAL_SEED_BASE // VIDEO_STRIDE - 1}")
    return world_seed


def play_video(
    sim: Simulator, seed: int, video: int, max_primitives: int, render: bool = True
) -> dict[str, np.ndarray]:
    """Play one random-policy video and return its arrays (step arrays and one-row video arrays).

    With ``render=False`` the depth images are not drawn (``images`` is empty): what a calibration
    that only counts primitives needs, several times faster.
    """
    world = sim.load(world_seed_for(seed, video))
    rng = np.random.default_rng([seed, video])
    pose = world.start.copy()
    poses, applied = [], []
    collided = False
    for step in range(max_primitives):
        action = int(rng.integers(sim.library.n))
        poses.append(pose)
        applied.append(action)
        result = sim.apply(pose, action, step)
        if result.collided:
            collided = True
            break
        pose = result.pose
    n = len(applied)
    labels = np.zeros(n, np.uint8)
    prims = np.asarray(applied, np.int16)
    if collided:
        labels[-1] = 1
        prims = prims.copy()
        prims[-1] = -1
    images = sim.depth(np.asarray(poses), np.arange(n)) if render else np.empty((0,))  # step k at time k
    return {
        "images": images.astype(np.float16),
        "prims": prims,
        "labels": labels,
        "applied": np.asarray(applied, np.int16),
        "episode": np.full(n, video, np.int32),
        "step": np.arange(n, dtype=np.int16),
        "poses": np.asarray(poses, np.float32),
        "world_seeds": np.array([world.seed], np.int64),
        "lengths": np.array([n], np.int16),
        "collided": np.array([collided], np.uint8),
    }


def fresh_pairs(n: int, seed: int, config: SimConfig | None = None) -> dict[str, np.ndarray]:
    """``n`` new ``(image t, primitive, image t+1)`` pairs from freshly generated worlds.

    One random-policy step is taken from a random safe point of each new world's video (the
    paper's "completely new dataset" of 20 images, Section 4.1). Use a ``seed`` other than the
    training collection's so none of these worlds was trained on.
    """
    if not is_int(n) or n < 1:  # type: ignore[operator]
        raise ValueError(f"n must be >= 1, got {n!r} (an integer number of pairs)")
    sim = FastSimulator(config)
    rng = np.random.default_rng([seed, 99])
    out: dict[str, list] = {"image": [], "prim": [], "next": [], "world_seed": []}
    video = 0
    while len(out["prim"]) < n:
        v = play_video(sim, seed, video, sim.config.max_primitives)
        video += 1
        safe = np.flatnonzero(v["labels"] == 0)
        if safe.size == 0:
            continue
        t = int(rng.choice(safe))
        pose = v["poses"][t].astype(float)  # step t of the video: at time t
        end = sim.apply(pose, int(v["applied"][t]), t).pose
        out["image"].append(sim.depth(pose[None], t)[0])
        out["next"].append(sim.depth(end[None], t + 1)[0])
        out["prim"].append(int(v["applied"][t]))
        out["world_seed"].append(int(v["world_seeds"][0]))
    return {k: np.asarray(val) for k, val in out.items()}


def _concat(parts: list[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    return {k: np.concatenate([p[k] for p in parts]).astype(DTYPES[k]) for k in DTYPES}


def _shard_job(job: tuple) -> int:
    """Collect one shard of videos and write it atomically (a task: its simulator is built here)."""
    shard_path, profile, backend, seed, start, stop, shard_id = job
    with make_simulator(backend, profile.sim) as sim:
        parts = [play_video(sim, seed, v, profile.sim.max_primitives) for v in range(start, stop)]
    buf = io.BytesIO()
    np.savez(buf, **_concat(parts))
    atomic_write_bytes(Path(shard_path), buf.getvalue())
    return shard_id


def _load_shard(path: Path) -> dict[str, np.ndarray]:
    try:
        with np.load(path, allow_pickle=False) as z:
            return {k: z[k] for k in DTYPES}
    except Exception as exc:  # zipfile/ValueError/KeyError/OSError: all mean unusable
        raise DatasetError(f"shard {path} is truncated or corrupted ({exc}); delete it and rerun") from exc


def collection_spec(profile: Profile, videos: int, seed: int, backend: str) -> dict:
    """Everything that determines the dataset's bytes (compared on resume)."""
    return {
        "format": FORMAT_VERSION,
        "sim": to_dict(profile.sim),
        "videos": videos,
        "seed": seed,
        "backend": backend,
        "shard_videos": profile.data.shard_videos,
    }


def collect(
    out: str | Path,
    profile: Profile,
    videos: int | None = None,
    seed: int | None = None,
    workers: int = 1,
    backend: str | None = None,
    progress: bool = True,
    engine: str | None = None,
) -> Path:
    """Collect (or finish collecting) a random-policy dataset into ``out`` and return ``out``.

    Sizes default to the profile's ``data`` config. Finished shards are kept until the final
    arrays and ``meta.json`` are written, so an interrupted run resumes where it stopped. One
    task per shard runs on ``engine`` (:func:`husky_course.engines.map_tasks`; ``ray`` writes
    the shards from its workers, so ``out`` must be on a file system they share); the bytes are the
    same for any engine and any number of ``workers``.
    """
    profile = check_profile(profile)
    videos = profile.data.videos if videos is None else videos
    seed = profile.data.seed if seed is None else seed
    backend = check_backend(backend or profile.data.backend)
    if not is_int(videos) or videos <= 0:  # type: ignore[operator]
        raise ValueError(f"the number of videos must be a positive integer, got {videos!r}")
    if not is_int(workers) or workers < 1:
        raise ValueError(f"workers must be a positive integer, got {workers!r}")
    check_int(seed, "the collection seed")
    engine = resolve_engine(engine)
    world_seed_for(seed, videos - 1)  # validates seed and video count
    profile = replace(
        profile, data=replace(profile.data, videos=int(videos), seed=int(seed), backend=backend)
    )
    out = Path(out)
    spec = collection_spec(profile, int(videos), int(seed), backend)
    spec_text = json.dumps(spec, indent=1, sort_keys=True)
    out.mkdir(parents=True, exist_ok=True)
    spec_path = out / "spec.json"
    if spec_path.exists():
        if json.loads(spec_path.read_text()) != spec:
            raise DatasetError(
                f"{out} holds a dataset made with a different config (see {spec_path}); "
                "choose another --out directory or delete this one"
            )
    elif any(out.iterdir()):
        raise DatasetError(f"{out} is not empty and holds no dataset spec; choose an empty directory")
    else:
        atomic_write_bytes(spec_path, spec_text.encode())
    if (out / "meta.json").exists():
        return out  # already finished

    shard_dir = out / "shards"
    shard_dir.mkdir(exist_ok=True)
    size = profile.data.shard_videos
    jobs = []
    for shard_id, start in enumerate(range(0, videos, size)):
        path = shard_dir / f"shard_{shard_id:05d}.npz"
        if path.exists():
            _load_shard(path)  # raises a clear error if a finished shard is damaged
            continue
        jobs.append((str(path), profile, backend, seed, start, min(start + size, videos), shard_id))
    n_shards = -(-videos // size)
    map_tasks(
        _shard_job,
        jobs,
        engine=engine,
        workers=workers,
        desc=f"collect ({backend})",
        unit="shard",
        initial=n_shards - len(jobs),  # shards finished by an earlier, interrupted run
        progress=progress,
    )
    _merge(out, spec, n_shards)
    return out


def _merge(out: Path, spec: dict, n_shards: int) -> None:
    shard_dir = out / "shards"
    data = _concat([_load_shard(shard_dir / f"shard_{i:05d}.npz") for i in range(n_shards)])
    for name in STEP_ARRAYS + VIDEO_ARRAYS:
        atomic_save_npy(out / f"{name}.npy", data[name])
    meta = {
        **spec,
        "package_version": __version__,
        "images": int(data["labels"].shape[0]),
        "mean_primitives_per_video": float(data["lengths"].mean()),
        "counting": "every primitive applied, the colliding one included",
        "sha256": {n: sha256_file(out / f"{n}.npy") for n in STEP_ARRAYS + VIDEO_ARRAYS},
    }
    atomic_write_bytes(out / "meta.json", json.dumps(meta, indent=1, sort_keys=True).encode())
    shutil.rmtree(shard_dir, ignore_errors=True)
