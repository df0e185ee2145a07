"""Experiment: which single misread decides each fatal decision of the moving disc planner?

Run: ``python benchmarks/exp_moving_fatal.py [--profile full] [--worlds 500] [--workers 2]`` (the
disc planner needs its network: ``python -m husky_course train discs``).

On the tuning set (evaluation set 1) of the moving course. ``exp_moving_failures.py`` sorts the
failures by what the planner knew of the cylinder it *hit*; but the planner is most often surprised
at its fatal decision (its own search still held a plan through its whole horizon), and the misread
that closed the way may be another cylinder's. Here each fatal decision (the last step from which
the true world still had a way through, found by the oracle's lattice search) is replayed with the
disc map told the truth (privileged, an analysis tool), and the planner's new choice is judged in
the true world (a way through remains after it):

* every disc's velocity at once (a disc within ``ON_CYLINDER`` of a cylinder's surface gets that
  cylinder's true lateral velocity);
* one disc's velocity at a time: the kinds of disc whose velocity alone fixes the decision (a
  first sight or tracked, a walker or standing, read walking or standing; at the episode's first
  decision or later);
* one disc's place, radius and velocity at a time;
* one cylinder an image has rendered but the map holds no disc on (its nearest disc belongs to another
  cylinder, or lies further than ``ON_CYLINDER`` from its surface) at a time, restored exactly with its
  true velocity: what the map's memory, or a disc that drifted off or covers two cylinders, cost. A
  restored cylinder is *forgotten* when no disc lies within 1 m of its surface.

Measured (full profile, 500 tuning worlds, the disc planner with its network-centre tracks): 87
fatal decisions, 19 of them the first; every disc's velocity told fixes 36, one disc's velocity 38
(its place too: 44); the disc whose velocity alone fixes it is a walker its tracks see for the first
time, read as standing, in 24 (14 of them at the first decision), a tracked walker read walking at a
wrong velocity in 7, a tracked walker read as standing in 4. One lost cylinder given back fixes 27
(that or one disc's velocity: 56); in 26 of them a disc lay within 1 m of it (a walker's disc that
drifted off it: 13 out of view, 9 in view; for 5 standing ones, a neighbour's disc or their own off by
more than ``ON_CYLINDER``), only one was forgotten outright.
So what the ladder calls memory is mostly discs off their cylinders, not cylinders forgotten.
The figures above were measured before the disc planner drew its tracked walkers' speeds
(``ArrivalsConfig.speed_sigma``); the script runs the planner as it is now. With the draws (full
profile, 500 tuning worlds): 74 fatal decisions, 12 of them the first; every disc's velocity told fixes
25, one disc's velocity 23 (its place too: 31), one lost cylinder given back 26 (that or one disc's
velocity: 43). The disc whose velocity alone fixes it: a first-sight walker read standing in 13 (7 at
the first decision), a tracked walker read walking at a wrong speed in 5, read standing in 2. The lost
cylinder: a walker with a disc within 1 m but none on it in 21 (12 out of view), forgotten in 3.
The figures above were measured before the planner broke the last ties by its draws' options
(``ArrivalsConfig.ties`` "options"). With them (fingerprint ``28e5ef29ec515817``, 500 tuning worlds, 380 s):
61 fatal decisions, 9 of them the first; every disc's velocity told fixes 27, one disc's velocity 28 (its
place too: 33), one lost cylinder given back 16 (that or one disc's velocity: 38). The disc whose velocity
alone fixes it: a walker read standing in 20 (a first sight in 12, 5 of them at the first decision; tracked
in 8), a tracked walker read walking at a wrong speed in 5, a tracked standing cylinder read walking in 3.
Its place and velocity: besides those, a tracked standing cylinder read standing in 8 (its place). The lost
cylinder: a walker out of view with a disc near it in 11, a walker in view forgotten at the first decision
in 2.
"""

from __future__ import annotations

import argparse
from collections import Counter
from multiprocessing import Pool

import numpy as np
from exp_moving_failures import crossable

from husky_course.config import Profile, get_profile, with_world
from husky_course.engines import limit_worker_threads
from husky_course.evaluation.episodes import eval_world_seeds
from husky_course.evaluation.rollout import Rollout
from husky_course.planners.reference import ON_CYLINDER, truth_in_frame
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator
from husky_course.sim.world import World


def survives(sim: FastSimulator, world: World, pose: np.ndarray, action: int, t: int, limit: int) -> bool:
    """Whether the true world still has a way through after ``action`` from ``pose`` at step ``t``."""
    result = sim.apply(pose, action, t)
    if result.collided:
        return False
    return limit - t - 1 <= 0 or crossable(sim, world, result.pose, t + 1, limit - t - 1)


