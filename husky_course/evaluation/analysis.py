"""Why did an episode end the way it did? Failure analysis of recorded episodes."""

from __future__ import annotations

import numpy as np

from ..sim.base import Simulator
from ..sim.fast import FastSimulator
from ..sim.world import World
from .episodes import Episode


def collision_cause(episode: Episode, sim: Simulator) -> str:
    """Why an episode's last primitive collided, seen from the decision pose.

    ``"wall"`` (a side wall), ``"out of view"`` (the obstacle hit was not rendered by any image
    column when the primitive was chosen: outside the field of view, hidden behind a nearer one,
    between two columns or beyond ``far``; :meth:`~husky_course.sim.fast.FastSimulator.visible_obstacles`)
    or ``"in view"``.
    """
    if not episode.collided:
        raise ValueError("the episode did not collide")
    hit, world, t = obstacle_hit(episode, sim)
    if hit < 0:
        return "wall"
    eyes = sim if isinstance(sim, FastSimulator) else FastSimulator(sim.config)
    eyes.load(world)
    return "in view" if hit in eyes.visible_obstacles(episode.poses[-2], t) else "out of view"


def obstacle_hit(episode: Episode, sim: Simulator) -> tuple[int, World, int]:
    """``(index, world, step)``: the cylinder a colliding episode's last primitive touched first
    (``-1`` for a side wall), its world, and the step that primitive started at (its time)."""
    if not episode.collided:
        raise ValueError("the episode did not collide")
    world = sim.load(episode.world_seed)
    t = episode.n_prims - 1
    path = sim.library.path_from(episode.poses[-2], episode.actions[-1])
    k = sim.contact_along(path, t)
    hit_pose, when = path[k], t + k / max(len(path) - 1, 1)
    radius = world.config.robot_radius
    if abs(hit_pose[1]) + radius > world.wall_y:
        return -1, world, t
    obs = world.obstacles_at(when)
    gap = np.hypot(*(obs[:, :2] - hit_pose[:2]).T) - obs[:, 2] - radius
    return int(np.argmin(gap)), world, t
