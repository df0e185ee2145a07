"""Experiment: variants of the moving disc planner as episodes, each beside the planner as it is.

Run: ``python benchmarks/exp_moving_variants.py [--profile full] [--variants memory:e lost:cylinder:0.1
doubt:aged] [--worlds 1000] [--start 1000] [--seed 1] [--base F.npz] [--check] [--workers 2]`` (the disc
planner needs its networks: ``python -m husky_course train discs``).

Three experiments define variants of the disc planner and run them as episodes on the same worlds as the
planner as it is (a paired comparison): ``exp_moving_memory.py`` its map told the truth by a rule
(privileged), ``exp_moving_lost.py`` rules of its map's memory, ``exp_moving_doubt_memory.py`` what its
draws doubt. Their episodes all run here (:func:`paired_episodes`), and this script runs any of them side
by side, named ``SCRIPT:VARIANT`` (:data:`SCRIPTS`): ``memory:el``, ``lost:keep:0.15``,
``doubt:evidence+aged``; and ``settings:KEY=VALUE[,KEY=VALUE]``, the disc planner built with other settings
(``exp_moving_paired.py``'s variants: ``settings:ties='draws'`` is the planner before its options
tie-break, ``ArrivalsConfig.ties``). Each prints its success rate with the exact 95% interval and the
worlds won only with it / only without it, with an exact two-sided sign test.

The planner as it is runs first, on worlds ``start`` to ``start + worlds - 1`` of evaluation set ``seed``
(1: the tuning set). With ``--base F.npz`` its successes are kept in ``F``, under a key of everything
they depend on (the library's code, the profile's configs, the weights of the networks the planner
loaded, the worlds: :func:`base_key`); a later run with the same key reads them instead of running the
planner again (about 5 minutes per 1,000 worlds of the full profile on 2 cores), and a file of another
key is run again and replaced, never read. ``--check`` adds each script's variant that changes nothing,
which must win exactly the planner's worlds (the script fails otherwise).
"""

from __future__ import annotations

import argparse
import hashlib
import importlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import torch

from husky_course.config import Profile, config_hash, get_profile, with_world
from husky_course.course.diagnosis import sign_test
from husky_course.data.code import library_fingerprint
from husky_course.data.io import atomic_save_npz, load_npz
from husky_course.engines import map_tasks
from husky_course.evaluation.episodes import eval_world_seeds, run_episode
from husky_course.evaluation.statistics import clopper_pearson
from husky_course.planners.base import Planner
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator

AS_IT_IS = "(as it is)"  #: the name the planner as it is prints under
#: ``SCRIPT`` of a ``SCRIPT:VARIANT`` name -> (its module, the function that builds its variants, the
#: variant that changes nothing)
SCRIPTS = {
    "memory": ("exp_moving_memory", "told", "(told nothing)"),
    "lost": ("exp_moving_lost", "wired", "nothing"),
    "doubt": ("exp_moving_doubt_memory", "doubting_planner", "nothing doubted"),
    "settings": ("exp_moving_paired", "variant_planner", ""),
}
BASE_HELP = ("a .npz file of the planner's own episodes: read when its key matches (the same code, configs, "
             "networks and worlds), else run and written")


def _episodes(task: tuple[Callable[[Profile, str], Planner], Profile, list[int], str]) -> list[bool]:
    """Success in each world of ``seeds`` of ``build(profile, variant)`` (a worker's task)."""
    build, profile, seeds, variant = task
    sim, planner = FastSimulator(profile.sim), build(profile, variant)
    return [run_episode(planner, sim, s, profile.sim.max_primitives).success for s in seeds]


def as_it_is(profile: Profile, _: str = AS_IT_IS) -> Planner:
    """The disc planner as it is: the side every variant is paired with."""
    return make_planner("discs", config=profile.sim, profile=profile)


def _weights(obj: object, h: Any, seen: set[int], depth: int = 0) -> None:
    """Feed ``h`` every network's parameters reachable from ``obj``'s attributes (three levels deep)."""
    if id(obj) in seen or depth > 3:
        return
    seen.add(id(obj))
    if isinstance(obj, torch.nn.Module):
        for name, value in obj.state_dict().items():
            h.update(name.encode() + value.detach().cpu().numpy().tobytes())
        return
    for value in getattr(obj, "__dict__", {}).values():
        _weights(value, h, seen, depth + 1)


def base_key(profile: Profile, worlds: list[int]) -> str:
    """What the planner as it is crosses on ``worlds`` depends on: the library's code (every module), the
    profile's configs, the networks it loaded and the worlds. A ``--base`` file is read only under it."""
    h = hashlib.sha256(f"{library_fingerprint()} {config_hash(profile)} {worlds}".encode())
    _weights(as_it_is(profile), h, set())
    return h.hexdigest()[:16]


def _base(base: Path, key: str) -> np.ndarray | None:
    """The successes ``base`` holds under ``key``, or None (no file, or another key's)."""
    if not base.exists():
        return None
    f = load_npz(base)  # a truncated or foreign file fails with a clear error
    if str(f.get("key")) == key and "won" in f:
        print(f"  the planner as it is: read from {base} (key {key})", flush=True)
        return f["won"].astype(bool)
    print(f"  {base} holds another key ({f.get('key')}, not {key}): the planner runs again", flush=True)
    return None


