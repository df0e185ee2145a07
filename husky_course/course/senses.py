"""Chapter 11's measurements of a real robot's senses: repeated views, dead reckoning, the noise sweep.

The models themselves are in :mod:`husky_course.config.sensing` (the figures) and
:mod:`husky_course.sim.sensing` (the draws); this module only looks at what they do.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..config import Profile, SensingConfig, with_sensing
from ..evaluation.episodes import Episode
from ..sim.base import Simulator
from ..sim.camera import denormalize_depth
from ..sim.primitives import PrimitiveLibrary

#: the noise levels chapter 11 sweeps (times the realistic figures)
LEVELS = (0.0, 0.5, 1.0, 2.0)


def camera_only(sensing: SensingConfig) -> SensingConfig:
    """``sensing`` with ideal wheels (the camera's noise alone)."""
    return replace(sensing, name=f"{sensing.name}, camera only", slip_scale=0.0, slip_heading_deg=0.0)


def wheels_only(sensing: SensingConfig) -> SensingConfig:
    """``sensing`` with an ideal camera (the wheels' slip alone)."""
    return replace(sensing, name=f"{sensing.name}, wheels only", sigma_k=0.0, depth_unit=0.0, min_range=0.0,
                   dropout=0.0, edge_dropout=0.0)


def at_level(profile: Profile, sensing: SensingConfig, level: float) -> Profile:
    """``profile`` with ``sensing``'s noise times ``level`` (0: ideal senses, exactly)."""
    return with_sensing(profile, "ideal" if level == 0 else sensing.scaled(level))


def repeated_views(sim: Simulator, pose: np.ndarray, views: int) -> np.ndarray:
    """Depth in metres ``(views, H, W)`` of one pose of a *static* world, one view per step: the
    scene is the same, the camera's noise is drawn anew each time (a pure function of the step)."""
    images = np.stack([sim.depth(np.asarray(pose)[None], k)[0] for k in range(views)])
    return denormalize_depth(images, sim.config.camera)


def dead_reckoning(episode: Episode, library: PrimitiveLibrary) -> np.ndarray:
    """The poses ``(steps + 1, 3)`` a robot believes it reached: the start, then each primitive's
    nominal displacement from the last belief (what the planners' maps are moved by)."""
    believed = [np.asarray(episode.poses[0], float)]
    for action in episode.actions:
        believed.append(library.end_pose(believed[-1], int(action)))
    return np.asarray(believed)


def drift(episode: Episode, library: PrimitiveLibrary) -> np.ndarray:
    """Metres between the believed and the true position after each step (``(steps + 1,)``; the colliding
    step's true pose is where contact stopped the robot, so it is left out)."""
    believed = dead_reckoning(episode, library)
    n = len(episode.poses) - (1 if episode.collided else 0)
    return np.hypot(*(believed[:n, :2] - episode.poses[:n, :2]).T)
