"""Evaluation with worker processes: numpy's BLAS at one thread per worker against the library's own.

Run: ``python benchmarks/bench_threads.py [--profile full] [--worlds 100] [--workers 2]
[--planner discs] [--world moving]`` (a learned planner needs its trained network; ``mapping`` needs
none).

Why: every evaluation, label and collection task runs in a pool of worker processes
(:func:`~husky_course.engines.map_tasks`). numpy's BLAS (OpenBLAS) starts as many threads as the
machine has cores in each process, so two workers on two cores run four BLAS threads that spin
against each other; the disc planner's network forward passes (small matrix products, many per
decision) slowed down most. :class:`~husky_course.engines.EngineConfig`'s ``worker_blas_threads``
(1) gives each worker one. This script evaluates the same planner on the same tuning worlds
(evaluation set ``EvalPlan.tuning_seed``) both ways, one after the other in one run, checks that the
episodes are the same, and prints the wall times and their ratio.

Measured (2 cores; full profile, the moving disc planner, 100 tuning worlds, 2 workers): 50.2 s
(105.1 ms per decision) with numpy's own threads, 24.9 s (51.9 ms) with one per worker, 2.02x, the
same episodes. Run it again rather than trusting these: the machines are noisy.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

from husky_course import engines
from husky_course.config import EvalPlan, get_profile, with_world
from husky_course.evaluation.episodes import evaluate
from husky_course.planners.registry import LEARNED_PLANNERS, make_planner


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--profile", default="quick")
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--planner", default="discs")
    ap.add_argument("--world", choices=("static", "moving"), default="moving")
    args = ap.parse_args()
    profile = with_world(get_profile(args.profile), args.world)
    extra = {"profile": profile} if args.planner in LEARNED_PLANNERS else {}
    planner = make_planner(args.planner, config=profile.sim, **extra)
    base, runs = engines.ENGINE, {}
    try:
        for label, blas in (("BLAS threads as numpy starts them", None), ("one BLAS thread per worker", 1)):
            engines.ENGINE = replace(base, worker_blas_threads=blas)
            start = time.perf_counter()
            r = evaluate(planner, args.worlds, EvalPlan.tuning_seed, config=profile.sim, workers=args.workers,
                         progress=False)
            runs[label] = (time.perf_counter() - start, r)
            print(f"{label:34s} {runs[label][0]:7.1f} s  success {r.success_rate:.3f}  "
                  f"{r.ms_per_decision:7.1f} ms/decision", flush=True)
    finally:
        engines.ENGINE = base
    (slow, a), (fast, b) = runs.values()
    same = [e.success for e in a.episodes] == [e.success for e in b.episodes] and \
        [e.actions for e in a.episodes] == [e.actions for e in b.episodes]
    print(f"{args.planner} on {args.worlds} {args.world} tuning worlds (evaluation set "
          f"{EvalPlan.tuning_seed}, {args.profile} profile, {args.workers} workers): one BLAS thread per "
          f"worker is {slow / fast:.2f}x as fast; same episodes: {same}")


if __name__ == "__main__":
    main()
