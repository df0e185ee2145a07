"""Experiment: how well do successive depth scans tell a cylinder's motion, and what is it worth?

Run: ``python benchmarks/exp_moving_tracker.py [--profile full] [--worlds 200] [--skip-planners]``.

All on the tuning set (evaluation set 1) of the moving course, nothing trained.

1. **Estimation.** Along the oracle's own runs, every point of every scan after the first gets an
   estimated lateral velocity from the previous scan; the truth is the displacement over that step
   of the cylinder the point lies on. Printed for moving and standing cylinders, three estimators:
   two images compared, each piece located by the mean of its points (the course's first
   estimator) or by the fitted circle of :func:`husky_course.planners.pieces.piece_centre` (with
   second-look averaging), and the tracks of :class:`husky_course.planners.motion.Tracks` (fitted
   circles followed over four looks, a weighted line through them), the one the planners use.
2. **What it is worth.** The mapping planner with motion (:mod:`husky_course.planners.tracking`)
   with its own estimate, and with the true velocity of every point it sees (privileged, the
   ceiling of a perfect estimate for this planner), beside the mapping planner (no motion), the
   "seen, with motion" analysis planner (every cylinder seen, exactly) and
   :class:`~husky_course.planners.reference.SecondLookPlanner`, the same with a cylinder's motion known
   only from its second image on (what reading motion off images could reach with perfect
   perception); then the horizon sweep of the tracker.
"""

from __future__ import annotations

import argparse

import numpy as np

from husky_course.config import get_profile, with_world
from husky_course.evaluation.episodes import eval_world_seeds, evaluate
from husky_course.planners.base import episode_start
from husky_course.planners.mapping import MappingPlanner
from husky_course.planners.motion import MotionMemory
from husky_course.planners.oracle import OraclePlanner
from husky_course.planners.perception import DepthScan
from husky_course.planners.pieces import piece_centre, segments
from husky_course.planners.reference import SecondLookPlanner, SeenMotionPlanner
from husky_course.planners.tracking import TrackingPlanner
from husky_course.sim.fast import FastSimulator
from husky_course.sim.world import World


def lateral_velocities(
    previous: np.ndarray,
    current: np.ndarray,
    max_step: float,
    previous_v: np.ndarray | None = None,
    camera_x: float = 0.45,
    radius: float = 0.25,
    spacing: float = 0.0,
    x_gate: float = 0.3,
    gap: float = 0.3,
) -> np.ndarray:
    """Estimated lateral displacement per step ``(m,)`` of every point of ``current``: the two-image
    estimator the course used first (each piece matched to the previous image's nearest piece, its
    displacement averaged with the previous estimate), kept here for the comparison (the planners
    use :class:`husky_course.planners.motion.Tracks`).

    ``previous`` and ``current`` are scans in the *current* robot frame, ``previous_v`` the
    velocities estimated for ``previous`` (or ``None``); ``max_step`` bounds how far a piece can
    move across in one step (a match further away is no match).
    """
    v = np.zeros(len(current))
    before = segments(previous, gap, spacing)
    if not before or not len(current):
        return v
    centres = np.array([piece_centre(previous[idx], camera_x, radius) for idx in before])
    known = np.array([0.0 if previous_v is None else float(np.mean(previous_v[idx])) for idx in before])
    for idx in segments(current, gap, spacing):
        cx, cy = piece_centre(current[idx], camera_x, radius)
        dy = cy - centres[:, 1]
        ok = np.flatnonzero((np.abs(centres[:, 0] - cx) < x_gate) & (np.abs(dy) <= max_step))
        if ok.size:
            i = ok[np.argmin(np.abs(dy[ok] - known[ok]))]
            v[idx] = dy[i] if known[i] == 0 else (dy[i] + known[i]) / 2
    return v


