"""Planner quality and speed on held-out evaluation worlds.

Run: ``python benchmarks/bench_planners.py [--worlds 500] [--seed 1]``. Evaluates the non-learned
planners (random, heuristic with and without memory, oracle) on the same evaluation worlds and
prints success rate with its exact 95% interval, mean primitives, ms per decision and ms per reset
(the oracle plans at reset). The worlds are the tuning set (evaluation set
``EvalPlan.tuning_seed`` = 1) unless ``--seed`` names another: the book's reporting set (0) is
for the tables, not for comparing settings.
"""

from __future__ import annotations

import argparse

from husky_course.config import EvalPlan
from husky_course.evaluation.episodes import evaluate
from husky_course.planners.classic import HeuristicPlanner
from husky_course.planners.registry import make_planner


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--worlds", type=int, default=500)
    ap.add_argument("--seed", type=int, default=EvalPlan.tuning_seed, help="evaluation set (default: tuning)")
    args = ap.parse_args()
    planners = {
        "random": make_planner("random"),
        "heuristic": make_planner("heuristic"),
        "heuristic+memory": HeuristicPlanner(memory=True, lateral_weight=0.05),
        "heuristic depth 1": HeuristicPlanner(depth=1),
        "oracle": make_planner("oracle"),
    }
    print(f"{args.worlds} worlds of evaluation set {args.seed}")
    for label, planner in planners.items():
        r = evaluate(planner, args.worlds, args.seed, progress=False)
        lo, hi = r.success_ci95
        extra = f", crossable {r.crossable_rate:.3f}" if r.crossable_rate is not None else ""
        print(
            f"{label:18s} success {r.success_rate:.3f} [{lo:.3f}, {hi:.3f}]  mean prims {r.mean_prims:.2f}  "
            f"{r.ms_per_decision:6.2f} ms/decision  {r.ms_per_reset:6.2f} ms/reset{extra}"
        )


if __name__ == "__main__":
    main()
