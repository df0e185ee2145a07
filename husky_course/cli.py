"""Command line: ``python -m husky_course {collect,stats,train,evaluate,certify,clean,fingerprint} ...``.

Examples
--------
``python -m husky_course collect --profile full --workers 2`` (into the artifact store)
``python -m husky_course collect --profile full --out artifacts/full/my-dataset --workers 2``
``python -m husky_course stats artifacts/full/my-dataset --json``
``python -m husky_course train all --profile full``
``python -m husky_course evaluate --planner heuristic --worlds 500 --json`` (the tuning set, 1)
``python -m husky_course train discs``, then ``evaluate --planner discs --worlds 500 --seed 0`` (reporting)
``python -m husky_course train memory --world moving`` (chapter 10's student, on moving obstacles)
``python -m husky_course evaluate --planner memory --world moving --trained-on static``
``python -m husky_course evaluate --planner mapping --sensing realistic`` (chapter 11: a noisy camera,
slipping wheels; ``--trained-with ideal`` runs a learned planner trained on ideal senses under them)
``python -m husky_course certify --profile full --worlds 2000 --workers 2`` (chapter 9's certificate,
at another scale: its own artifact; ``train certificate`` builds the profile's)
``python -m husky_course clean --profile full --dry-run`` (the artifacts no current code or config makes)
``python -m husky_course fingerprint`` (the library's code, docstrings and comments left out: ``make book``);
``python -m husky_course fingerprint husky_course.data.labels`` (a module's, with the modules it imports)
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace

from .checks import check_int
from .config import PROFILES, SENSING, WORLD_KINDS, ConfigError, get_profile, with_sensing, with_world
from .data.code import code_fingerprint, library_fingerprint
from .data.collect import collect
from .data.dataset import load_dataset, stats
from .data.io import DatasetError
from .data.store import dataset_dir
from .device import CHOICES, ENV, resolve_device, set_device
from .engines import ENGINES, set_engine
from .evaluation.episodes import eval_world_seeds, evaluate
from .planners.base import PlannerError, check_look_ahead
from .planners.learned import to_device
from .planners.registry import LEARNED_PLANNERS, PLANNERS, make_planner
from .sim.backends import BACKENDS, check_backend


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for tests and ``--help``)."""
    parser = argparse.ArgumentParser(prog="python -m husky_course", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    c = sub.add_parser("collect", help="collect a random-policy dataset (resumable)")
    c.add_argument(
        "--profile",
        default=None,
        help=f"one of {', '.join(PROFILES)} (default: $HUSKY_PROFILE or quick)",
    )
    c.add_argument("--videos", type=int, default=None, help="number of videos (default: the profile's)")
    c.add_argument("--seed", type=int, default=None, help="collection seed (default: the profile's)")
    c.add_argument("--workers", type=int, default=1, help="worker processes (result is the same for any)")
    c.add_argument("--backend", default=None, help=f"one of {', '.join(BACKENDS)} (default: fast)")
    c.add_argument(
        "--out", default=None, help="output directory (default: the profile's dataset in the artifact store)"
    )
    c.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    _engine_option(c)
    _world_option(c)
    _sensing_option(c)
    s = sub.add_parser("stats", help="summarise a dataset")
    s.add_argument("dir", help="dataset directory")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    e = sub.add_parser("evaluate", help="evaluate a planner on held-out evaluation worlds")
    e.add_argument(
        "--planner",
        required=True,
        help=f"one of {', '.join(PLANNERS)}; learned (need `train` first): {', '.join(LEARNED_PLANNERS)}",
    )
    e.add_argument("--worlds", type=int, default=100, help="number of evaluation worlds (default 100)")
    e.add_argument(
        "--seed", type=int, default=None,
        help="evaluation set (default: the tuning set, EvalPlan.tuning_seed = 1; the book reports on set 0)",
    )
    e.add_argument(
        "--look-ahead",
        type=int,
        default=None,
        help=f"look-ahead K of the learned planners ({', '.join(LEARNED_PLANNERS)})",
    )
    e.add_argument("--profile", default=None, help=f"one of {', '.join(PROFILES)} (default: $HUSKY_PROFILE)")
    e.add_argument("--backend", default="fast", help=f"one of {', '.join(BACKENDS)} (default: fast)")
    e.add_argument("--json", action="store_true", help="print one JSON object")
    e.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    e.add_argument(
        "--device",
        choices=CHOICES,
        default="cpu",
        help="where a learned planner's network decides (default cpu: one image per decision is "
        "faster on one CPU thread than a GPU round trip; auto = cuda when there is one)",
    )
    _engine_option(e)
    e.add_argument(
        "--workers",
        type=int,
        default=1,
        help="worker processes (local), or the CPUs of a local Ray cluster (default 1)",
    )
    _world_option(e)
    e.add_argument(
        "--trained-on",
        choices=WORLD_KINDS,
        default=None,
        help="which course a learned planner was trained on (default: the --world it is evaluated on)",
    )
    _sensing_option(e)
    e.add_argument(
        "--trained-with",
        choices=tuple(SENSING),
        default=None,
        help="the senses a learned planner was trained with (default: the --sensing it is evaluated with)",
    )
    t = sub.add_parser("train", help="train (or load) the chapters' models into the artifact store")
    t.add_argument("model", choices=(*TRAINABLE, "all"), help="which model ('all': every one, in order)")
    t.add_argument("--profile", default=None, help=f"one of {', '.join(PROFILES)} (default: $HUSKY_PROFILE)")
    t.add_argument("--no-progress", action="store_true", help="hide the progress bars")
    t.add_argument(
        "--device",
        choices=CHOICES,
        default=None,
        help=f"where to train and run batched inference (default: ${ENV}, else auto = cuda when "
        "there is one); checkpoints load on any device",
    )
    _engine_option(t)
    _world_option(t)
    _sensing_option(t)
    g = sub.add_parser(
        "certify",
        help="chapter 9's PAC-Bayes certificate for the memory student, at the profile's scale or another",
    )
    g.add_argument("--profile", default=None, help=f"one of {', '.join(PROFILES)} (default: $HUSKY_PROFILE)")
    g.add_argument("--worlds", type=int, default=None, help="N, training worlds (default: the profile's)")
    g.add_argument("--heldout-worlds", type=int, default=None, help="held-out worlds (default: profile)")
    g.add_argument("--workers", type=int, default=2, help="local processes, or a local Ray cluster's CPUs")
    g.add_argument("--no-progress", action="store_true", help="hide the progress bars")
    _engine_option(g)
    k = sub.add_parser("clean", help="delete the artifacts no current code or config would make")
    k.add_argument("--profile", default=None, help=f"one of {', '.join(PROFILES)} (default: $HUSKY_PROFILE)")
    k.add_argument("--dry-run", action="store_true", help="only list them")
    f = sub.add_parser("fingerprint", help="print the fingerprint of the library's code (no docstrings)")
    f.add_argument("modules", nargs="*", help="only these modules and what they import (as artifact keys do)")
    return parser


def _engine_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--engine",
        choices=ENGINES,
        default=None,
        help="where parallel work runs: local processes or Ray (default: $HUSKY_ENGINE, else local; "
        "ray attaches to $RAY_ADDRESS when set)",
    )


