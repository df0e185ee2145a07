"""Experiment: where do the moving course's camera-based planners fail, and what did they know?

Run: ``python benchmarks/exp_moving_failures.py [--profile full] [--worlds 200]
[--planner tracking|memory|discs] [--told RULE]``.

On the tuning set (evaluation set 1) of the moving course. For every episode that ends in a
collision on a world the oracle crosses, it finds the **fatal decision**: the last step from
which the true world (every cylinder, its motion) still had a way through, found by the oracle's
lattice search from the pose and time of that step. It then asks what the planner knew there of
the cylinder it hit, from its tracks (:class:`husky_course.planners.motion.Tracks`; the tracking
planner, the disc planner and the moving-trained student keep the same ones):

* *unseen*: no image had rendered it yet, split by where it was at the fatal decision: *beside
  the view* (its bearing outside the field of view), *beyond range* (further than the far plane)
  or *hidden* (in the view, behind something else);
* *seen, not in its tracks*: rendered, but no track lies near it (occluded, merged, forgotten);
* *first sight*: a moving cylinder seen by one image only, so its motion was unknown;
* *motion read right / wrong*: a moving cylinder with a track whose velocity is within 0.1 m per
  step of the truth, or not;
* *standing, tracked*: a standing cylinder the planner had located;
* *a side wall*, or a world *the oracle finds no way through*.

Printed: the success rate and the failures per kind. What the student would gain from better
motion estimates is in the first four; the last is the planner's own precision.

The disc planner's failures are also split by what its **disc map** held of that cylinder at the
fatal decision (a disc within 0.3 m of its surface, ``ON_CYLINDER``): a disc, read as a first
sight or tracked, standing or walking, its velocity right or wrong (within 0.1 m per step); no
disc any more, because an image saw through its place, a new disc landed on it, or it drifted off
the cylinder (a wrong velocity) or fell behind; or never a disc, with the map's scan points on it
(the network read it as a wall) or nothing. ``--told RULE`` runs the privileged ``told-discs``
reference instead (:data:`~husky_course.planners.reference.TOLD_RULES`), to see what is left once
its map is told that much of the truth.

Measured (full profile, ``--planner discs --worlds 500``, tuning worlds 0-499; the disc planner of library
fingerprint ``42a1261e60447925``; 285 s on 2 cores): success 0.854; of its 73 failures, 7 on worlds the
oracle finds no way through and 3 at a side wall. What it knew at the fatal decision of the cylinder it hit:
standing, tracked 18; unseen, beyond range 11 (at the fatal decision it lay beyond the camera's range);
motion read wrong 10, right 10; first sight 8; seen, not in its tracks 4; unseen, hidden 2. What its disc
map held of it: a standing cylinder's disc, tracked and right, 13 (its disc read standing, within
``ON_CYLINDER`` of it: what misled those choices was another cylinder's reading, this disc's place by up to
that much, or what no image had shown; ``exp_moving_fatal.py`` replays such decisions); a walker's tracked
disc read standing 9; unseen 7 walkers and 6 standing; a walker's tracked disc walking at the right speed 6;
a first sight's disc read standing, 5 walkers and 5 standing ones; a standing cylinder's tracked disc read
walking 4; the rest (5 kinds, 8 failures) 2 or fewer each.
The figures above were measured before the planner broke the last ties by its draws' options
(``ArrivalsConfig.ties`` "options"). With them (fingerprint ``28e5ef29ec515817``, the same command, 476 s):
success 0.864; of its 68 failures, 7 on worlds the oracle finds no way through and 1 at a side wall. What it
knew: standing, tracked 14; first sight 9; unseen, beyond range 9; motion read right 9, wrong 9; seen, not in
its tracks 6; unseen, hidden 4. What its disc map held: a standing cylinder's disc, tracked and right, 11; a
walker's tracked disc read standing 9; unseen 8 standing and 5 walkers; a first sight's disc read standing, 7
walkers and 4 standing ones; a walker's tracked disc walking at the right speed 5, at a wrong one 3; a
walker's disc drifted off or fallen behind 4; the rest (3 kinds) 2 or fewer each.
With the ghosts (fingerprint ``ccc53ec5b3102cd9``, commit 8d8f781's library; the same command, about 14
minutes on 2 cores beside another run): success 0.866; of its 67 failures, 7 on worlds the oracle finds no
way through and 2 at a side wall. What it knew: standing, tracked 12; unseen, beyond range 10; motion read
right 10; first sight 9; motion read wrong 7; seen, not in its tracks 6; unseen, hidden 4. What its disc map
held: a standing cylinder's disc, tracked and right, 10; unseen 9 standing and 5 walkers; a walker's tracked
disc read standing 7; a walker's first sight read standing 7; a walker's tracked disc walking at the right
speed 6; a standing first sight read standing 4; a walker's disc drifted off or fallen behind 4; at a wrong
speed 3; the rest (3 kinds) 2 or fewer each (a disc an image saw through: 1). Cylinders no image had shown
at the fatal decision are now the largest kind (14 of 58); drawing them from the course's prior
(``exp_moving_unseen.py``) did not show a gain.
"""

