"""Experiment: first sightings that walked in (:mod:`husky_course.planners.arrivals`), on and off.

Run: ``python benchmarks/exp_moving_arrivals.py [--profile full] [--worlds 300] [--seed 1]``.

On the moving course's tuning set (evaluation set 1 by default), the disc planner and the tracker,
each with a first sight taken as standing (as before) and with the arrivals rule, side by side on
the same worlds: success with its exact 95% interval, and the paired count of worlds only one of
the two won. The disc planner needs its network (``python -m husky_course train discs``).
"""

from __future__ import annotations

import argparse

from husky_course.config import get_profile, with_world
from husky_course.evaluation.episodes import evaluate
from husky_course.planners.registry import make_planner


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=300)
    parser.add_argument("--seed", type=int, default=1, help="evaluation set (1: the tuning set)")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    profile = get_profile(args.profile)
    sim = with_world(profile, "moving").sim
    print(f"moving course, {args.worlds} worlds of evaluation set {args.seed}, profile {profile.name}")
    for name in ("discs", "tracking"):
        runs = {}
        for arrivals in (False, True):
            extra = {"profile": profile} if name == "discs" else {}
            planner = make_planner(name, config=sim, arrivals=arrivals, **extra)
            runs[arrivals] = r = evaluate(planner, args.worlds, args.seed, config=sim, progress=False,
                                          workers=args.workers)
            lo, hi = r.success_ci95
            label = "arrivals" if arrivals else "first sight stands"
            print(f"  {name:9s} {label:19s} {r.success_rate:.3f} [{lo:.3f}, {hi:.3f}]", flush=True)
        pairs = list(zip(runs[False].episodes, runs[True].episodes, strict=True))
        gained = sum(b.success and not a.success for a, b in pairs)
        lost = sum(a.success and not b.success for a, b in pairs)
        print(f"  {name:9s} worlds won only with arrivals: {gained}, only without: {lost}")


if __name__ == "__main__":
    main()
