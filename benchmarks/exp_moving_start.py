"""Experiment: what the moving course's blind first decision costs (a look before the start).

Run: ``python benchmarks/exp_moving_start.py [--profile full] [--worlds 300] [--looks 0,1,2]
[--planners discs,tracking] [--seed 1]`` (the disc planner needs its network: ``python -m
husky_course train discs``).

On the moving course a planner reads motion off successive images, and the first decision has
one image only: every cylinder in view is a first sight, and the arrivals rule
(:mod:`husky_course.planners.arrivals`) has no earlier image to compare with. Here the planner is
also given ``looks`` images taken before the start, while the robot stands on the start line and
the cylinders walk (times ``-looks, ..., -1``): its map reads them as it reads any image, with a
step of no motion between them. That is a change of the course's protocol (its episodes start
with one image), not a planner: an analysis of how much of the first-sight loss is the start's,
which no planner that reads motion off its own images can recover within today's protocol.

Within today's protocol, ``--samples`` tries the planners' ``first_samples`` setting
(:class:`~husky_course.config.ArrivalsConfig`): at the first decision the first primitive is chosen
by its mean safe steps over draws of the course's motion model for the first sights in view. The
disc planner runs with its every-decision draws off (``samples`` 0), as when this was measured.

For each planner and each setting: the success rate on the tuning set (evaluation set 1 by
default) with its exact 95% interval, the paired count of worlds won only with it / only without
(against the plain planner), and for the plain planner how many failures were already fatal at
the first decision: the last state from which the true world (every cylinder, its motion) had a
way through, found by the oracle's lattice search, was the start.

Measured on 1,000 moving tuning worlds (full profile, ``--worlds 1000``): the disc planner 0.770;
one / two looks before the start 0.804 / 0.808 (worlds won only with / only without them: 73 / 39,
72 / 34); the first decision sampled 16 / 32 times 0.778 / 0.771 (15 / 7, 21 / 20). The tracker
0.735, sampled 16 times 0.728; on 300 worlds one look took it from 0.740 to 0.790. Of the disc
planner's 67 failures in the first 300 worlds, 12 were already fatal at the first decision.
"""

from __future__ import annotations

import argparse

import numpy as np
from exp_moving_failures import crossable  # benchmarks/, the script's own folder

from husky_course.config import get_profile, with_world
from husky_course.course.diagnosis import sign_test
from husky_course.evaluation.episodes import eval_world_seeds
from husky_course.evaluation.rollout import Rollout
from husky_course.evaluation.statistics import clopper_pearson
from husky_course.planners.base import Planner
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator


def run(planner: Planner, sim: FastSimulator, seed: int, looks: int, limit: int) -> tuple[bool, int | None]:
    """One episode with ``looks`` standing images before the start: ``(success, fatal step)``, the
    fatal step (the last from which the true world had a way through) only for a failure."""
    rollout = Rollout(planner, sim, seed, limit)
    world, pose = rollout.world, rollout.start
    for k in range(looks, 0, -1):  # the robot stands; the cylinders walk
        planner.map.add(sim.depth(pose[None], -float(k))[0])  # type: ignore[attr-defined]
        planner.map.move(0.0, 0.0)  # type: ignore[attr-defined]
    made = list(rollout)
    if not made[-1].result.collided:  # type: ignore[union-attr]
        return True, None
    ok = [d.step for d in made if crossable(sim, world, d.pose, d.step, limit - d.step)]
    return False, (max(ok) if ok else None)


def paired_line(label: str, won: np.ndarray, base: np.ndarray | None) -> str:
    """One printed line: ``label``, the success rate of ``won`` (per world) with its exact 95% interval,
    and against ``base`` (the same worlds; none for the baseline itself) the worlds won only with /
    only without and the sign test's p."""
    lo, hi = clopper_pearson(int(won.sum()), len(won))
    line = f"  {label} {won.mean():.3f} [{lo:.3f}, {hi:.3f}]"
    if base is not None:
        only_with, only_without, p = sign_test(won, base)
        line += f"   worlds won only with: {only_with}, only without: {only_without}, p = {p:.2f}"
    return line


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=300)
    parser.add_argument("--seed", type=int, default=1, help="evaluation set (1: the tuning set)")
    parser.add_argument("--looks", default="0,1,2", help="comma-separated numbers of looks before the start")
    parser.add_argument("--samples", default="16,32",
                        help="comma-separated first_samples settings to try, with no look before the start")
    parser.add_argument("--planners", default="discs,tracking", help="comma-separated: discs, tracking")
    args = parser.parse_args()
    looks = [int(k) for k in args.looks.split(",")]
    samples = [int(k) for k in args.samples.split(",") if k]
    if any(k < 0 for k in looks + samples) or 0 not in looks:
        parser.error(f"--looks must include 0 and be 0 or more, --samples 0 or more: got {args.looks!r}, "
                     f"{args.samples!r}")
    profile = with_world(get_profile(args.profile), "moving")
    sim, limit = FastSimulator(profile.sim), profile.sim.max_primitives
    seeds = [int(s) for s in eval_world_seeds(args.worlds, args.seed)]
    print(f"moving course, {args.worlds} worlds of evaluation set {args.seed}, profile {profile.name}:")
    for name in args.planners.split(","):
        extra = {"profile": profile, "samples": 0} if name == "discs" else {}  # its every-decision draws off
        base = None
        for k, n in [(k, 0) for k in sorted(looks)] + [(0, n) for n in samples]:
            planner = make_planner(name, config=profile.sim, first_samples=n, **extra)
            runs = [run(planner, sim, s, k, limit) for s in seeds]
            won = np.array([ok for ok, _ in runs])
            what = f"looks before the start: {k}" if not n else f"first decision sampled: {n}"
            print(paired_line(f"{name:9s} {what:30s}", won, base), flush=True)
            base = won if base is None else base
            if k == n == 0:
                fatal = [f for ok, f in runs if not ok]
                at_start = sum(f == 0 for f in fatal)
                print(f"  {'':9s} of its {len(fatal)} failures, {at_start} already fatal at the first "
                      "decision", flush=True)


if __name__ == "__main__":
    main()
