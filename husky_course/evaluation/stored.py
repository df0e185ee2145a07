"""Evaluations kept in the artifact store: one planner on one set of worlds runs once per build.

Chapters 7, 8 and 10 evaluate several of the same planners on the same held-out worlds (chapter
8's table is every planner of the course, chapter 10's static column five of them). Their runs are
the same numbers each time (:func:`~husky_course.evaluation.episodes.evaluate` is deterministic for
any engine and worker count), so :func:`evaluate_stored` keeps each run under
``artifacts/<profile>/evaluations/`` and a second call with the same inputs reads it back.

A run's key is everything its result depends on:

* the planner's whole state (:func:`planner_fingerprint`): its class and, recursively, every
  attribute -- network weights and arrays by their bytes, configs by their fields -- so a retrained
  model or a changed parameter is a new key, never a stale hit;
* the worlds (how many, which evaluation set), the course (backend, simulator config), the step
  limit and whether paths are kept;
* the source code of the whole ``husky_course`` package: any change to the library runs every
  evaluation again.

A planner whose state cannot be fingerprinted (an attribute of a type this module does not know)
is evaluated without the store. Timings (``ms_per_decision``) are those of the stored run. Files are
written whole and renamed into place (:func:`~husky_course.data.io.atomic_save_npz`), so a killed
run leaves nothing half-written.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from ..config import Profile, SimConfig, check_profile, config_hash
from ..data.io import atomic_save_npz, load_npz
from ..data.store import artifacts_root
from ..planners.base import Planner
from .episodes import Episode, EvalResult, evaluate

_SCALARS = (str, int, float, bool, type(None), np.integer, np.floating, np.bool_)


class Unfingerprintable(TypeError):
    """A planner attribute of a type :func:`planner_fingerprint` does not know how to hash."""


@functools.cache
def source_fingerprint() -> str:
    """sha256 of every ``.py`` file of the ``husky_course`` package (relative path and bytes)."""
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        h.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()


def _feed(h: Any, obj: object, seen: set[int]) -> None:
    """Hash ``obj`` into ``h`` (see :func:`planner_fingerprint`)."""
    if isinstance(obj, _SCALARS):
        h.update(f"{type(obj).__name__}:{obj!r};".encode())
        return
    if id(obj) in seen:  # a cycle or a shared object: hashed once, referred to by its type
        h.update(f"<seen {type(obj).__qualname__}>".encode())
        return
    seen.add(id(obj))
    if isinstance(obj, torch.Tensor):
        obj = obj.detach().cpu().numpy()
    if isinstance(obj, np.ndarray):
        h.update(f"ndarray{obj.dtype.str}{obj.shape};".encode())
        h.update(np.ascontiguousarray(obj).tobytes())
    elif isinstance(obj, nn.Module):
        h.update(f"module {obj!r} training={obj.training};".encode())  # the architecture
        for name, value in obj.state_dict().items():
            _feed(h, name, seen)
            _feed(h, value, seen)
        _feed(h, {k: v for k, v in vars(obj).items() if not k.startswith("_") and k != "training"}, seen)
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        h.update(f"dataclass {type(obj).__qualname__};".encode())
        for f in dataclasses.fields(obj):
            _feed(h, f.name, seen)
            _feed(h, getattr(obj, f.name), seen)
    elif isinstance(obj, dict):
        h.update(f"dict{len(obj)};".encode())
        for key, value in obj.items():
            _feed(h, key, seen)
            _feed(h, value, seen)
    elif isinstance(obj, (list, tuple)):
        h.update(f"{type(obj).__name__}{len(obj)};".encode())
        for item in obj:
            _feed(h, item, seen)
    elif isinstance(obj, (set, frozenset)):
        _feed(h, sorted(obj, key=repr), seen)
    elif isinstance(obj, np.random.Generator):
        _feed(h, obj.bit_generator.state, seen)
    elif callable(obj) and hasattr(obj, "__qualname__") and not hasattr(obj, "__dict__"):
        h.update(f"callable {obj.__module__}.{obj.__qualname__};".encode())
    elif hasattr(obj, "__dict__") and type(obj).__module__.startswith("husky_course"):
        h.update(f"object {type(obj).__module__}.{type(obj).__qualname__};".encode())
        _feed(h, vars(obj), seen)
    else:
        raise Unfingerprintable(f"cannot fingerprint a {type(obj).__module__}.{type(obj).__qualname__}")


def planner_fingerprint(planner: Planner) -> str:
    """sha256 of a planner's class and whole state (raises :class:`Unfingerprintable`)."""
    h = hashlib.sha256()
    _feed(h, planner, set())
    return h.hexdigest()


