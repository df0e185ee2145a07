"""Lateral motion from successive scans: what a planner on the moving course infers with its memory.

Nothing privileged: the robot keeps the previous image's scan (the points of
:class:`~husky_course.planners.perception.DepthScan`) and the velocities it estimated for it, moves
them into the current frame by dead reckoning, and compares them with the current scan.

* :func:`segments` cuts a scan (points in column order) into pieces of surface: neighbouring points
  closer than ``gap``, or than ``spacing`` times their forward distance (the camera's columns
  spread apart with distance), belong to the same piece (a cylinder's visible arc, a stretch of wall);
* :func:`piece_centre` locates a piece: a circle fitted to its points, its radius held near the
  course's typical radius, its centre behind the points as seen from the camera (a piece over 1 m
  long is a wall, or several things: its mean). A cylinder's centre moves only with the cylinder,
  where the mean of its visible points also moves as the robot's viewpoint changes which columns
  hit it; on the tuning worlds the fit's median error on a moving cylinder's step is 0.02 m,
  the mean's 0.11 m (``benchmarks/exp_moving_tracker.py``);
* :func:`lateral_velocities` matches each current piece to a previous piece at about the same
  forward distance (cylinders move only across the course) within one step's walk, the one whose
  displacement best continues its own estimated velocity, and gives every point of the piece that
  displacement, averaged with the previous estimate when there is one (a second look halves the
  noise); 0 where nothing matches (a piece seen for the first time: taken as standing);
* :class:`MotionMemory` keeps the previous scan and its velocities between decisions;
* :class:`WalkingMap` is the mapping planner's map (:class:`~husky_course.planners.perception.EgoMap`)
  whose points carry those velocities and walk on between images: what both planners of the moving
  course that remember see (the classical :mod:`~husky_course.planners.tracking` and the memory
  student).

Partial occlusion and two cylinders seen as one piece still show as motion: an estimate, which a
learned planner learns to trust as far as it deserves.
"""

from __future__ import annotations

import numpy as np

from ..config import SimConfig
from .perception import DepthScan, EgoMap


def segments(points: np.ndarray, gap: float = 0.3, spacing: float = 0.0) -> list[np.ndarray]:
    """Index arrays of the pieces of surface in a scan ``(m, 2)`` given in column order (see the module)."""
    if not len(points):
        return []
    step = np.linalg.norm(np.diff(points[:, :2], axis=0), axis=1)
    limit = np.maximum(gap, spacing * np.maximum(points[:-1, 0], points[1:, 0]))
    starts = np.r_[0, np.flatnonzero(step > limit) + 1]
    ends = np.r_[starts[1:], len(points)]
    return [np.arange(a, b) for a, b in zip(starts, ends, strict=True)]