def _sensing_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--sensing",
        choices=tuple(SENSING),
        default="ideal",
        help="the robot's senses: ideal (chapters 1-10), or a real depth camera's noise and slipping "
        "wheels (chapter 11, husky_course.config.sensing); artifacts are keyed by it (default ideal)",
    )


def _world_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--world",
        choices=WORLD_KINDS,
        default="static",
        help="the course: static cylinders (the paper's), or some of them moving (chapter 10); "
        "artifacts are keyed by it (default static)",
    )


#: what ``train`` can build, in the order the chapters need them
TRAINABLE = (
    "encoder_decoder",
    "reward_net",
    "safety_image",
    "safety_prim",
    "joint",
    "diagnosis",
    "rnn",
    "distilled",
    "memory",
    "discs",
    "cuts",
    "certificate",
)


def _train(args: argparse.Namespace) -> dict:
    """Run the ``train`` subcommand: build or load each model, return its validation loss."""
    from .course.diagnosis import get_diagnosis
    from .training.builders import BUILDERS

    profile = with_sensing(with_world(get_profile(args.profile), args.world), args.sensing)
    progress = not args.no_progress
    if args.device is not None:
        set_device(args.device)
    out = {}
    for name in TRAINABLE if args.model == "all" else (args.model,):
        if name == "memory":  # chapter 8's student: DAgger rounds from the oracle
            from .imitation.dagger import get_memory

            student = get_memory(profile, progress)
            out[name] = {
                "best_val_loss": student.history.best_val,
                "rounds": student.rounds,
                "path": student.path,
            }
            continue
        if name in ("discs", "cuts"):  # chapter 8's disc network, chapter 10's cut network (after it):
            from .imitation.cuts import get_cuts  # simulated views, the planner's own perception
            from .imitation.discs import get_discs

            _, hist, path = (get_discs if name == "discs" else get_cuts)(profile, progress)
            out[name] = {"best_val_loss": hist.best_val, "epochs": len(hist.train_loss),
                         "seconds": round(hist.seconds, 1), "path": path}
            continue
        if name == "certificate":  # chapter 9: the memory student's PAC-Bayes certificate
            from .evaluation.certificate import get_certificate

            found = get_certificate(profile, progress)
            out[name] = {**found.to_json(), "path": found.path}
            continue
        if name == "diagnosis":  # chapter 4's variants and probes: many small runs, one JSON
            found = get_diagnosis(profile, progress)
            out[name] = {
                "variants": {r.variant.name: r.quality.auc for r in found.variants},
                "probes": found.probes,
            }
            continue
        trained = BUILDERS[name](profile, progress)
        out[name] = {
            "best_val_loss": trained.history.best_val,
            "epochs": len(trained.history.train_loss),
            "seconds": round(trained.history.seconds, 1),
            "path": trained.path,
        }
    return out


