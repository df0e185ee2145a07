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
* the code that ran it (:func:`evaluation_code`): the modules of the planner and of every object
  in its state, the episode loop and this module, with their imports, docstrings and comments left
  out (:func:`~husky_course.data.code.code_fingerprint`): an edit that can change the numbers runs
  the evaluation again, a docstring does not.

Each stored file records that code fingerprint and the modules it covers, so ``python -m
husky_course clean`` can tell a run that no current code would make (:func:`stale_evaluation`).

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
from ..data.code import code_fingerprint, module_path
from ..data.io import DatasetError, atomic_save_npz, load_npz
from ..data.store import artifacts_root
from ..planners.base import Planner
from .episodes import Episode, EvalResult, evaluate

_SCALARS = (str, int, float, bool, type(None), np.integer, np.floating, np.bool_)


class Unfingerprintable(TypeError):
    """A planner attribute of a type :func:`planner_fingerprint` does not know how to hash."""


#: what runs every stored evaluation, besides the planner's own modules
EVALUATION_CODE = ("husky_course.evaluation.episodes", __name__)


def _feed(h: Any, obj: object, seen: set[int], modules: set[str]) -> None:
    """Hash ``obj`` into ``h`` (see :func:`planner_fingerprint`); the module of its type (and of a
    function or class, its own) joins ``modules``."""
    modules.add(type(obj).__module__)
    if callable(obj) and hasattr(obj, "__qualname__"):
        modules.add(str(getattr(obj, "__module__", "")))
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
            _feed(h, name, seen, modules)
            _feed(h, value, seen, modules)
        state = {k: v for k, v in vars(obj).items() if not k.startswith("_") and k != "training"}
        _feed(h, state, seen, modules)
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        h.update(f"dataclass {type(obj).__qualname__};".encode())
        for f in dataclasses.fields(obj):
            _feed(h, f.name, seen, modules)
            _feed(h, getattr(obj, f.name), seen, modules)
    elif isinstance(obj, dict):
        h.update(f"dict{len(obj)};".encode())
        for key, value in obj.items():
            _feed(h, key, seen, modules)
            _feed(h, value, seen, modules)
    elif isinstance(obj, (list, tuple)):
        h.update(f"{type(obj).__name__}{len(obj)};".encode())
        for item in obj:
            _feed(h, item, seen, modules)
    elif isinstance(obj, (set, frozenset)):
        _feed(h, sorted(obj, key=repr), seen, modules)
    elif isinstance(obj, np.random.Generator):
        _feed(h, obj.bit_generator.state, seen, modules)
    elif callable(obj) and hasattr(obj, "__qualname__") and not hasattr(obj, "__dict__"):
        h.update(f"callable {obj.__module__}.{obj.__qualname__};".encode())
    elif hasattr(obj, "__dict__") and type(obj).__module__.startswith("husky_course"):
        h.update(f"object {type(obj).__module__}.{type(obj).__qualname__};".encode())
        _feed(h, vars(obj), seen, modules)
    else:
        raise Unfingerprintable(f"cannot fingerprint a {type(obj).__module__}.{type(obj).__qualname__}")


def _walk(planner: Planner) -> tuple[str, list[str]]:
    """``(state hash, package modules of the types in it)`` (raises :class:`Unfingerprintable`)."""
    h, modules = hashlib.sha256(), set[str]()
    _feed(h, planner, set(), modules)
    return h.hexdigest(), sorted(m for m in modules if module_path(m) is not None)


def planner_fingerprint(planner: Planner) -> str:
    """sha256 of a planner's class and whole state (raises :class:`Unfingerprintable`)."""
    return _walk(planner)[0]


def evaluation_code(planner: Planner) -> tuple[str, list[str]]:
    """``(code fingerprint, modules)``: the code a stored run of ``planner`` depends on -- the modules
    of its class and of every object in its state, and :data:`EVALUATION_CODE` (with their imports)."""
    return _code(_walk(planner)[1])


def _code(planner_modules: list[str]) -> tuple[str, list[str]]:
    modules = sorted({*planner_modules, *EVALUATION_CODE})
    return code_fingerprint(*modules), modules


def stale_evaluation(path: Path) -> bool:
    """Whether no current code would make the stored run at ``path``: its recorded code fingerprint
    differs from today's over the same modules (or it records none, or cannot be read)."""
    try:
        meta = json.loads(str(load_npz(path)["meta"]))
        return meta["code"] != code_fingerprint(*meta["code_modules"])
    except (DatasetError, KeyError, ValueError, TypeError, OSError):
        return True


def evaluation_path(
    planner: Planner, worlds: int, seed: int, profile: Profile, config: SimConfig,
    backend: str = "fast", max_primitives: int | None = None, keep_paths: bool = True,
) -> Path:
    """Where :func:`evaluate_stored` keeps this run (raises :class:`Unfingerprintable`)."""
    state, modules = _walk(planner)
    key = {"planner": state, "worlds": int(worlds), "seed": int(seed),
           "backend": backend, "sim": config_hash(config), "max_primitives": max_primitives,
           "keep_paths": bool(keep_paths), "code": _code(modules)[0]}
    root = artifacts_root() / check_profile(profile).name / "evaluations"
    return root / f"{planner.name.replace(' ', '_')}-{config_hash(key)}.npz"


def _save(path: Path, result: EvalResult, code: tuple[str, list[str]]) -> None:
    eps = result.episodes
    meta = {**dataclasses.asdict(dataclasses.replace(result, episodes=[])), "episodes": len(eps),
            "code": code[0], "code_modules": code[1]}
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
    meta.pop("code", None)
    meta.pop("code_modules", None)
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
    _save(path, result, evaluation_code(planner))
    return result