def piece_centre(points: np.ndarray, camera_x: float, radius: float, iterations: int = 8) -> np.ndarray:
    """Where a piece of surface ``(m, 2+)`` is: the centre ``(x, y)`` of a fitted circle (see the module).

    Gauss-Newton on ``sum (|p_i - c| - r)^2 + (r - radius)^2`` from a centre behind the points'
    mean, as seen from the camera at ``(camera_x, 0)``; ``r`` stays in ``[0.4, 2] radius``.
    ``radius=0`` gives the points' mean (the course's first estimator, kept for comparison).
    """
    p = np.asarray(points, float)[:, :2]
    mean = p.mean(0)
    if radius <= 0 or np.ptp(p, axis=0).max() > 1.0:
        return mean
    ray = mean - (camera_x, 0.0)
    c, r = mean + 0.8 * radius * ray / max(float(np.hypot(*ray)), 1e-9), radius
    prior = np.array([[0.0, 0.0, 1.0]])
    for _ in range(iterations):
        d = p - c
        n = np.hypot(d[:, 0], d[:, 1]) + 1e-9
        jac = np.r_[np.c_[-d / n[:, None], -np.ones(len(p))], prior]
        step = np.linalg.lstsq(jac, -np.r_[n - r, r - radius], rcond=None)[0]
        c, r = c + step[:2], float(np.clip(r + step[2], 0.4 * radius, 2.0 * radius))
    return c


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
    """Estimated lateral displacement per step ``(m,)`` of every point of ``current`` (see the module).

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


class MotionMemory:
    """The previous scan and its velocities, carried between decisions (see the module).

    :meth:`update` estimates the current scan's velocities and remembers both; :meth:`move` is dead
    reckoning after a primitive that moved the robot by ``(dx, dy)``.
    """

    def __init__(self, config: SimConfig) -> None:
        world, cam = config.world, config.camera
        self.max_step = float(getattr(world, "speed_range", (0.0, 0.0))[1])  # the fastest walker, per step
        self.radius = float(np.mean(world.radius_range))
        self.camera_x = cam.mount_forward
        self.spacing = 1.5 * 2 * np.tan(np.radians(cam.fov_deg) / 2) / cam.size  # 1.5 columns' tangent step
        self.reset()

    def reset(self) -> None:
        """Forget (a new episode)."""
        self.previous, self.velocity = np.empty((0, 2)), np.empty(0)

    def update(self, now: np.ndarray) -> np.ndarray:
        """Velocities ``(m,)`` of the current scan ``now`` ``(m, 2)``; ``now`` becomes the previous scan."""
        v = lateral_velocities(
            self.previous, now, self.max_step, self.velocity, self.camera_x, self.radius, self.spacing
        )
        self.previous, self.velocity = np.asarray(now, float)[:, :2].copy(), v
        return v

    def move(self, dx: float, dy: float) -> None:
        """Dead reckoning: the previous scan moves by ``(-dx, -dy)`` in the robot's new frame."""
        self.previous = self.previous - (dx, dy)


class WalkingMap:
    """An :class:`~husky_course.planners.perception.EgoMap` whose points walk (see the module).

    :meth:`add` merges an image's scan, each new point with the velocity :class:`MotionMemory`
    estimates for it (a point seen again is replaced, as in the map); :meth:`move` is dead
    reckoning of the robot *and* of the obstacles: after a primitive that moved the robot by
    ``(dx, dy)`` every point moves by ``(-dx, -dy)`` and then one step's walk along ``y``.
    On the static course every velocity is 0 and it is the map itself.
    """

    def __init__(self, config: SimConfig, forget_behind: float) -> None:
        self.map = EgoMap(DepthScan(config), forget_behind)
        self.motion = MotionMemory(config)
        self.velocity = np.empty(0)  #: per point, m per step along y

    @property
    def points(self) -> np.ndarray:
        """The map's points ``(x, y, r)`` now, in the robot's frame."""
        return self.map.points

    def scan(self, obs: np.ndarray) -> np.ndarray:
        """The points ``(m, 2)`` of one image's scan."""
        return self.map.scan(obs)

    def reset(self) -> None:
        """Forget everything (a new episode)."""
        self.map.reset()
        self.motion.reset()
        self.velocity = np.empty(0)

    def add(self, obs: np.ndarray) -> np.ndarray:
        """Merge the scan of ``obs``; return its points' velocities (they come first in :attr:`points`)."""
        v = self.motion.update(self.map.scan(obs))
        kept = self.map.add(obs)
        self.velocity = np.concatenate([v, self.velocity[kept]])
        return v

    def at(self, t: float | np.ndarray) -> np.ndarray:
        """The points ``(x, y, r)`` where they will be ``t`` steps from now (one ``t`` per point, or one)."""
        out = self.map.points.copy()
        out[:, 1] += self.velocity * t
        return out

    def move(self, dx: float, dy: float) -> None:
        """Dead reckoning after a primitive that moved the robot by ``(dx, dy)``, and one step's walk."""
        kept = self.map.move(dx, dy)
        self.velocity = self.velocity[kept]
        self.map.points[:, 1] += self.velocity
        self.motion.move(dx, dy)