def _evaluate(args: argparse.Namespace) -> dict:
    """Run the ``evaluate`` subcommand and return the result's JSON dict."""
    base = get_profile(args.profile)
    profile = with_sensing(with_world(base, args.world), args.sensing)
    if args.planner not in PLANNERS:
        raise PlannerError(f"unknown planner {args.planner!r}: choose one of {', '.join(PLANNERS)}")
    learned = args.planner in LEARNED_PLANNERS
    kwargs: dict = {}
    if args.look_ahead is not None:
        if not learned:
            raise PlannerError(f"--look-ahead applies only to {', '.join(LEARNED_PLANNERS)}")
        kwargs["look_ahead"] = check_look_ahead(args.look_ahead)
    for flag, value in (("--trained-on", args.trained_on), ("--trained-with", args.trained_with)):
        if value is not None and not learned:
            raise PlannerError(f"{flag} applies only to {', '.join(LEARNED_PLANNERS)}")
    if learned:
        kwargs["profile"] = with_sensing(with_world(base, args.trained_on or args.world),
                                         args.trained_with or args.sensing)
    if args.planner in ("heuristic", "mapping", "tracking", "discs"):  # they read the course (its speeds)
        kwargs["config"] = profile.sim
    if args.seed is None:  # every choice is made on the tuning set; the reporting set is asked for by name
        args.seed = profile.eval.tuning_seed
    eval_world_seeds(args.worlds, args.seed)  # validate before building anything
    device = resolve_device(args.device)
    planner = to_device(make_planner(args.planner, **kwargs), device)
    result = evaluate(
        planner,
        args.worlds,
        args.seed,
        progress=not args.no_progress,
        engine=args.engine,
        workers=args.workers,
        backend=check_backend(args.backend),
        config=profile.sim,
        keep_paths=False,  # only the summary is printed
    )
    out = result.to_json()
    out["world"], out["sensing"] = args.world, args.sensing
    if learned:
        out["trained_on"] = args.trained_on or args.world
        out["trained_with"] = args.trained_with or args.sensing
    return out


