"""Experiment: is the moving disc planner's belief about who walks, and how fast, calibrated?

Run: ``python benchmarks/exp_moving_beliefs.py [--profile full] [--worlds 300] [--workers 2]`` (the
disc planner needs its network: ``python -m husky_course train discs``).

On the tuning set (evaluation set 1) of the moving course. The disc planner, as it is, drives; at
every decision its map's discs that lie on a cylinder (within ``ON_CYLINDER`` of its surface) are
compared with the truth (privileged: an analysis tool). Printed:

* **first sights** (the discs of the decision's image that its tracks see for the first time), by
  how the arrivals rule (:mod:`husky_course.planners.arrivals`) left them: *undecided* (the planner
  draws their walk from :meth:`~husky_course.planners.arrivals.Arrivals.weights`: its chance of a
  walk against the share that do walk, by range), *read walking* (the share that walk, and that
  walk the way read), *read standing* (the share that walk). At the first decision every cylinder
  in view is an undecided first sight;
* **tracked discs** (a track of two looks or more): on walkers, the share whose speed is off by
  more than 0.1 and 0.2 m per step and the share read standing, split by whether an image shows the
  cylinder now and whether it turned at a wall in the last three steps; on standing cylinders,
  the share read walking.

A calibrated belief whose failures remain is short of information, not of judgement: drawing from
it more cleverly cannot help, seeing more can.

Measured (full profile, 300 worlds; the planner with its draws, ``ArrivalsConfig.samples``): undecided
first sights at the first decision 1,837, believed to walk 0.400, walking 0.394 (0.406 / 0.391 / 0.390
at 2-3 / 3-4 / 4-6 m ahead); later 2,432, believed 0.390, walking 0.398 (0-2 m ahead: believed 0.332,
walking 0.288; 2-3 m: 0.367 / 0.288). Read walking 445, of which 0.843 walk, 0.960 of those the way
read; read standing 264, of which 0.087 walk. Tracked walkers off by more than 0.1 / 0.2 m per step:
in an image, no turn 0.105 / 0.066 (3,391 sightings; read standing 0.041), turned at a wall 0.529 /
0.461 (206); out of sight, no turn 0.069 / 0.041 (3,643), turned 0.342 / 0.300 (473). Tracked
standing cylinders read walking: 0.025 of 11,445. So the belief about first sights is calibrated. A
turn at a wall makes a tracked walker's large error about five times as likely (0.40 of 679 sightings
against 0.086 of 7,034), but turns are rare: 607 of the 878 large errors came without one.
"""

from __future__ import annotations

import argparse
from collections import defaultdict
from multiprocessing import Pool

import numpy as np

from husky_course.config import Profile, get_profile, with_world
from husky_course.engines import limit_worker_threads
from husky_course.evaluation.episodes import eval_world_seeds
from husky_course.evaluation.rollout import Rollout
from husky_course.planners.reference import ON_CYLINDER, truth_in_frame
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator

RANGES = ((0.0, 2.0), (2.0, 3.0), (3.0, 4.0), (4.0, 6.0))  #: m ahead, the undecided first sights' bins


def recording(planner) -> dict:
    """Make ``planner``'s disc map record how many of its discs the last image added (they come first)."""
    last = {"new": 0}
    base = type(planner.map)

    class Recorded(base):  # type: ignore[misc, valid-type]
        def _merge(self, obs, d, new, other):
            last["new"] = len(new)
            return super()._merge(obs, d, new, other)

    planner.map.__class__ = Recorded
    return last