def truth(world: World, t: int, pose: np.ndarray, now: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For scan points ``now`` (robot frame) at time ``t``: which lie on a cylinder, and its
    displacement along ``y`` from ``t`` to ``t + 1``."""
    obs = world.obstacles_at(float(t))
    at = now[:, :2] + pose[:2]
    gap = np.hypot(at[:, None, 0] - obs[None, :, 0], at[:, None, 1] - obs[None, :, 1]) - obs[None, :, 2]
    j = gap.argmin(1)
    dy = world.obstacle_y(j, np.full(len(j), t + 1.0)) - world.obstacle_y(j, np.full(len(j), float(t)))
    return gap.min(1) < 0.1, np.where(world.speeds[j] != 0, dy, 0.0)


def estimation(profile, worlds: int) -> None:  # type: ignore[no-untyped-def]
    sim, scan = FastSimulator(profile.sim), DepthScan(profile.sim)
    mean_way = MotionMemory(profile.sim)
    rows: dict[str, list] = {"mean of the points": [], "fitted circle": [], "tracks": []}
    for seed in eval_world_seeds(worlds, 1):
        world = sim.load(int(seed))
        pose, oracle = world.start.copy(), OraclePlanner()
        oracle.reset(episode_start(oracle, sim, int(seed), pose, profile.sim.max_primitives))
        fitted, previous, v_pair = MotionMemory(profile.sim), np.empty((0, 2)), np.empty(0)
        for t in range(profile.sim.max_primitives):
            obs = sim.depth(pose[None], t)[0]
            now = scan(obs)
            on, dy = truth(world, t - 1, pose, now)  # the step that ended now
            v_mean = lateral_velocities(previous, now, mean_way.max_step, radius=0.0, x_gate=0.5)
            v_pair = lateral_velocities(
                previous, now, fitted.max_step, v_pair, fitted.camera_x, fitted.radius, fitted.spacing
            )
            v_fit = fitted.update(now)
            if t > 0:
                moving = dy[on] != 0
                rows["mean of the points"].append(np.c_[v_mean[on], dy[on], moving])
                rows["fitted circle"].append(np.c_[v_pair[on], dy[on], moving])
                rows["tracks"].append(np.c_[v_fit[on], dy[on], moving])
            action = oracle.act(obs, pose.copy())
            result = sim.apply(pose, action, t)
            end = sim.library.local_paths[action, -1]
            previous = now - end[:2]
            fitted.move(float(end[0]), float(end[1]))
            pose = result.pose
            if result.collided:
                break
    print(f"velocity estimates on {worlds} tuning worlds, along the oracle's runs (m per step):")
    for name, parts in rows.items():
        r = np.concatenate(parts)
        err, moving = np.abs(r[:, 0] - r[:, 1]), r[:, 2] > 0
        matched = moving & (r[:, 0] != 0)
        print(
            f"  {name:20s} moving: median error when matched {np.median(err[matched]):.3f}, "
            f"within 0.1 {np.mean(err[matched] < 0.1):.3f}, unmatched {np.mean(r[moving, 0] == 0):.3f}"
            f" | standing: mean |v| {err[~moving].mean():.3f}, over 0.1 {np.mean(err[~moving] > 0.1):.3f}"
        )


class TrueMotion(TrackingPlanner):
    """Privileged: the tracker with every seen point's true velocity (an analysis tool)."""

    privileged = True
    name = "mapping, with true motion of what it sees"

    def reset(self, start):  # type: ignore[no-untyped-def]
        super().reset(start)
        self._world, self._t = start.sim.world, 0
        walking = self.map
        outer = self

        def update(now: np.ndarray) -> np.ndarray:
            on, dy = truth(outer._world, outer._t, outer._pose, now)
            outer._t += 1
            walking.motion.tracks.fresh = np.zeros(len(now), bool)  # the truth: no motion is unknown
            return np.where(on, dy, 0.0)

        walking.motion.update = update  # type: ignore[method-assign]

    def act(self, obs, pose=None):  # type: ignore[no-untyped-def]
        self._pose = pose
        return super().act(obs, pose)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=200)
    parser.add_argument("--skip-planners", action="store_true")
    args = parser.parse_args()
    profile = with_world(get_profile(args.profile), "moving")
    estimation(profile, min(args.worlds, 100))
    if args.skip_planners:
        return
    print(f"success on {args.worlds} tuning worlds (evaluation set 1):")
    sim = profile.sim
    planners = [MappingPlanner(sim), TrackingPlanner(sim), TrueMotion(sim), SeenMotionPlanner()]
    planners += [SecondLookPlanner(), SecondLookPlanner(widen=1), SecondLookPlanner(widen=2)]
    planners += [TrackingPlanner(sim, horizon=h) for h in (3, 4, 6, 8)]
    for planner in planners:
        r = evaluate(planner, args.worlds, 1, config=sim, progress=False, workers=2)
        lo, hi = r.success_ci95
        tracker = isinstance(planner, TrackingPlanner)
        label = planner.name + (f" (horizon {planner.horizon})" if tracker else "")
        print(f"  {label:58s} {r.success_rate:.3f} [{lo:.3f}, {hi:.3f}]  {r.ms_per_decision:.0f} ms/decision")


if __name__ == "__main__":
    main()
