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

    def columns(self, obs: np.ndarray) -> np.ndarray:
        """View-axis depth (m) of the nearest vertical surface per column, ``inf`` where none is seen."""
        cam = self.camera
        col = np.median(check_observation(obs, cam.size)[self.rows], axis=0)
        return np.where(col < NOTHING_SEEN, denormalize_depth(col, cam), np.inf)

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        d = self.columns(obs)
        seen = np.isfinite(d)
        return np.stack([self.camera.mount_forward + d[seen], d[seen] * self.u[seen]], axis=1)


def raster(points: np.ndarray, cells: int, behind: float, ahead: float, half_width: float) -> np.ndarray:
    """Robot-frame points ``(m, 2+)`` as a ``(cells, cells)`` occupancy image (see :meth:`EgoMap.raster`)."""
    out = np.zeros((cells, cells), np.float32)
    if not len(points):
        return out
    i = np.floor((points[:, 0] + behind) / (ahead + behind) * cells).astype(int)
    j = np.floor((half_width - points[:, 1]) / (2 * half_width) * cells).astype(int)
    ok = (i >= 0) & (i < cells) & (j >= 0) & (j < cells)
    out[i[ok], j[ok]] = 1.0
    return out[::-1].copy()  # far rows at the top


class EgoMap:
    """Obstacle points ``(x, y, r)`` in the robot's frame, from every scan so far (no privileged input).

    * :meth:`add` puts in the points of a new image, each with an uncertainty radius ``r`` of half
      the gap between neighbouring columns at its distance (a surface can hide between two
      columns), and drops remembered points that the new image sees again or sees through (inside
      the field of view and in front of that column's depth): where the camera looks now, the
      current image is the truth, and memory keeps what it cannot see (beside and behind the robot,
      or occluded);
    * :meth:`move` is dead reckoning: after a primitive that ended at ``(dx, dy)`` with heading 0
      (every primitive does), the points move by ``(-dx, -dy)``; points further behind than
      ``forget_behind`` are dropped.
    """

    def __init__(self, scan: DepthScan, forget_behind: float) -> None:
        self.scan, self.forget_behind = scan, float(forget_behind)
        cam = scan.camera
        self._t = float(scan.u[0])  # tangent of half the field of view
        self._half_gap = self._t / cam.size  # half the tangent step between two columns
        self.points = np.empty((0, 3))

    def reset(self) -> None:
        """Forget everything (a new episode)."""
        self.points = np.empty((0, 3))

    def add(
        self, obs: np.ndarray, use: np.ndarray | None = None, depth: np.ndarray | None = None
    ) -> np.ndarray:
        """Merge the scan of ``obs`` into the map (see the class docstring).

        ``use`` (a boolean mask over the image's columns) limits which columns' points join the
        map (default: every column that sees something); every column still clears what it sees
        again or sees through. ``depth``: the image's per-column depth when the caller has it
        (:meth:`DepthScan.columns`). Returns which of the points held before were kept (a boolean
        mask over them): the new scan's points come first in :attr:`points`, then the kept ones.
        """
        cam = self.scan.camera
        d = self.scan.columns(obs) if depth is None else depth
        kept = np.ones(len(self.points), bool)
        if len(self.points):
            dx = self.points[:, 0] - cam.mount_forward
            with np.errstate(divide="ignore", invalid="ignore"):
                u = np.where(dx > cam.near, self.points[:, 1] / dx, np.inf)
            col = np.where(np.isfinite(u), (self._t - u) * cam.size / (2 * self._t), -1.0)
            j = np.floor(col + 0.5).astype(int)
            in_view = (dx > cam.near) & (j >= 0) & (j < cam.size)
            seen_again = in_view & (dx < d[np.clip(j, 0, cam.size - 1)] + self.points[:, 2] + 0.05)
            kept = ~seen_again
            self.points = self.points[kept]
        seen = np.isfinite(d) if use is None else np.isfinite(d) & use
        ds, us = d[seen], self.scan.u[seen]
        new = np.stack([cam.mount_forward + ds, ds * us, ds * self._half_gap], axis=1)
        self.points = np.concatenate([new, self.points])
        return kept

    def raster(self, cells: int, behind: float, ahead: float, half_width: float) -> np.ndarray:
        """The map as a ``(cells, cells)`` occupancy image: row = forward distance, column = lateral.

        Cell ``(i, j)`` is 1 where a map point lies in it: rows cover ``x`` from ``-behind`` (row 0)
        to ``ahead``, columns ``y`` from ``+half_width`` (column 0, the robot's left) to
        ``-half_width``, so the image reads like a top-down view with the robot near the bottom.
        """
        return raster(self.points, cells, behind, ahead, half_width)

    def move(self, dx: float, dy: float) -> np.ndarray:
        """Dead reckoning after a primitive that moved the robot by ``(dx, dy)`` (heading unchanged);
        returns which points were kept (a boolean mask over those held before)."""
        moved = self.points - np.array([dx, dy, 0.0])
        kept = moved[:, 0] > -self.forget_behind
        self.points = moved[kept]
        return kept
