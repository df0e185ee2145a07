"""Experiment: what separates the mapping planner from perfect perception, rung by rung (static course).

Run: ``python benchmarks/exp_static_ladder.py [--profile full] [--worlds 1000] [--seed 1] [--sweep]``
(needs the disc network: ``python -m husky_course train discs``).

``--sweep`` runs, instead, the disc planner's settings one at a time around ``DiscConfig`` (the
search's margin, the growth of every predicted radius, the tolerance for unexplained points, the
horizon): the measurements that chose them, on the same tuning worlds.

On the tuning set (evaluation set 1; never the reporting set); the rungs and what each changes:
:mod:`husky_course.course.ladder`. Chapter 8 prints the same ladder on the profile's tuning worlds.
"""

from __future__ import annotations

import argparse
import time

from husky_course.config import get_profile
from husky_course.course.ladder import static_ladder
from husky_course.evaluation.episodes import evaluate
from husky_course.planners.registry import make_planner

#: the disc planner's settings, one changed at a time (``--sweep``)
SWEEP = [
    {}, {"margin": 0.02}, {"grow": 0.02}, {"unexplained": 0.03}, {"unexplained": 0.1}, {"unexplained": 0.2},
    {"unexplained": float("inf")}, {"horizon": 4}, {"horizon": 6},
]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--profile", default="full")
    ap.add_argument("--worlds", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=None, help="evaluation set (default: the tuning set)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--sweep", action="store_true", help="the disc planner's settings instead of the ladder")
    args = ap.parse_args()
    profile = get_profile(args.profile)
    seed = profile.eval.tuning_seed if args.seed is None else args.seed
    print(f"{args.worlds} worlds of evaluation set {seed}, {profile.name} profile")
    print("| rung | success | 95% interval | ms / decision |")
    print("|---|---|---|---|")
    rows = ([(f"discs {change or '(DiscConfig)'}", make_planner("discs", profile=profile, **change))
             for change in SWEEP] if args.sweep else static_ladder(profile))
    for name, planner in rows:
        t0 = time.perf_counter()
        r = evaluate(planner, args.worlds, seed, config=profile.sim, workers=args.workers, progress=False,
                     keep_paths=False)
        lo, hi = r.success_ci95
        print(f"| {name} | {r.success_rate:.3f} | [{lo:.3f}, {hi:.3f}] | {r.ms_per_decision:.2f} |"
              f"  ({time.perf_counter() - t0:.0f} s)", flush=True)


if __name__ == "__main__":
    main()
