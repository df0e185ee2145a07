"""Experiment: how much of the moving-course student's shortfall is its motion estimate?

Run: ``python benchmarks/exp_moving_student.py [--profile quick] [--eval-worlds 200] [--rounds N]
[--worlds-per-round N] [--epochs N]`` (the last three change the privileged student's recipe only:
a smoke run, no longer like for like).

Trains, in a separate artifact store (``--store``, default ``/tmp/husky-exp-moving``), the moving-course
memory student by the same DAgger recipe, but with a privileged motion estimate: every point of the
current scan gets the true lateral speed of the cylinder it lies on (0 for walls and standing
cylinders) instead of the course's estimate (:class:`husky_course.planners.motion.Tracks`; where it walks on
from there, in the walking map, is as in the course's student). Everything else is
the course's student. Evaluates it and the course's student (which must be trained already) on the
tuning set (evaluation set 1) and prints both success rates: the gap is what a perfect motion
estimate would buy this network; the rest of the distance to the oracle is learning.

The privileged estimate is wired in by patching the planner module for this process only (the
episode's world and time are recorded as the simulator loads worlds and the planner observes
steps), so evaluation runs in one process.
"""

from __future__ import annotations

import argparse
import os
from dataclasses import replace

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="quick")
    parser.add_argument("--eval-worlds", type=int, default=200)
    parser.add_argument("--store", default="/tmp/husky-exp-moving")
    parser.add_argument("--rounds", type=int)
    parser.add_argument("--worlds-per-round", type=int)
    parser.add_argument("--epochs", type=int)
    args = parser.parse_args()
    course_store = os.environ.get("HUSKY_ARTIFACTS")

    from husky_course.config import get_profile, with_world
    from husky_course.evaluation.episodes import evaluate
    from husky_course.planners.registry import make_planner

    profile = with_world(get_profile(args.profile), "moving")
    mem = profile.memory
    changes = {k: v for k, v in (("rounds", args.rounds), ("worlds_per_round", args.worlds_per_round)) if v}
    if "worlds_per_round" in changes:  # on either course
        changes["moving_worlds_per_round"] = changes["worlds_per_round"]
    mem = replace(mem, **changes)
    if args.epochs is not None:
        mem = replace(mem, train=replace(mem.train, epochs=args.epochs))
    variant = replace(profile, memory=mem)
    ours = evaluate(make_planner("memory", profile=profile), args.eval_worlds, 1, config=profile.sim,
                    progress=False, workers=2)

    import husky_course.planners.memory as memory_module
    from husky_course.data import store
    from husky_course.planners import motion
    from husky_course.sim.fast import FastSimulator

    state: dict = {}
    planner = memory_module.MemoryPlanner
    load, reset, observe = FastSimulator.load, planner.reset, planner.observe

    def traced_load(self, world):  # type: ignore[no-untyped-def]
        state["world"] = load(self, world)
        return state["world"]

    def traced_reset(self, start):  # type: ignore[no-untyped-def]
        reset(self, start)
        state["t"], state["pose"] = 0, np.array(state["world"].start, float)

    def traced_observe(self, action, obs):  # type: ignore[no-untyped-def]
        observe(self, action, obs)
        state["t"] += 1
        state["pose"] = state["pose"] + np.r_[self._library.local_paths[action, -1][:2], 0.0]

    def true_velocities(self, now):  # type: ignore[no-untyped-def]
        world, pose = state["world"], state["pose"]
        obs = world.obstacles_at(float(state["t"]))
        at = now + pose[:2]
        gap = np.hypot(at[:, None, 0] - obs[None, :, 0], at[:, None, 1] - obs[None, :, 1]) - obs[None, :, 2]
        nearest = np.argmin(gap, 1)
        on = gap[np.arange(len(nearest)), nearest] < 0.05
        self.previous = np.asarray(now, float)[:, :2].copy()
        self.velocity = np.where(on, world.speeds[nearest], 0.0)
        self.tracks.fresh = np.zeros(len(at), bool)  # the truth: no point's motion is unknown
        return self.velocity

    FastSimulator.load = traced_load
    planner.reset = traced_reset
    planner.observe = traced_observe
    motion.MotionMemory.update = true_velocities
    os.environ[store.ARTIFACTS_ENV] = args.store
    from husky_course.imitation.dagger import get_memory

    student = get_memory(variant, progress=False)
    theirs = evaluate(make_planner("memory", profile=variant), args.eval_worlds, 1, config=profile.sim,
                      progress=False)
    if course_store is not None:
        os.environ[store.ARTIFACTS_ENV] = course_store
    print(f"rounds (privileged motion): {[round(r['success_in_its_worlds'], 3) for r in student.rounds]}")
    for name, r in (("course's student (estimated motion)", ours), ("same recipe, true motion", theirs)):
        lo, hi = r.success_ci95
        print(f"  {name:38s} tuning-set success {r.success_rate:.3f} [{lo:.3f}, {hi:.3f}]")


if __name__ == "__main__":
    main()
