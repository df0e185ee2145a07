"""Experiment: would another DAgger recipe make a better memory student?

Run: ``python benchmarks/exp_memory_recipe.py [--profile full] [--world moving] [--rounds 5]
[--worlds-per-round 450] [--map-cells 32] [--epochs 10] [--eval-worlds 200]``.

Trains the memory student with the course's recipe changed only where an option says so, in a
separate artifact store (``--store``, default ``/tmp/husky-exp-recipe``; the student's artifact is
keyed by its whole config, so variants never collide), and evaluates it on the tuning set
(evaluation set 1) beside the course's own student (which must be trained already, in the course's
store). Prints the DAgger rounds' success in their own worlds and both success rates with exact
95% intervals. Nothing here changes the course: a recipe that wins goes into the config, and the
book's table, on the reporting set, says what it is worth.
"""

from __future__ import annotations

import argparse
import os
from dataclasses import replace


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--world", default="moving", choices=("static", "moving"))
    parser.add_argument("--rounds", type=int)
    parser.add_argument("--worlds-per-round", type=int)
    parser.add_argument("--map-cells", type=int)
    parser.add_argument("--epochs", type=int)
    parser.add_argument("--eval-worlds", type=int, default=200)
    parser.add_argument("--store", default="/tmp/husky-exp-recipe")
    args = parser.parse_args()

    from husky_course.config import get_profile, with_world
    from husky_course.data import store
    from husky_course.evaluation.episodes import evaluate
    from husky_course.imitation.dagger import get_memory
    from husky_course.planners.memory import MemoryPlanner
    from husky_course.planners.registry import make_planner

    course = with_world(get_profile(args.profile), args.world)
    mem = course.memory
    changes = {k: v for k, v in (("rounds", args.rounds), ("worlds_per_round", args.worlds_per_round),
                                 ("map_cells", args.map_cells)) if v is not None}
    if "worlds_per_round" in changes:  # on either course
        changes["moving_worlds_per_round"] = changes["worlds_per_round"]
    mem = replace(mem, **changes)
    if args.epochs is not None:
        mem = replace(mem, train=replace(mem.train, epochs=args.epochs))
    variant = replace(course, memory=mem)
    ours = evaluate(make_planner("memory", profile=course), args.eval_worlds, 1, config=course.sim,
                    progress=False, workers=2)
    os.environ[store.ARTIFACTS_ENV] = args.store
    student = get_memory(variant, progress=True)
    theirs = evaluate(MemoryPlanner(student.model, variant.sim, mem), args.eval_worlds, 1, config=variant.sim,
                      progress=False, workers=2)
    said = ", ".join(f"{k} {v}" for k, v in {**changes, "epochs": args.epochs}.items() if v is not None)
    print(f"variant ({said or 'the course recipe'}): rounds' success in their own worlds "
          f"{[round(r['success_in_its_worlds'], 3) for r in student.rounds]}")
    print(f"tuning set, {args.eval_worlds} worlds of evaluation set 1, {args.world} course:")
    for name, r in (("course's student", ours), ("variant", theirs)):
        lo, hi = r.success_ci95
        print(f"  {name:18s} success {r.success_rate:.3f} [{lo:.3f}, {hi:.3f}]")


if __name__ == "__main__":
    main()
