"""Random obstacle courses, each reproducible from one integer seed.

A :class:`World` is pure data (obstacle centres and radii, walls, the start pose, and on the
moving course each cylinder's speed); the simulator backends (:mod:`husky_course.sim.fast`,
:mod:`husky_course.sim.pybullet_backend`) turn it into depth images and collision checks.

**Time** is counted in primitive steps: the robot's ``k``-th image is taken at time ``k`` and the
recorded samples ``s = 0 .. S-1`` of the primitive it then plays back are at times
``k + s / (S - 1)``. On the static course nothing depends on time.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..checks import is_int
from ..config import MovingWorldConfig, WorldConfig


@dataclass(frozen=True)
class World:
    """One obstacle course.

    Attributes
    ----------
    seed : int
        The seed it was generated from.
    obstacles : ndarray, shape (n, 3)
        ``(x, y, radius)`` of each cylinder.
        On the moving course: where each cylinder is at time 0.
    start : ndarray, shape (3,)
        The start pose ``(x, y, yaw)``; never in collision.
    speeds : ndarray, shape (n,)
        Each cylinder's velocity along ``y`` (m per step; 0 for those that stand still).
    """

    seed: int
    config: WorldConfig
    obstacles: np.ndarray
    start: np.ndarray
    speeds: np.ndarray | None = None

    @property
    def wall_y(self) -> float:
        """|y| of the inner faces of the two side walls."""
        return self.config.width / 2.0

    @property
    def moving(self) -> np.ndarray:
        """Indices of the cylinders that move (empty on the static course)."""
        return np.empty(0, int) if self.speeds is None else np.flatnonzero(self.speeds != 0)

    @property
    def max_speed(self) -> float:
        """The fastest cylinder's speed (m per step; 0 on the static course)."""
        return 0.0 if self.speeds is None or not len(self.speeds) else float(np.abs(self.speeds).max())

    def obstacle_y(self, index: np.ndarray, t: np.ndarray | float) -> np.ndarray:
        """``y`` of cylinder ``index[i]`` at times ``t[i, ...]`` (``index (P,)``, ``t (P, ...)`` or a number).

        A moving cylinder of radius ``r`` travels at its constant speed between ``lo = -W/2 + r``
        and ``hi = W/2 - r`` (touching a wall's face) and reflects there: a triangle wave in
        ``t``, so its position is a closed-form function of the seed and the time. Cylinders pass
        through one another (no mover-mover contact), which keeps it closed-form.
        """
        index = np.asarray(index, int)
        t = np.asarray(t, float)
        if t.ndim == 0:
            t = np.broadcast_to(t, index.shape)
        shape = (-1,) + (1,) * (t.ndim - 1)
        obs = self.obstacles[index]
        y0, r = obs[:, 1].reshape(shape), obs[:, 2].reshape(shape)
        v = (np.zeros(len(index)) if self.speeds is None else self.speeds[index]).reshape(shape)
        lo, span = -self.wall_y + r, 2 * (self.wall_y - r)
        u = np.mod(y0 - lo + v * t, 2 * span)
        return np.where(v == 0, y0, lo + span - np.abs(u - span))

    def obstacles_at(self, t: np.ndarray | float) -> np.ndarray:
        """``(x, y, r)`` of every cylinder at times ``t``: shape ``shape(t) + (n, 3)``."""
        t = np.asarray(t, float)
        out = np.broadcast_to(self.obstacles, t.shape + self.obstacles.shape).copy()
        movers = self.moving
        if len(movers):
            y = self.obstacle_y(movers, np.broadcast_to(t, (len(movers),) + t.shape))
            out[..., movers, 1] = np.moveaxis(y, 0, -1)
        return out


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


def sample_times(t: np.ndarray | float, samples: int) -> np.ndarray:
    """Times ``shape(t) + (samples,)`` of a primitive's recorded samples when it starts at ``t``."""
    return np.asarray(t, float)[..., None] + _fractions(samples)


@functools.cache
def _fractions(samples: int) -> np.ndarray:
    """``0..1`` in ``samples`` steps (read-only: one array shared by every call)."""
    frac = np.linspace(0.0, 1.0, samples) if samples > 1 else np.zeros(1)
    frac.flags.writeable = False
    return frac


def pose_times(t: np.ndarray | float, n: int) -> np.ndarray:
    """``t`` as one time per pose, shape ``(n,)`` (a number is shared by every pose)."""
    t = np.asarray(t, float)
    if t.ndim and t.shape != (n,):
        raise ValueError(f"need one time per pose: {t.shape} times for {n} poses")
    return np.broadcast_to(t, (n,))


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

    **The moving course** (``cfg`` a :class:`~husky_course.config.MovingWorldConfig`) is this same
    world, drawn from the same generator, and then ``round(moving_fraction * n)`` cylinders chosen at
    random get a speed along ``y`` (uniform in ``speed_range``, either sign). A moving cylinder
    starts where the static one stands (moved inside the walls if it overlapped one) and walks
    across the course, bouncing off the side walls (:meth:`World.obstacles_at`) and passing through
    other cylinders (only the robot collides with anything). Why this model:
    crossing traffic is what opens and closes the gaps the robot chooses between, and what a
    forward-facing camera sees least of (a cylinder can walk in from outside the field of view);
    motion along ``y`` only keeps the obstacles' spread along the course, hence the course's length
    in obstacles, the static one's; the walls keep every cylinder in the course at every time, and
    the same seed gives the same starting layout in both courses, so the two are compared world by
    world. The first primitive can never be hit: cylinders stand at ``x >= obstacle_x_min`` and move
    only across.
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
    speeds = None
    if isinstance(cfg, MovingWorldConfig):
        speeds = np.zeros(cfg.n_obstacles)
        movers = rng.choice(cfg.n_obstacles, int(round(cfg.moving_fraction * cfg.n_obstacles)), replace=False)
        s_lo, s_hi = cfg.speed_range
        speeds[movers] = rng.uniform(s_lo, s_hi, len(movers)) * rng.choice([-1.0, 1.0], len(movers))
        inside = half - obstacles[movers, 2]
        obstacles[movers, 1] = np.clip(obstacles[movers, 1], -inside, inside)
        speeds.setflags(write=False)
    obstacles.setflags(write=False)
    start.setflags(write=False)
    return World(seed, cfg, obstacles, start, speeds)
