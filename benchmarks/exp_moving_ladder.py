"""Experiment: how far would perfect motion estimates take the moving course's camera-based planners?

Run: ``python benchmarks/exp_moving_ladder.py [--profile full] [--worlds 200]`` (the memory
student's rows need the moving student trained: ``python -m husky_course train memory --world moving``;
``HUSKY_ARTIFACTS`` may point at a store that has it).

On the tuning set (evaluation set 1) of the moving course. The tracker
(:mod:`husky_course.planners.tracking`) and the moving-trained memory student
(:mod:`husky_course.planners.memory`) both plan on a walking map
(:class:`~husky_course.planners.motion.WalkingMap`) whose points carry velocities read off
successive images. Here the map is *told* the true velocities (privileged, an analysis tool),
in rungs of what a velocity oracle may give away:

* ``estimated``: nothing (the planner as it is);
* ``tracked``: the true velocity for the current scan's points whose track has at least two
  looks (where the tracks think they know the motion), 0 where they think it a first sight;
* ``second image``: the true velocity for every map point, remembered or new, on a cylinder some
  earlier image has rendered, 0 on one seen for the first time: the most any estimator reading
  motion off images could know, with the planner's own map geometry;
* ``always``: the true velocity for every map point on a cylinder, first sight included (beyond
  any camera).

A map point belongs to the cylinder whose surface is within 0.3 m of it (else it is a wall and
stands). Printed beside them, on the same worlds: the privileged planners with perfect perception
(:class:`~husky_course.planners.reference.SecondLookPlanner`,
:class:`~husky_course.planners.reference.SeenMotionPlanner`) and the oracle, with 90% of its success
(issue 14's goal, there stated on the reporting set).
"""

from __future__ import annotations

import argparse

import numpy as np

from husky_course.config import get_profile, with_world
from husky_course.evaluation.episodes import evaluate
from husky_course.planners.base import EpisodeStart, Planner
from husky_course.planners.motion import WalkingMap
from husky_course.planners.oracle import OraclePlanner
from husky_course.planners.reference import SecondLookPlanner, SeenMotionPlanner
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator

RULES = ("estimated", "tracked", "second image", "always")
ON_CYLINDER = 0.3  #: a map point within this of a cylinder's surface is on it (m)


class InformedMap(WalkingMap):
    """A walking map whose velocities are overwritten by the truth, as ``rule`` allows (module)."""

    def __init__(self, inner: WalkingMap, rule: str) -> None:
        self.__dict__.update(inner.__dict__)
        self.rule = rule
        self.sim: FastSimulator | None = None
        self.pose, self.time, self.before = np.zeros(3), 0.0, np.zeros(0, int)

    def add(self, obs: np.ndarray) -> np.ndarray:
        v = super().add(obs)
        if self.rule == "estimated":
            return v
        assert self.sim is not None and self.sim.world is not None
        world, (px, py, yaw) = self.sim.world, self.pose
        now, later = world.obstacles_at(self.time), world.obstacles_at(self.time + 1.0)
        c, s = np.cos(yaw), np.sin(yaw)  # the map is in the robot's frame
        rx = c * (now[:, 0] - px) + s * (now[:, 1] - py)
        ry = -s * (now[:, 0] - px) + c * (now[:, 1] - py)
        vy = -s * (later[:, 0] - now[:, 0]) + c * (later[:, 1] - now[:, 1])
        points = self.points if self.rule != "tracked" else self.points[: len(v)]
        gap = np.hypot(points[:, :1] - rx, points[:, 1:2] - ry) - now[:, 2]
        j = np.argmin(gap, axis=1)
        truth = np.where(gap[np.arange(len(j)), j] < ON_CYLINDER, vy[j], 0.0)
        if self.rule == "tracked":
            self.velocity[: len(v)] = np.where(self.fresh[: len(v)], 0.0, truth)
        elif self.rule == "second image":
            self.velocity = np.where(np.isin(j, self.before), truth, 0.0)
        else:
            self.velocity = truth
        return self.velocity[: len(v)].copy()


class Informed(Planner):
    """A camera-based planner whose walking map is told true velocities by ``rule`` (privileged)."""

    privileged = True

    def __init__(self, inner: Planner, rule: str) -> None:
        super().__init__()
        self.inner, self.rule = inner, rule
        self.name = f"{inner.name}, velocities {rule}"
        self.map = inner.map = InformedMap(inner.map, rule)  # type: ignore[attr-defined]
        self._seen: set[int] = set()

    def reset(self, start: EpisodeStart) -> None:
        super().reset(start)
        self.inner.reset(start)
        self.map.sim = FastSimulator(start.sim.config)
        self.map.sim.load(start.sim.world)
        self.map.time, self._seen = 0.0, set()

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        assert pose is not None and self.map.sim is not None
        self.map.pose, self.map.before = np.asarray(pose, float), np.array(sorted(self._seen), int)
        self._seen |= set(self.map.sim.visible_obstacles(pose, self.map.time).tolist())
        return self.inner.act(obs)

    def observe(self, action: int, obs_next: np.ndarray | None) -> None:
        self.inner.observe(action, obs_next)
        self.map.time += 1.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=200)
    args = parser.parse_args()
    profile = with_world(get_profile(args.profile), "moving")
    sim = profile.sim
    planners: list[Planner] = []
    for name in ("tracking", "memory"):
        for rule in RULES:
            kwargs = {"profile": profile} if name == "memory" else {"config": sim}
            inner = make_planner(name, **kwargs)
            planners.append(Informed(inner, rule))
    planners += [SecondLookPlanner(), SeenMotionPlanner(), OraclePlanner()]
    print(f"success on {args.worlds} moving tuning worlds (evaluation set 1), profile {profile.name}:")
    oracle = 0.0
    for planner in planners:
        r = evaluate(planner, args.worlds, 1, config=sim, progress=False, workers=2)
        lo, hi = r.success_ci95
        print(f"  {planner.name:58s} {r.success_rate:.3f} [{lo:.3f}, {hi:.3f}]", flush=True)
        oracle = r.success_rate if isinstance(planner, OraclePlanner) else oracle
    goal = profile.eval.moving_goal
    print(f"  {f'{goal:.0%} of the oracle (the goal)':58s} {goal * oracle:.3f}")


if __name__ == "__main__":
    main()
