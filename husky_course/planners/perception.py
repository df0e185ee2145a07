"""What a planner can read off one depth image without learning: a laser scan of vertical surfaces.

Obstacles and walls are vertical and the camera is level, so in the rows that see neither the
ground nor an obstacle's top within ``far``, a column's depth ``D`` is the distance (along the view
axis) to the nearest vertical surface in that column: one point ``(mount_forward + D, D u_j)`` in
the robot frame per column. Columns at ``far`` saw nothing there: unknown space, not free space.
"""

from __future__ import annotations

import numpy as np

from ..config import SimConfig
from ..sim.camera import denormalize_depth, pixel_tangents
from .base import check_observation

#: a column whose normalised depth is at least this saw nothing within ``far``
NOTHING_SEEN = 0.999


class DepthScan:
    """``scan(obs) -> (m, 2)`` robot-frame points, one per column that sees a vertical surface."""

    def __init__(self, config: SimConfig | None = None) -> None:
        cfg = config or SimConfig()
        cam = cfg.camera
        self.camera = cam
        self.u, v = pixel_tangents(cam)
        height = cfg.world.obstacle_height - cam.mount_height
        with np.errstate(divide="ignore"):
            ground = np.where(v < 0, cam.mount_height / -v, np.inf)
            top = np.where(v > 0, height / v, np.inf)
        rows = np.flatnonzero((ground >= cam.far) & (top >= cam.far))
        self.rows = rows if rows.size else np.array([cam.size // 2])

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        cam = self.camera
        col = np.median(check_observation(obs, cam.size)[self.rows], axis=0)
        seen = col < NOTHING_SEEN
        d = denormalize_depth(col[seen], cam)
        return np.stack([cam.mount_forward + d, d * self.u[seen]], axis=1)