def replay(planner, sim: FastSimulator, world: World, pose: np.ndarray, step: int, limit: int,
           seen: np.ndarray) -> dict:
    """The fatal decision at ``step`` (the planner has just acted), told the truth disc by disc, then
    given back one at a time the cylinders ``seen`` by some image so far that the map holds no disc on."""
    m, horizon = planner.map, max(1, min(planner.horizon, planner._remaining))
    cyl, vy = truth_in_frame(world, pose, float(step))
    discs, speeds = m.discs.copy(), m.speeds.copy()
    gap = np.hypot(discs[:, None, 0] - cyl[None, :, 0], discs[:, None, 1] - cyl[None, :, 1]) - cyl[None, :, 2]
    j = np.argmin(gap, axis=1) if len(discs) else np.zeros(0, int)
    on = gap[np.arange(len(discs)), j] < ON_CYLINDER if len(discs) else np.zeros(0, bool)

    def good() -> bool:
        return survives(sim, world, pose, planner._decide(horizon)[0], step, limit)

    out: dict = {"step": step, "velocity": [], "place": []}
    m.speeds = np.where(on, vy[j] if len(discs) else speeds, speeds)
    out["all"] = good()
    for i in np.flatnonzero(on):
        kind = "first sight" if m.fresh[i] else "tracked"
        kind += (", walker" if world.speeds[j[i]] else ", standing") + (", read walking" if speeds[i] else
                                                                         ", read standing")
        m.speeds = speeds.copy()
        m.speeds[i] = vy[j[i]]
        if abs(speeds[i] - vy[j[i]]) > 1e-9 and good():
            out["velocity"].append(kind)
        m.discs = discs.copy()
        m.discs[i] = cyl[j[i]]
        if good():
            out["place"].append(kind)
        m.discs = discs.copy()
    m.speeds = speeds
    out["restored"] = restore(planner, sim, pose, step, seen, cyl, vy, set(j[on].tolist()), good)
    return out


def restore(planner, sim: FastSimulator, pose: np.ndarray, step: int, seen: np.ndarray, cyl: np.ndarray,
            vy: np.ndarray, held: set, good) -> list[str]:
    """The kinds of the lost cylinders (``seen``, not in ``held``) whose return alone fixes the decision."""
    m, world = planner.map, sim.world
    discs, speeds, fresh, doubt = m.discs, m.speeds, m.fresh, m.doubt
    in_view = set(sim.visible_obstacles(pose, float(step)).tolist())
    fixed = []
    for k in (int(k) for k in seen if int(k) not in held):
        m.discs, m.speeds = np.r_[discs, cyl[k][None]], np.r_[speeds, vy[k]]
        m.fresh, m.doubt = np.r_[fresh, False], np.r_[doubt, np.zeros((1, doubt.shape[1]))]
        if good():
            near = len(discs) and (np.hypot(*(discs[:, :2] - cyl[k, :2]).T) - cyl[k, 2]).min() < 1.0
            fixed.append(("walker" if world.speeds[k] else "standing") + (", in view" if k in in_view else
                         ", out of view") + (", a disc near it" if near else ", forgotten"))
    m.discs, m.speeds, m.fresh, m.doubt = discs, speeds, fresh, doubt
    return fixed


def chunk(args: tuple[Profile, list[int]]) -> list[dict]:
    """The fatal decisions of the disc planner on worlds ``seeds``, replayed (:func:`replay`)."""
    profile, seeds = args
    sim, limit = FastSimulator(profile.sim), profile.sim.max_primitives
    planner = make_planner("discs", config=profile.sim, profile=profile)
    found = []
    for seed in seeds:
        rollout = Rollout(planner, sim, seed, limit)
        world = rollout.world
        seen = np.zeros(0, int)  # the cylinders some image so far has rendered
        for d in rollout:
            seen = np.union1d(seen, sim.visible_obstacles(d.pose, float(d.step)))
            winnable = crossable(sim, world, d.pose, d.step, limit - d.step)
            if winnable and not survives(sim, world, d.pose, d.action, d.step, limit):
                found.append(replay(planner, sim, world, d.pose, d.step, limit, seen))
                break
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=500)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    profile = with_world(get_profile(args.profile), "moving")
    seeds = [int(s) for s in eval_world_seeds(args.worlds, 1)]
    parts = [(profile, seeds[i :: args.workers]) for i in range(args.workers)]
    if args.workers > 1:
        with Pool(args.workers, initializer=limit_worker_threads) as pool:
            found = [r for part in pool.map(chunk, parts) for r in part]
    else:
        found = chunk(parts[0])
    print(f"discs on {args.worlds} moving tuning worlds: {len(found)} fatal decisions, "
          f"{sum(r['step'] == 0 for r in found)} of them the first")
    print(f"  fixed by every disc's velocity told: {sum(r['all'] for r in found)}")
    print(f"  fixed by one disc's velocity told: {sum(bool(r['velocity']) for r in found)}; "
          f"by one disc's place and velocity: {sum(bool(r['place']) for r in found)}")
    back = sum(bool(r["restored"]) for r in found)
    print(f"  fixed by one lost cylinder given back: {back}; by that or one disc's velocity: "
          f"{sum(bool(r['restored']) or bool(r['velocity']) for r in found)}")
    names = {"velocity": "disc whose velocity", "place": "disc whose place and velocity",
             "restored": "lost cylinder whose return"}
    for told in ("velocity", "place", "restored"):
        kinds = Counter(k + (" (first decision)" if r["step"] == 0 else " (later)")
                        for r in found for k in set(r[told]))
        print(f"  the {names[told]} alone fixes it (a decision may count under two):")
        for name, count in kinds.most_common():
            print(f"    {count:4d}  {name}")


if __name__ == "__main__":
    main()
