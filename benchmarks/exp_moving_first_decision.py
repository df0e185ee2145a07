"""Experiment: how much could the moving disc planner's first decision gain, by any camera-based rule?

Run: ``python benchmarks/exp_moving_first_decision.py [--profile full] [--worlds 250] [--draws 12]
[--workers 2]`` (the disc planner needs its network: ``python -m husky_course train discs``).

At the episode's first decision the planner has one image: every cylinder in view is a first sight,
and nothing in one image tells a walker from a standing cylinder. A camera-based planner's first
primitive is therefore the same in every world that differs from this one only in those cylinders'
motion. Here, on the tuning set (evaluation set 1) of the moving course, each world's first decision
is judged over ``draws`` such worlds: the cylinders the first image renders get their motion drawn
again from the course's model (the same number of them walk as in the world, chosen at random, each
at a speed uniform in ``speed_range``, either way); every place, and the motion of every cylinder not
rendered, are kept. For every first primitive it counts the draws in which the true world still has a
way through after it (the oracle's lattice search, which knows everything from then on), and takes
the primitive with the most: the best first primitive a planner could choose with *more* than the
image tells it (every cylinder's place, the walkers' count) and an oracle after it. Ties go to the
disc planner's own choice. Judged in the true world, it bounds what a better first decision can
gain; the mean over worlds of its share of draws estimates how often a first decision can keep a
way through (optimistic: the largest of 25 estimates).

Measured (full profile, worlds 0-249 of the tuning set, 12 draws, the disc planner with its
network-centre tracks; 12 min on 2 cores): 248 worlds have a way through at the start; the disc
planner's first primitive keeps one in 237, the best over the draws in 240 (it fixes 4 and breaks 1,
changing 46 choices). So a better first decision is worth at most about one point of success here
(3 of 248, with more knowledge than an image and an oracle after it), and 8 of the 11 worlds lost at
the first decision are lost to any first primitive chosen this way: their cylinders walk as the draws
rarely do. The mean share of draws the best primitive keeps a way through, 0.972 (the planner's
choice 0.945), estimates from above how often any camera-based first decision can keep one: 0.964
of the 250 worlds, far above the issue's goal, so it proves nothing impossible.
The figures above were measured before the disc planner drew its tracked walkers' speeds
(``ArrivalsConfig.speed_sigma``); the script runs the planner as it is now.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from multiprocessing import Pool

import numpy as np
from exp_moving_failures import crossable

from husky_course.config import Profile, get_profile, with_world
from husky_course.engines import limit_worker_threads
from husky_course.evaluation.episodes import eval_world_seeds
from husky_course.planners.base import episode_start
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator
from husky_course.sim.world import World


def first_ways(sim: FastSimulator, world: World, limit: int) -> np.ndarray:
    """Per first primitive ``(n,)``: the true ``world`` still has a way through after it (loads ``world``)."""
    sim.load(world)
    pose, out = world.start, np.zeros(sim.library.n, bool)
    for a in range(sim.library.n):
        result = sim.apply(pose, a, 0)
        out[a] = not result.collided and crossable(sim, world, result.pose, 1, limit - 1)
    return out


def redrawn(world: World, seen: np.ndarray, rng: np.random.Generator) -> World:
    """``world`` with the motion of the cylinders ``seen`` drawn again (as many walk; places kept)."""
    speeds = np.array(world.speeds, float)
    walkers = int((speeds[seen] != 0).sum())
    speeds[seen] = 0.0
    movers = rng.choice(seen, walkers, replace=False) if walkers else np.empty(0, int)
    lo, hi = world.config.speed_range  # type: ignore[attr-defined]
    speeds[movers] = rng.uniform(lo, hi, len(movers)) * rng.choice([-1.0, 1.0], len(movers))
    return replace(world, speeds=speeds)


def judge(args: tuple[Profile, int, int]) -> dict | None:
    """One world's first decision: the disc planner's, and the best over redrawn motions (None: no way)."""
    profile, seed, draws = args
    sim, limit = FastSimulator(profile.sim), profile.sim.max_primitives
    world = sim.load(seed)
    if not crossable(sim, world, world.start, 0, limit):
        return None
    planner = make_planner("discs", config=profile.sim, profile=profile)
    planner.reset(episode_start(planner, sim, seed, world.start.copy(), limit))
    ours = planner.act(sim.depth(world.start[None], 0.0)[0], world.start.copy())
    seen = sim.visible_obstacles(world.start, 0.0)
    rng = np.random.default_rng(seed)
    share = np.mean([first_ways(sim, redrawn(world, seen, rng), limit) for _ in range(draws)], axis=0)
    truth = first_ways(sim, world, limit)
    best = ours if share[ours] == share.max() else int(np.argmax(share))
    return {"ours": bool(truth[ours]), "best": bool(truth[best]), "share_ours": float(share[ours]),
            "share_best": float(share.max()), "changed": best != ours}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=250)
    parser.add_argument("--draws", type=int, default=12)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    if args.worlds < 1 or args.draws < 1 or args.workers < 1:
        parser.error("--worlds, --draws and --workers must be at least 1")
    profile = with_world(get_profile(args.profile), "moving")
    jobs = [(profile, int(s), args.draws) for s in eval_world_seeds(args.worlds, 1)]
    if args.workers > 1:
        with Pool(args.workers, initializer=limit_worker_threads) as pool:
            found = pool.map(judge, jobs, chunksize=1)
    else:
        found = [judge(job) for job in jobs]
    runs = [r for r in found if r is not None]
    n = len(runs)
    ours, best = sum(r["ours"] for r in runs), sum(r["best"] for r in runs)
    fixed = sum(r["best"] and not r["ours"] for r in runs)
    broken = sum(r["ours"] and not r["best"] for r in runs)
    print(f"{args.worlds} moving tuning worlds, {n} with a way through at the start, {args.draws} draws each")
    print(f"  the disc planner's first primitive keeps a way through in {ours} of {n}")
    print(f"  the best over the draws (ties to the planner's) in {best} of {n}: fixes {fixed}, "
          f"breaks {broken}, changes {sum(r['changed'] for r in runs)} choices")
    if n:
        print(f"  mean share of draws: the planner's choice {np.mean([r['share_ours'] for r in runs]):.3f}, "
              f"the best {np.mean([r['share_best'] for r in runs]):.3f}")


if __name__ == "__main__":
    main()