def evaluation_path(
    planner: Planner, worlds: int, seed: int, profile: Profile, config: SimConfig,
    backend: str = "fast", max_primitives: int | None = None, keep_paths: bool = True,
) -> Path:
    """Where :func:`evaluate_stored` keeps this run (raises :class:`Unfingerprintable`)."""
    key = {"planner": planner_fingerprint(planner), "worlds": int(worlds), "seed": int(seed),
           "backend": backend, "sim": config_hash(config), "max_primitives": max_primitives,
           "keep_paths": bool(keep_paths), "source": source_fingerprint()}
    root = artifacts_root() / check_profile(profile).name / "evaluations"
    return root / f"{planner.name.replace(' ', '_')}-{config_hash(key)}.npz"


def _save(path: Path, result: EvalResult) -> None:
    eps = result.episodes
    meta = {**dataclasses.asdict(dataclasses.replace(result, episodes=[])), "episodes": len(eps)}
    arrays = {
        "meta": np.array(json.dumps(meta)),
        "world_seed": np.array([e.world_seed for e in eps], np.int64),
        "flags": np.array([[e.collided, e.success] for e in eps], bool).reshape(-1, 2),
        "reset_time": np.array([e.reset_time for e in eps], float),
        "n_actions": np.array([len(e.actions) for e in eps], np.int64),
        "actions": np.array([a for e in eps for a in e.actions], np.int64),
        "decision_times": np.array([t for e in eps for t in e.decision_times], float),
        "poses": np.concatenate([e.poses for e in eps]) if eps else np.empty((0, 3)),
        "n_path": np.array([len(e.path) for e in eps], np.int64),
        "path": np.concatenate([e.path for e in eps]) if eps else np.empty((0, 3)),
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_save_npz(path, arrays)


def _load(path: Path) -> EvalResult:
    a = load_npz(path)
    meta = json.loads(str(a.pop("meta")))
    n = meta.pop("episodes")
    meta["success_ci95"] = tuple(meta["success_ci95"])
    ends = np.cumsum(a["n_actions"])
    starts = ends - a["n_actions"]
    path_ends = np.cumsum(a["n_path"])
    episodes = []
    for i in range(n):
        s, e = int(starts[i]), int(ends[i])
        episodes.append(Episode(
            world_seed=int(a["world_seed"][i]), actions=[int(x) for x in a["actions"][s:e]],
            poses=a["poses"][s + i : e + i + 1], path=a["path"][path_ends[i] - a["n_path"][i] : path_ends[i]],
            collided=bool(a["flags"][i, 0]), n_prims=e - s, success=bool(a["flags"][i, 1]),
            decision_times=[float(t) for t in a["decision_times"][s:e]],
            reset_time=float(a["reset_time"][i])))
    return EvalResult(**meta, episodes=episodes)


def evaluate_stored(
    planner: Planner, worlds: int, seed: int, profile: Profile, sim_config: SimConfig | None = None,
    backend: str = "fast", max_primitives: int | None = None, keep_paths: bool = True, **kwargs: Any,
) -> EvalResult:
    """:func:`~husky_course.evaluation.episodes.evaluate` on a fresh simulator of ``backend`` and
    ``sim_config`` (default ``profile.sim``), read from the store when this exact run was made before
    (module docstring). ``kwargs`` (``workers``, ``engine``, ``progress``, ...) change how it runs,
    never its result.
    """
    config = sim_config or check_profile(profile).sim
    run = functools.partial(evaluate, planner, worlds, seed, backend=backend, config=config,
                            max_primitives=max_primitives, keep_paths=keep_paths, **kwargs)
    try:
        path = evaluation_path(planner, worlds, seed, profile, config, backend, max_primitives, keep_paths)
    except Unfingerprintable:
        return run()
    if path.is_file():
        return _load(path)
    result = run()
    _save(path, result)
    return result
