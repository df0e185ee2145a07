"""Experiment: the moving course's walking discs and walking points, bouncing off the side walls or not.

Run: ``python benchmarks/exp_moving_walls.py [--profile full] [--worlds 1000] [--skip 0] [--seed 1]
[--planners discs,tracking]`` (the disc planner needs its network: ``python -m husky_course train discs``).

A walking cylinder of the moving course reflects off the side walls. The disc planner reads the
walls' faces off the points it has seen (:mod:`husky_course.planners.walls`) and lets its walking
discs bounce off them, in its map's dead reckoning and in its space-time search; the tracker's
walking points do the same (``--planners``). Three variants on
the same worlds of the tuning set (evaluation set 1 by default; ``--skip`` passes over its first
worlds, for a second slice that confirms a first one):

* ``bouncing, faces read``: the planner as it is;
* ``bouncing, faces told``: the faces placed from the true start (privileged: what reading them
  costs);
* ``straight``: no faces, every walk a straight line (the planner before the walls).

Each line gives the success rate with its exact 95% interval and the paired count of worlds won
only with the variant / only without, against ``straight``.

Measured (full profile): worlds 0-999 straight 0.770, bouncing 0.780 either way (12 / 2, p = 0.01);
worlds 1,000-1,999 (``--skip 1000``) 0.766 and 0.776 (13 / 3, p = 0.02): the faces it reads won and
lost the same worlds as the faces told (before the first sights' column evidence,
:meth:`~husky_course.planners.arrivals.Arrivals.read`). The tracker's walking points bounce by the
same rule (``WallsConfig.tracker``): 0.735 -> 0.741 (8 / 2) and 0.756 -> 0.761 (9 / 4).
"""

from __future__ import annotations

import argparse

import numpy as np
from exp_moving_start import paired_line  # benchmarks/, the script's own folder

from husky_course.config import Profile, get_profile, with_world
from husky_course.evaluation.episodes import eval_world_seeds
from husky_course.planners.base import Planner, episode_start
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator

VARIANTS = ("straight", "bouncing, faces read", "bouncing, faces told")


def run(planner: Planner, sim: FastSimulator, seed: int, limit: int, variant: str) -> bool:
    """One episode of ``planner`` (the disc planner or the tracker) in ``variant`` (module docstring):
    did it cross?"""
    world = sim.load(seed)
    pose = world.start.copy()
    planner.reset(episode_start(planner, sim, seed, pose, limit))
    disc_map = planner.map  # type: ignore[attr-defined]
    width = world.config.width
    disc_map.width = np.inf if variant == "straight" else width  # an infinite course has no faces
    told = variant == "bouncing, faces told"
    obs = sim.depth(pose[None], 0.0)[0]
    for step in range(limit):
        if told:  # the faces in the robot's frame, from its true place (privileged)
            disc_map.faces = (-width / 2 - pose[1], width / 2 - pose[1])
        action = planner.act(obs, pose)
        result = sim.apply(pose, action, step)
        if told:  # for the walk of this step (dead reckoning shifts them into the next frame)
            disc_map.faces = (-width / 2 - pose[1], width / 2 - pose[1])
        planner.observe(action, None)
        if result.collided:
            return False
        pose = result.pose
        obs = sim.depth(pose[None], step + 1)[0]
    return True


def slice_setup(doc: str) -> tuple[list[str], Profile, FastSimulator, int, list[int]]:
    """The command line of a moving benchmark on a slice of worlds (this one's, and
    ``exp_moving_evidence.py``'s): ``(planners, profile, simulator, primitives per episode, world seeds)``,
    after printing which worlds."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=1000)
    parser.add_argument("--skip", type=int, default=0, help="worlds of the set passed over first")
    parser.add_argument("--seed", type=int, default=1, help="evaluation set (1: the tuning set)")
    parser.add_argument("--planners", default="discs,tracking", help="any of discs, tracking")
    args = parser.parse_args()
    names = [n for n in args.planners.split(",") if n]
    if args.worlds < 1 or args.skip < 0 or not names or set(names) - {"discs", "tracking"}:
        parser.error(f"need --worlds >= 1, --skip >= 0 and --planners among discs, tracking; got {args}")
    profile = with_world(get_profile(args.profile), "moving")
    seeds = [int(s) for s in eval_world_seeds(args.skip + args.worlds, args.seed)][args.skip:]
    print(f"{args.worlds} moving worlds of evaluation set {args.seed} "
          f"(after its first {args.skip}), profile {profile.name}:")
    return names, profile, FastSimulator(profile.sim), profile.sim.max_primitives, seeds


def main() -> None:
    names, profile, sim, limit, seeds = slice_setup(__doc__)
    for name in names:
        base = None
        for variant in VARIANTS:
            learned = {"profile": profile} if name == "discs" else {}
            planner = make_planner(name, config=profile.sim, **learned)
            won = np.array([run(planner, sim, s, limit, variant) for s in seeds])
            print(paired_line(f"{name:9s} {variant:22s}", won, base), flush=True)
            base = won if base is None else base


if __name__ == "__main__":
    main()