from __future__ import annotations

import argparse
import math
from collections import Counter

import numpy as np

from husky_course.config import CameraConfig, OracleConfig, get_profile, with_world
from husky_course.evaluation.episodes import eval_world_seeds
from husky_course.evaluation.rollout import Rollout
from husky_course.planners.base import Planner
from husky_course.planners.moving_discs import WalkingDiscMap
from husky_course.planners.reference import ON_CYLINDER, TOLD_RULES, truth_in_frame
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator
from husky_course.sim.lattice import expand, survival
from husky_course.sim.world import World

FOV_HALF_DEG, FAR = CameraConfig.fov_deg / 2, CameraConfig.far


def crossable(sim: FastSimulator, world: World, pose: np.ndarray, t: int, steps: int) -> bool:
    """Whether the true world still has a way through from ``pose`` at time ``t`` for ``steps`` steps."""
    lattice = expand(world, sim.library, pose, steps, OracleConfig.cap, t)
    return int(survival(lattice).max()) == steps


def kind(world: World, j: int, t: int, pose: np.ndarray, first_seen: int | None, tracks: list) -> str:
    """What the planner knew at step ``t`` of cylinder ``j`` (see the module)."""
    if first_seen is None or first_seen > t:
        rel = world.obstacles_at(float(t))[j, :2] - pose[:2]
        if abs(math.degrees(math.atan2(rel[1], rel[0]))) > FOV_HALF_DEG:
            return "unseen, beside the view"
        return "unseen, beyond range" if math.hypot(*rel) > FAR else "unseen, hidden"
    moving = world.speeds[j] != 0
    rel = world.obstacles_at(float(t))[j, :2] - pose[:2]
    near = [(v, looks) for (y, v), x, looks in tracks if abs(x - rel[0]) < 0.4 and abs(y - rel[1]) < 0.4]
    if not near:
        return "seen, not in its tracks"
    v, looks = near[-1]
    if not moving:
        return "standing, tracked" if abs(v) < 0.1 else "motion read wrong"
    if looks == 1:
        return "first sight"
    truth = float(world.obstacle_y(np.array([j]), t + 1.0)[0] - world.obstacle_y(np.array([j]), float(t))[0])
    return "motion read right" if abs(v - truth) < 0.1 else "motion read wrong"


def surface_gap(points: np.ndarray, cylinder: np.ndarray) -> np.ndarray:
    """Distance ``(m,)`` from each of ``points (m, 2+)`` to the surface of ``cylinder (x, y, r)``."""
    return np.hypot(points[:, 0] - cylinder[0], points[:, 1] - cylinder[1]) - cylinder[2]


def map_knew(log: list, j: int, fatal: int, world: World) -> str:
    """What the disc map held of cylinder ``j`` at step ``fatal``, from ``log`` (per step: the pose,
    the map's discs, speeds and first-sight marks, its scan points, and the discs each rule dropped)."""
    pose, discs, speeds, fresh, walls, _ = log[fatal]
    cyl, vy = truth_in_frame(world, pose, float(fatal))
    near = np.flatnonzero(surface_gap(discs, cyl[j]) < ON_CYLINDER)
    if len(near):
        i = near[0]
        right = "right" if abs(speeds[i] - vy[j]) <= 0.1 else "wrong"
        return (f"a disc, {'first sight' if fresh[i] else 'tracked'}, "
                f"{'walking' if speeds[i] else 'standing'}, {right}")

    def on(discs: np.ndarray, at: np.ndarray) -> bool:
        return bool((surface_gap(discs, at[j]) < ON_CYLINDER).any())

    for step in range(fatal, -1, -1):  # back in time: the last moment the map lost a disc on it, and why
        at = truth_in_frame(world, log[step][0], float(step))[0]
        if step < fatal and on(log[step][1], at):  # held after this step's image: lost between images
            return "no disc any more: drifted off, or fell behind"
        for why, lost in log[step][5].items():  # dropped when this step's image came
            if on(lost, at):
                return f"no disc any more: {why}"
    points = bool((surface_gap(walls, cyl[j]) < 0.15).any())
    return "never a disc, " + ("scan points on it" if points else "nothing on it")


