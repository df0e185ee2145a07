"""Experiment: tracks unfolding a walk that bounced off a side wall between two looks, or not.

Run: ``python benchmarks/exp_moving_fold.py [--profile full] [--worlds 2000] [--skip 1000] [--seed 1]
[--planners discs,tracking] [--workers 2]`` (the disc planner needs its network:
``python -m husky_course train discs``).

A walking cylinder turns back at a side wall. When it turned between two of a track's looks, the
straight line through them is flat and the track reads standing;
:class:`~husky_course.planners.motion.Tracks` unfolds such a line once the walls' faces are known
(:func:`~husky_course.planners.walls.reflected_line`, ``TrackingConfig.bounce_gain``). Two variants
of each planner on the same worlds of the tuning set (evaluation set 1 by default; ``--skip`` passes
over its first worlds): ``straight`` (``bounce_gain`` None: every line straight, the planners
before the fold) and ``folded`` (the planner as it is). Each line gives the success rate with its
exact 95% interval and, for ``folded``, the worlds won only with it / only without.

Measured (full profile; throwaway runs of the same two variants): worlds 1,000-2,999 (``--skip 1000
--worlds 2000``), the disc planner 0.858 -> 0.861 (8 / 2), the tracker 0.759 -> 0.760 (7 / 4); worlds
3,000-4,999, used for nothing before, 0.832 -> 0.837 (10 / 1) and 0.736 -> 0.738 (6 / 3). Pooled: the
disc planner 18 / 3 (p = 0.001), the tracker 13 / 7 (p = 0.26, no gain shown).
"""

from __future__ import annotations

import argparse

import numpy as np
from exp_moving_start import paired_line  # benchmarks/, the script's own folder

from husky_course.config import get_profile, with_world
from husky_course.engines import map_tasks
from husky_course.evaluation.episodes import eval_world_seeds, run_episode
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator

VARIANTS = ("straight", "folded")


def episodes(task: tuple[str, str, str, list[int]]) -> list[bool]:
    """Did ``name`` in ``variant`` cross each of ``seeds`` (moving worlds, profile ``profile``)?"""
    name, variant, profile_name, seeds = task
    profile = with_world(get_profile(profile_name), "moving")
    learned = {"profile": profile} if name == "discs" else {}
    planner = make_planner(name, config=profile.sim, **learned)
    if variant == "straight":
        planner.map.motion.tracks.bounce_gain = None  # type: ignore[attr-defined]
    sim = FastSimulator(profile.sim)
    return [run_episode(planner, sim, s, profile.sim.max_primitives).success for s in seeds]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=1000)
    parser.add_argument("--skip", type=int, default=0, help="worlds of the set passed over first")
    parser.add_argument("--seed", type=int, default=1, help="evaluation set (1: the tuning set)")
    parser.add_argument("--planners", default="discs,tracking", help="any of discs, tracking")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    names = [n for n in args.planners.split(",") if n]
    if min(args.worlds, args.workers) < 1 or args.skip < 0 or not names or set(names) - {"discs", "tracking"}:
        parser.error(f"need --worlds, --workers >= 1, --skip >= 0, --planners of discs, tracking; got {args}")
    profile = get_profile(args.profile)
    seeds = [int(s) for s in eval_world_seeds(args.skip + args.worlds, args.seed)][args.skip:]
    print(f"{args.worlds} moving worlds of evaluation set {args.seed} "
          f"(after its first {args.skip}), profile {profile.name}:")
    for name in names:
        base = None
        for variant in VARIANTS:
            tasks = [(name, variant, profile.name, seeds[i : i + 10]) for i in range(0, len(seeds), 10)]
            won = np.array([w for part in map_tasks(episodes, tasks, workers=args.workers,
                                                       desc=f"{name}, {variant}") for w in part])
            print(paired_line(f"{name:9s} {variant:9s}", won, base), flush=True)
            base = won if base is None else base


if __name__ == "__main__":
    main()
