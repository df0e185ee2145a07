"""Why did an episode end the way it did? Failure analysis of recorded episodes."""

from __future__ import annotations

import numpy as np

from ..sim.base import Simulator
from .episodes import Episode


def collision_cause(episode: Episode, sim: Simulator) -> str:
    """Why an episode's last primitive collided, seen from the decision pose.

    ``"wall"`` (a side wall), ``"out of view"`` (the obstacle hit was outside the camera's
    horizontal field of view when the primitive was chosen) or ``"in view"``.
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
    ox, oy = world.obstacles[int(np.argmin(gap)), :2] - decision[:2]
    bearing = abs(np.degrees(np.arctan2(oy, ox) - decision[2]))
    half_fov = sim.config.camera.fov_deg / 2.0
    return "out of view" if bearing > half_fov else "in view"