def recording(planner: Planner) -> list:
    """Make ``planner``'s disc map record, per :meth:`~husky_course.planners.discs.DiscMap.add`, the
    remembered discs its rules drop; returns the list each step's drops are appended to."""
    drops: list = []
    base = type(planner.map)  # type: ignore[attr-defined]

    class Recorded(base):  # type: ignore[misc, valid-type]
        def forgotten(self, d: np.ndarray, new: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            seen, landed = super().forgotten(d, new)
            lost = {"seen through": seen, "a new disc landed on it": landed & ~seen}
            drops.append({why: self.discs[mask] for why, mask in lost.items()})
            return seen, landed

    planner.map.__class__ = Recorded  # type: ignore[attr-defined]
    return drops


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=200)
    parser.add_argument("--planner", default="tracking", choices=("tracking", "memory", "discs"))
    parser.add_argument("--told", choices=TOLD_RULES, help="the disc planner told this much (privileged)")
    args = parser.parse_args()
    if args.told and args.planner != "discs":
        parser.error("--told needs --planner discs")
    profile = with_world(get_profile(args.profile), "moving")
    sim, limit = FastSimulator(profile.sim), profile.sim.max_primitives
    if args.planner == "tracking":
        planner = make_planner("tracking", config=profile.sim)
    elif args.told:
        planner = make_planner("told-discs", profile=profile, rule=args.told, config=profile.sim)
    elif args.planner == "discs":  # its discs walk on the course it is given
        planner = make_planner("discs", profile=profile, config=profile.sim)
    else:
        planner = make_planner("memory", profile=profile)
    disc_map = isinstance(planner.map, WalkingDiscMap)  # type: ignore[attr-defined]
    drops = recording(planner) if disc_map else []
    failures: Counter[str] = Counter()
    held: Counter[str] = Counter()  # the disc planner's: what its map held of the cylinder it hit
    successes = 0
    for seed in eval_world_seeds(args.worlds, 1):
        rollout = Rollout(planner, sim, int(seed), limit)
        world = rollout.world
        first: dict[int, int] = {}
        known: list[tuple[np.ndarray, list]] = []  # per step: the pose, the planner's tracks
        log: list = []  # the disc planner's map, per step (map_knew)
        for d in rollout:
            for j in sim.visible_obstacles(d.pose, float(d.step)).tolist():
                first.setdefault(j, d.step)
            if disc_map:
                m = planner.map  # type: ignore[attr-defined]
                log.append((d.pose.copy(), m.discs.copy(), m.speeds.copy(), m.fresh.copy(),
                            m.walls.points.copy(), drops[-1]))
            tracks = planner.map.motion.tracks  # type: ignore[attr-defined]
            lines = [(tracks.line(t), float(np.average(t[:, 1], weights=t[:, 3] ** -2.0)), len(t))
                     for t in tracks.tracks]
            known.append((d.pose.copy(), lines))
        step, result = d.step, d.result
        if not result.collided:
            successes += 1
            continue
        if not crossable(sim, world, world.start.copy(), 0, limit):
            failures["the oracle finds no way through"] += 1
            continue
        end, f = result.path[-1], len(result.path) / sim.library.local_paths.shape[1]
        at = world.obstacles_at(step + f)
        gaps = np.hypot(at[:, 0] - end[0], at[:, 1] - end[1]) - at[:, 2]
        j = int(np.argmin(gaps))
        if world.wall_y - abs(end[1]) < gaps[j]:
            failures["a side wall"] += 1
            continue
        fatal = max(s for s in range(step + 1) if crossable(sim, world, known[s][0], s, limit - s))
        failures[kind(world, j, fatal, known[fatal][0], first.get(j), known[fatal][1])] += 1
        if disc_map:
            seen = first.get(j) is not None and first[j] <= fatal
            walker = "walking" if world.speeds[j] != 0 else "standing"
            held[f"{walker}: " + (map_knew(log, j, fatal, world) if seen else "unseen")] += 1
    print(f"{planner.name} on {args.worlds} moving tuning worlds: success {successes / args.worlds:.3f}")
    print("failures by what it knew, at the fatal decision, of the cylinder it hit:")
    for name, count in failures.most_common():
        print(f"  {count:4d}  {name}")
    if disc_map:
        print("the same failures (but walls and worlds without a way through) by what its disc map held of "
              "the cylinder it hit:")
        for name, count in held.most_common():
            print(f"  {count:4d}  {name}")


if __name__ == "__main__":
    main()