def chunk(args: tuple[Profile, list[int]]) -> dict[str, list]:
    """Per kind of disc, rows of what the map believed and the truth, on worlds ``seeds``."""
    profile, seeds = args
    sim, limit = FastSimulator(profile.sim), profile.sim.max_primitives
    planner = make_planner("discs", config=profile.sim, profile=profile)
    last = recording(planner)
    rows: dict[str, list] = defaultdict(list)
    for seed in seeds:
        rollout = Rollout(planner, sim, seed, limit)
        world = rollout.world
        for d in rollout:
            step, pose, m = d.step, d.pose, planner.map
            cyl, vy = truth_in_frame(world, pose, float(step))
            turned = np.zeros(len(cyl), bool)
            for back in (1, 2, 3):  # its lateral velocity changed sign: it turned at a wall
                turned |= np.sign(truth_in_frame(world, pose, float(step - back))[1]) != np.sign(vy)
            shown = set(sim.visible_obstacles(pose, float(step)).tolist())
            for i, (x, y, _) in enumerate(m.discs):
                gap = np.hypot(cyl[:, 0] - x, cyl[:, 1] - y) - cyl[:, 2]
                j = int(np.argmin(gap))
                if gap[j] >= ON_CYLINDER:
                    continue
                walker = bool(world.speeds[j] != 0)
                if m.fresh[i] and i < last["new"]:  # a first sight, in this decision's image
                    if m.doubt[i].any():
                        rows["undecided"].append((step == 0, x, 1.0 - m.doubt[i, 0], walker))
                    else:
                        read = m.speeds[i]
                        rows["read walking" if read else "read standing"].append(
                            (walker, walker and np.sign(read) == np.sign(vy[j])))
                elif not m.fresh[i]:
                    rows["tracked"].append((walker, abs(m.speeds[i] - vy[j]), m.speeds[i] == 0, j in shown,
                                            bool(turned[j])))
    return rows


def report(rows: dict[str, list]) -> None:
    """Print the tables (module docstring)."""
    und = np.array(rows["undecided"], float).reshape(-1, 4)
    print("first sights of the decision's image, by how the arrivals rule left them:")
    for name, sel in (("at the first decision", und[:, 0] == 1), ("later", und[:, 0] == 0)):
        part = und[sel]
        if len(part):
            print(f"  undecided, {name}: {len(part)}; believed to walk {part[:, 2].mean():.3f}, "
                  f"walk {part[:, 3].mean():.3f}")
        for lo, hi in RANGES:
            b = part[(part[:, 1] >= lo) & (part[:, 1] < hi)]
            if len(b):
                print(f"    {lo:.0f}-{hi:.0f} m ahead: {len(b):5d}; believed {b[:, 2].mean():.3f}, walk "
                      f"{b[:, 3].mean():.3f}")
    for name in ("read walking", "read standing"):
        r = np.array(rows[name], float).reshape(-1, 2)
        if len(r):
            right = r[:, 1].sum() / max(r[:, 0].sum(), 1)
            tail = f", the way read {right:.3f} of them" if name == "read walking" else ""
            print(f"  {name}: {len(r)}; walk {r[:, 0].mean():.3f}{tail}")
    t = np.array(rows["tracked"], float).reshape(-1, 5)
    print("tracked discs on walkers (speed off by more than 0.1 / 0.2 m per step; read standing):")
    walk = t[t[:, 0] == 1]
    for shown in (1, 0):
        for turned in (0, 1):
            b = walk[(walk[:, 3] == shown) & (walk[:, 4] == turned)]
            if len(b):
                where = ("in an image" if shown else "out of sight") + (
                    ", turned at a wall" if turned else ", no turn")
                off = f"{np.mean(b[:, 1] > 0.1):.3f} / {np.mean(b[:, 1] > 0.2):.3f}"
                print(f"  {where:30s} {len(b):6d}: {off}; {np.mean(b[:, 2] == 1):.3f}")
    stand = t[t[:, 0] == 0]
    if len(stand):
        walking = np.mean(stand[:, 2] == 0)
        print(f"tracked discs on standing cylinders: {len(stand)}; read walking {walking:.3f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=300)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    if args.worlds < 1 or args.workers < 1:
        parser.error("--worlds and --workers must be at least 1")
    profile = with_world(get_profile(args.profile), "moving")
    seeds = [int(s) for s in eval_world_seeds(args.worlds, 1)]
    parts = [(profile, seeds[i:: args.workers]) for i in range(args.workers)]
    with Pool(args.workers, initializer=limit_worker_threads) as pool:
        found = pool.map(chunk, parts)
    rows: dict[str, list] = defaultdict(list)
    for part in found:
        for key, value in part.items():
            rows[key] += value
    print(f"discs on {args.worlds} moving tuning worlds (evaluation set 1): "
          f"{len(rows['undecided']) + len(rows['read walking']) + len(rows['read standing'])} first sights, "
          f"{len(rows['tracked'])} tracked discs on cylinders")
    report(rows)


if __name__ == "__main__":
    main()
