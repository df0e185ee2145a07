"""Command line: ``python -m husky_course {collect,stats} ...``.

Examples
--------
``python -m husky_course collect --profile full --out artifacts/full/my-dataset --workers 2``
``python -m husky_course stats artifacts/full/my-dataset --json``
"""

from __future__ import annotations

import argparse
import json
import sys

from .backends import BACKENDS
from .collect import collect
from .config import PROFILES, ConfigError
from .dataset import DatasetError, load_dataset, stats


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
    c.add_argument("--out", required=True, help="output directory")
    c.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    s = sub.add_parser("stats", help="summarise a dataset")
    s.add_argument("dir", help="dataset directory")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the process exit code."""
    args = build_parser().parse_args(argv)
    try:
        if args.command == "collect":
            out = collect(
                args.out,
                args.profile,
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
    except (ConfigError, DatasetError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0