def _certify(args: argparse.Namespace) -> dict:
    """Run the ``certify`` subcommand: the certificate at the asked scale (its own artifact)."""
    from .evaluation.certificate import get_certificate
    from .evaluation.pac_bayes import MIN_WORLDS

    profile = get_profile(args.profile)
    g = profile.guarantee
    worlds = g.worlds if args.worlds is None else check_int(args.worlds, "--worlds", MIN_WORLDS, 10**6)
    heldout = g.heldout_worlds if args.heldout_worlds is None else args.heldout_worlds
    heldout = check_int(heldout, "--heldout-worlds", 1, 10**6)
    finetune = min(g.finetune_worlds, worlds)
    g = replace(g, worlds=worlds, heldout_worlds=heldout, finetune_worlds=finetune)
    workers = check_int(args.workers, "--workers", 1, 10**4)
    found = get_certificate(replace(profile, guarantee=g), not args.no_progress, workers=workers)
    return {**found.to_json(), "path": found.path}


def _clean(args: argparse.Namespace) -> None:
    """Run the ``clean`` subcommand: list the stale artifacts, and delete them unless ``--dry-run``."""
    from .evaluation.stale import remove, sweep

    found = sweep(get_profile(args.profile))
    for path in found.stale:
        print(f"{'stale' if args.dry_run else 'removed'} {path}")
    for path in found.unchecked:
        print(f"kept (not checked) {path}")
    if not args.dry_run:
        remove(found.stale)
    verb = "would remove" if args.dry_run else "removed"
    kept = f"kept {len(found.current)} current and {len(found.unchecked)} not checked"
    print(f"{verb} {len(found.stale)}, {kept}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the process exit code."""
    args = build_parser().parse_args(argv)
    try:
        if getattr(args, "engine", None) is not None:
            set_engine(args.engine)  # reaches the labels that `train` computes without threading it through
        if args.command == "collect":
            profile = with_sensing(with_world(get_profile(args.profile), args.world), args.sensing)
            if args.out is None:  # the store's directory for exactly this spec (its name is the spec's hash)
                data = replace(
                    profile.data,
                    videos=profile.data.videos if args.videos is None else args.videos,
                    seed=profile.data.seed if args.seed is None else args.seed,
                    backend=check_backend(args.backend or profile.data.backend),
                )
                args.out = dataset_dir(replace(profile, data=data))
            out = collect(
                args.out,
                profile,
                videos=args.videos,
                seed=args.seed,
                workers=args.workers,
                backend=args.backend,
                progress=not args.no_progress,
            )
            print(json.dumps(stats(load_dataset(out)), indent=1))
        elif args.command == "stats":
            result = stats(load_dataset(args.dir))
            if args.json:
                print(json.dumps(result))
            else:
                for key, value in result.items():
                    print(f"{key:28s} {value}")
        elif args.command == "train":
            print(json.dumps(_train(args), indent=1))
        elif args.command == "clean":
            _clean(args)
        elif args.command == "fingerprint":
            print(code_fingerprint(*args.modules) if args.modules else library_fingerprint())
        elif args.command == "certify":
            print(json.dumps(_certify(args), indent=1))
        elif args.command == "evaluate":
            result = _evaluate(args)
            if args.json:
                print(json.dumps(result))
            else:
                for key, value in result.items():
                    print(f"{key:28s} {value}")
    except (ConfigError, DatasetError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0
