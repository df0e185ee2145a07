"""Why did an episode end the way it did? Failure analysis of recorded episodes."""

from __future__ import annotations

import numpy as np

from ..sim.base import Simulator
from ..sim.fast import FastSimulator
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
    world = sim.load(episode.world_seed)
    decision = episode.poses[-2]
    path = sim.library.path_from(decision, episode.actions[-1])
    hit_pose = path[sim.contact_along(path)]
    radius = world.config.robot_radius
    if abs(hit_pose[1]) + radius > world.wall_y:
        return "wall"
    gap = np.hypot(*(world.obstacles[:, :2] - hit_pose[:2]).T) - world.obstacles[:, 2] - radius
    eyes = sim if isinstance(sim, FastSimulator) else FastSimulator(sim.config)
    eyes.load(world)
    return "in view" if int(np.argmin(gap)) in eyes.visible_obstacles(decision) else "out of view"
