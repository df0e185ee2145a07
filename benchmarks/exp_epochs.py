"""Experiment: the paper's networks trained to more epochs, each judged as a planner on the tuning set.

Run: ``python benchmarks/exp_epochs.py rnn 5,10,15 [--profile full] [--worlds 500] [--seed 1]``
(or ``joint``, judged through Algorithm 1, the ``lookahead`` planner; or ``distilled``).

The full profile caps each network's epochs so that ``make book`` fits its budget on 2 cores; the
paper's networks were still improving at their caps. For each cap in the list, the network is
trained (or loaded: each cap is its own artifact, in the store ``--store`` names, default the
course's) and its planner evaluated on the same worlds of evaluation set ``--seed`` (1: the tuning
set). Printed: the best validation loss and training time, success with its exact 95% interval, and
against the first cap the worlds crossed only with each (exact sign test). The caps in
``TrainingPlan`` name the runs of this script that chose them.
"""

from __future__ import annotations

import argparse
import os
from dataclasses import replace

PLANNERS = {"rnn": "rnn", "joint": "lookahead", "distilled": "distilled"}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("model", choices=PLANNERS, help="which network's epoch cap to vary")
    parser.add_argument("epochs", help="comma-separated caps, e.g. 5,10,15 (the first is the reference)")
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=500)
    parser.add_argument("--seed", type=int, default=1, help="evaluation set (1: the tuning set)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--store", default=None, help="artifact store (default: the course's)")
    args = parser.parse_args()
    try:
        caps = [int(e) for e in args.epochs.split(",")]
    except ValueError:
        parser.error(f"epochs must be comma-separated integers, got {args.epochs!r}")
    if not caps or min(caps) < 1:
        parser.error(f"every cap must be >= 1, got {args.epochs!r}")

    from husky_course.data import store

    if args.store:  # before anything reads the store's location
        os.environ[store.ARTIFACTS_ENV] = args.store
    from husky_course.config import get_profile
    from husky_course.course.diagnosis import sign_test
    from husky_course.evaluation.episodes import evaluate
    from husky_course.planners.registry import make_planner
    from husky_course.training.builders import BUILDERS

    profile = get_profile(args.profile)
    planner = PLANNERS[args.model]
    print(f"{args.model} ({planner} planner), {args.worlds} worlds of evaluation set {args.seed}, "
          f"profile {profile.name}", flush=True)
    runs = {}
    for cap in caps:
        plan = replace(profile.train, **{args.model: replace(getattr(profile.train, args.model), epochs=cap)})
        capped = replace(profile, train=plan)
        history = BUILDERS[args.model](capped, False).history
        runs[cap] = r = evaluate(make_planner(planner, profile=capped), args.worlds, args.seed,
                                 progress=False, workers=args.workers)
        lo, hi = r.success_ci95
        line = (f"  {cap:3d} epochs  val {history.best_val:.4f}  {history.seconds:6.0f} s  "
                f"success {r.success_rate:.3f} [{lo:.3f}, {hi:.3f}]")
        if cap != caps[0]:
            only_this, only_first, p = sign_test([e.success for e in r.episodes],
                                                 [e.success for e in runs[caps[0]].episodes])
            line += f"  worlds only with {cap}: {only_this}, only with {caps[0]}: {only_first}, p = {p:.2f}"
        print(line, flush=True)


if __name__ == "__main__":
    main()