def paired_episodes(build: Callable[[Profile, str], Planner], variants: list[str], profile: Profile,
                    worlds: list[int], workers: int, base: Path | None = None,
                    known: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Each of ``variants`` (``build(profile, v)``; a module-level function, which the workers import) as
    a planner on ``worlds``, beside the disc planner as it is on the same worlds: print each one's success
    with its exact interval and the worlds won only with it / only without (exact sign test).

    The planner as it is runs first unless ``known`` holds its successes on ``worlds``, or ``base`` names
    a file holding them under :func:`base_key` (else it runs and the file is written). Returns the
    successes by name, :data:`AS_IT_IS` first.
    """
    key = base_key(profile, worlds) if base is not None else ""
    if known is None and base is not None:
        known = _base(base, key)
        if known is not None and len(known) != len(worlds):
            raise SystemExit(f"{base} holds {len(known)} worlds under the key of {len(worlds)}")
    won: dict[str, np.ndarray] = {}
    for name in [AS_IT_IS, *variants]:
        if name == AS_IT_IS and known is not None:
            a = np.asarray(known, bool)
        else:
            tasks = [(as_it_is if name == AS_IT_IS else build, profile, worlds[i : i + 10], name)
                     for i in range(0, len(worlds), 10)]
            done = map_tasks(_episodes, tasks, workers=workers, desc=name, unit="10 worlds")
            a = np.array([w for part in done for w in part], bool)
            if name == AS_IT_IS and base is not None:
                base.parent.mkdir(parents=True, exist_ok=True)
                atomic_save_npz(base, {"key": np.array(key), "won": a})  # never half-written
        won[name] = a
        lo, hi = clopper_pearson(int(a.sum()), len(a))
        line = f"  {name:30s} {a.mean():.3f} [{lo:.3f}, {hi:.3f}]"
        if name != AS_IT_IS:
            only_a, only_b, p = sign_test(a, won[AS_IT_IS])
            line += f"  won only with it: {only_a}, only without: {only_b}, p = {p:.3f}"
        print(line, flush=True)
    return won


def tuning_worlds(start: int, n: int, profile: str, seed: int = 1) -> list[int]:
    """Worlds ``start`` to ``start + n - 1`` of evaluation set ``seed`` (1: the tuning set); print which."""
    tuning = " (tuning)" if seed == 1 else ""
    print(f"episodes, worlds {start}-{start + n - 1} of evaluation set {seed}{tuning}, moving course, "
          f"{profile} profile:", flush=True)
    return [int(s) for s in eval_world_seeds(start + n, seed)[start:]]


def rule_main(doc: str, build_variant: Callable[[Profile, str], Planner], default: list[str], same: str,
              differs: str) -> None:
    """The command line of an experiment whose variants change rules of the disc planner (``build_variant``,
    a module-level builder): ``--profile --worlds --start --variants --check --base --workers``, tuning
    worlds ``start`` onwards; ``--check`` adds the variant ``same``, which must win exactly the planner's
    worlds (else the run fails with ``differs``)."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=1000)
    parser.add_argument("--start", type=int, default=7000, help="the first tuning world (evaluation set 1)")
    parser.add_argument("--variants", nargs="*", default=default)
    parser.add_argument("--check", action="store_true", help=f"add {same!r}: it must win the same worlds")
    parser.add_argument("--base", type=Path, help=BASE_HELP)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    if args.worlds < 1:
        raise SystemExit(f"--worlds must be positive; got {args.worlds}")
    profile = with_world(get_profile(args.profile), "moving")
    names = list(dict.fromkeys([*args.variants, *([same] if args.check else [])]))
    for name in names:
        build_variant(profile, name)  # a bad name fails before any world runs
    if not names:
        return
    worlds = tuning_worlds(args.start, args.worlds, profile.name)
    won = paired_episodes(build_variant, names, profile, worlds, args.workers, args.base)
    if args.check:
        agree = bool(np.array_equal(won[same], won[AS_IT_IS]))
        print(f"{same!r} won exactly the planner's worlds: {agree}")
        if not agree:
            raise SystemExit(differs)


def build(profile: Profile, name: str) -> Planner:
    """The planner ``SCRIPT:VARIANT`` names (:data:`SCRIPTS`), built by that script."""
    script, _, variant = name.partition(":")
    module, function, _ = SCRIPTS[script]
    return getattr(importlib.import_module(module), function)(profile, variant)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--variants", nargs="+", default=["memory:e", "lost:cylinder:0.1", "doubt:aged"])
    parser.add_argument("--worlds", type=int, default=1000)
    parser.add_argument("--start", type=int, default=1000, help="the first world of the evaluation set")
    parser.add_argument("--seed", type=int, default=1, help="evaluation set (1: the tuning set)")
    parser.add_argument("--base", type=Path, help=BASE_HELP)
    parser.add_argument("--check", action="store_true", help="add each script's variant that changes nothing")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    names = list(args.variants) + ([f"{s}:{v[2]}" for s, v in SCRIPTS.items()] if args.check else [])
    profile = with_world(get_profile(args.profile), "moving")
    for name in names:  # a bad name fails before any world runs
        if name.partition(":")[0] not in SCRIPTS:
            raise SystemExit(f"a variant is SCRIPT:VARIANT, SCRIPT one of {', '.join(SCRIPTS)}; got {name!r}")
        build(profile, name)
    worlds = tuning_worlds(args.start, args.worlds, args.profile, args.seed)
    won = paired_episodes(build, names, profile, worlds, args.workers, args.base)
    if args.check:
        differ = [n for n in names[len(args.variants):] if (won[n] != won[AS_IT_IS]).any()]
        if differ:
            raise SystemExit(f"changing nothing, {', '.join(differ)} won other worlds than the planner")
        print(f"checked: {len(SCRIPTS)} variants that change nothing won exactly the planner's worlds")


if __name__ == "__main__":
    main()
