"""Experiment: first sights whose motion is still open, taken as possibly walking (a band), on and off.

Run: ``python benchmarks/exp_moving_doubt.py [--profile full] [--worlds 300] [--seed 1]``.

A cylinder seen once, that the arrivals rule (:mod:`husky_course.planners.arrivals`) could not
judge, is planned around as standing. Here it also stands for the band it could have walked to by
each sample's time, at the course's fastest walk, for up to ``doubt_steps`` steps: in the clearance
a plan is ranked by (soft), or as an obstacle (hard). Or (hedge) the first primitive is chosen by
its expected safe steps over three hypotheses for all of them at once: standing, walking left,
walking right (the course's mean speed), weighted by the course's share of walking cylinders. Or
(samples 16) every decision draws 16 walks for each first sight the earlier images leave undecided,
from the course's motion model over the walks no earlier column saw through, and chooses by the
mean safe steps over the draws (:class:`~husky_course.config.ArrivalsConfig`'s ``samples``). On
the moving course's tuning set (evaluation
set 1 by default), the disc planner and the tracker with each setting side by side on the same
worlds: success with its exact 95% interval, and the paired count of worlds won only with / only
without the band. The disc planner runs with its draws off (``samples`` 0, as these rules were
measured; "samples 16" also draws its tracked walkers' speeds, ``speed_sigma``) and needs its
network (``python -m husky_course train discs``).
"""

from __future__ import annotations

import argparse

from husky_course.config import get_profile, with_world
from husky_course.evaluation.episodes import evaluate
from husky_course.planners.registry import make_planner

SETTINGS = {
    "off": {}, "soft 1": {"doubt_steps": 1.0}, "soft 2": {"doubt_steps": 2.0},
    "hard 0.5": {"doubt_steps": 0.5, "doubt_hard": True}, "hard 1": {"doubt_steps": 1.0, "doubt_hard": True},
    "hedge": {"hedge": True}, "samples 16": {"samples": 16},
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=300)
    parser.add_argument("--seed", type=int, default=1, help="evaluation set (1: the tuning set)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--planners", default="discs,tracking")
    parser.add_argument("--settings", default=",".join(SETTINGS), help=f"of {', '.join(SETTINGS)}")
    args = parser.parse_args()
    profile = get_profile(args.profile)
    sim = with_world(profile, "moving").sim
    print(f"moving course, {args.worlds} worlds of evaluation set {args.seed}, profile {profile.name}")
    for name in args.planners.split(","):
        runs = {}
        for label in args.settings.split(","):
            extra = {"profile": profile, "samples": 0} if name == "discs" else {}  # its draws off
            planner = make_planner(name, config=sim, **{**extra, **SETTINGS[label]})
            runs[label] = r = evaluate(planner, args.worlds, args.seed, config=sim, progress=False,
                                       workers=args.workers)
            lo, hi = r.success_ci95
            line = f"  {name:9s} {label:9s} {r.success_rate:.3f} [{lo:.3f}, {hi:.3f}]"
            if label != "off" and "off" in runs:
                pairs = list(zip(runs["off"].episodes, r.episodes, strict=True))
                gained = sum(b.success and not a.success for a, b in pairs)
                lost = sum(a.success and not b.success for a, b in pairs)
                line += f"   worlds won only with it: {gained}, only without: {lost}"
            print(line, flush=True)


if __name__ == "__main__":
    main()
