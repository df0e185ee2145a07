"""Random obstacle courses, each reproducible from one integer seed.

A :class:`World` is pure data (obstacle centres and radii, walls, the start pose); the simulator
backends (:mod:`husky_course.sim.fast`, :mod:`husky_course.sim.pybullet_backend`) turn it into
depth images and collision checks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..checks import is_int
from ..config import WorldConfig


@dataclass(frozen=True)
class World:
    """One obstacle course.

    Attributes
    ----------
    seed : int
        The seed it was generated from.
    obstacles : ndarray, shape (n, 3)
        ``(x, y, radius)`` of each cylinder.
    start : ndarray, shape (3,)
        The start pose ``(x, y, yaw)``; never in collision.
    """

    seed: int
    config: WorldConfig
    obstacles: np.ndarray
    start: np.ndarray

    @property
    def wall_y(self) -> float:
        """|y| of the inner faces of the two side walls."""
        return self.config.width / 2.0


#: Both backends draw a cylinder of radius ``r`` as the prism over the 20 rim points
#: ``r (cos a_k, sin a_k)``, ``a_k = 2 pi k / 32`` for these ``k``: the outline PyBullet's own
#: cylinder visual is built from (it samples 32 rim points and ``btShapeHull`` keeps these 20;
#: ``tests/test_fast_vs_pybullet.py`` re-measures it). PyBullet's hull also adds a 1 mm margin
#: and slightly different top and bottom outlines, so the PyBullet backend draws this prism as an
#: explicit mesh instead: then the geometry both backends render is defined here, exactly.
OUTLINE_VERTICES = (0, 2, 3, 5, 6, 8, 10, 11, 13, 14, 16, 18, 19, 21, 22, 24, 26, 27, 29, 30)


def obstacle_outline() -> np.ndarray:
    """Vertices ``(20, 2)`` of the unit-radius obstacle outline, counter-clockwise."""
    a = 2 * np.pi * np.array(OUTLINE_VERTICES) / 32
    return np.stack([np.cos(a), np.sin(a)], axis=1)


def check_seed(seed: object) -> int:
    """Return ``seed`` as a non-negative int or raise ``ValueError``."""
    if not is_int(seed) or seed < 0:  # type: ignore[operator]
        raise ValueError(f"a world seed must be a non-negative integer, got {seed!r}")
    return int(seed)


def make_world(seed: int, cfg: WorldConfig | None = None) -> World:
    """Generate the world for ``seed``.

    The start ``y`` is drawn first; then each obstacle's ``(x, y, r)`` is drawn uniformly and
    redrawn while it would touch the robot's start disc (plus ``start_clearance``).
    Everything comes from one ``numpy.random.Generator`` seeded with ``seed``.
    """
    cfg = cfg or WorldConfig()
    seed = check_seed(seed)
    rng = np.random.default_rng(seed)
    half = cfg.width / 2.0
    start = np.array([0.0, rng.uniform(-cfg.start_half_width, cfg.start_half_width), 0.0])
    r_lo, r_hi = cfg.radius_range
    obstacles = np.empty((cfg.n_obstacles, 3))
    for i in range(cfg.n_obstacles):
        while True:
            x = rng.uniform(cfg.obstacle_x_min, cfg.length)
            y = rng.uniform(-half, half)
            r = rng.uniform(r_lo, r_hi)
            clear = np.hypot(x - start[0], y - start[1]) > cfg.robot_radius + r + cfg.start_clearance
            if clear:
                break
        obstacles[i] = (x, y, r)
    obstacles.setflags(write=False)
    start.setflags(write=False)
    return World(seed, cfg, obstacles, start)
