"""First sightings on the moving course: a cylinder standing where the last image saw free space walked in.

A cylinder seen for the first time has no track yet (:class:`~husky_course.planners.motion.Tracks`
needs two looks), and the course's planners used to take it as standing. One image does say more.
The course's motion model (:class:`~husky_course.config.MovingWorldConfig`) lets a cylinder stand
or walk along ``y`` at a speed in ``speed_range``. Each of those velocities is a hypothesis about
where it stood one step ago; a hypothesis is ruled out when the previous image's column through
that place saw *through* it (its depth reached beyond the cylinder's front). When standing is
ruled out, the cylinder walked into the free space: it is a walker, and when every hypothesis
left walks one way, it is given the mean of those speeds. When both ways remain, or standing
does, it is still taken as standing (as before).

Nothing privileged: the previous image's per-column depth and dead reckoning. The rule was chosen
on the tuning set (evaluation set 1, 300 moving worlds, full profile; the disc planner: standing
0.727, this rule 0.787; the tolerance 0.08 / 0.15 / 0.25 m: 0.780 / 0.787 / 0.783; the slowest /
mean / fastest hypothesis left: 0.780 / 0.787 / 0.767). ``benchmarks/exp_moving_arrivals.py``
reruns it.
"""

from __future__ import annotations

import numpy as np

from ..config import ArrivalsConfig, SimConfig


class Arrivals:
    """The previous image's per-column depth, carried by dead reckoning, to judge first sightings.

    Parameters
    ----------
    config : SimConfig
        The course (its camera, and its world's ``speed_range``; a static course has none and
        :meth:`speeds` gives 0).
    tolerance : float
        Metres beyond a hypothesised cylinder's front the previous ray must have reached to rule
        the hypothesis out (the scan's and the disc's errors).
    hypotheses : int
        Walking speeds tried per direction, evenly spaced over ``speed_range``.
    """

    def __init__(self, config: SimConfig, tolerance: float = ArrivalsConfig.tolerance,
                 hypotheses: int = ArrivalsConfig.hypotheses) -> None:
        self.camera = config.camera
        self.half = float(np.tan(np.radians(self.camera.fov_deg) / 2))
        lo, hi = getattr(config.world, "speed_range", (0.0, 0.0))
        walks = np.linspace(lo, hi, hypotheses) if hi > 0 else np.empty(0)
        self.hypotheses = np.r_[0.0, walks, -walks]  #: velocities (m per step); standing first
        self.tolerance = float(tolerance)
        self.reset()

    def reset(self) -> None:
        """Forget the previous image (a new episode)."""
        self.depth: np.ndarray | None = None
        self.shift = np.zeros(2)

    def remember(self, depth: np.ndarray) -> None:
        """Keep this image's per-column depth ``(size,)`` (``inf`` where nothing is seen)."""
        self.depth, self.shift = np.asarray(depth, float).copy(), np.zeros(2)

    def move(self, dx: float, dy: float) -> None:
        """Dead reckoning: the robot moved by ``(dx, dy)`` since the remembered image."""
        self.shift += (dx, dy)

    def speeds(self, discs: np.ndarray) -> np.ndarray:
        """Velocity ``(k,)`` (m per step along ``y``) of first-sight cylinders ``discs (k, 3)``,
        ``(x, y, r)`` in the robot's frame now: a walk where the previous image rules standing out
        and leaves walks one way only, else 0 (see the module)."""
        discs = np.asarray(discs, float).reshape(-1, 3)
        out = np.zeros(len(discs))
        if self.depth is None or len(self.hypotheses) < 2 or not len(discs):
            return out
        cam, half = self.camera, self.half
        x = discs[:, None, 0] + self.shift[0] - cam.mount_forward  # ahead of the camera, then
        y = discs[:, None, 1] + self.shift[1] - self.hypotheses[None]  # where it stood one step ago
        front = x - discs[:, None, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            col = (half - y / x) * cam.size / (2 * half)
        j = np.floor(np.where(x > cam.near, col, -1.0) + 0.5).astype(int)
        in_view = (x > cam.near) & (j >= 0) & (j < cam.size) & (front + self.tolerance < cam.far)
        through = in_view & (self.depth[np.clip(j, 0, cam.size - 1)] > front + self.tolerance)
        for k in np.flatnonzero(through[:, 0]):  # standing ruled out
            left = self.hypotheses[~through[k]]
            if len(left) and (np.all(left > 0) or np.all(left < 0)):
                out[k] = float(left.mean())
        return out
