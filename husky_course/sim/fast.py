"""The fast backend: analytic ray casting and circle-vs-circle collision in numpy.

Everything in the course is vertical (cylinders and walls standing on flat ground) and the camera
never pitches or rolls, so the first vertical surface a pixel's ray meets depends only on the
pixel's *column*. For each column we intersect the horizontal ray with every obstacle (its
bounding circle first, then its 20-sided outline, :func:`husky_course.sim.world.obstacle_outline`) and
both walls (a line), then per row we keep that hit if it lies below the obstacles' top and in
front of the ground, otherwise the ground (or nothing, i.e. ``far``). This gives the same images as
PyBullet's TinyRenderer (checked in ``tests/test_fast_vs_pybullet.py``) hundreds of times faster,
and it is batched over many poses.

Collision: the robot's cylinder (radius ``R``) touches obstacle ``(x, y, r)`` at a recorded pose iff
the centres are closer than ``R + r``, and touches a wall iff ``|y| + R`` exceeds the wall's face.

On the moving course every query places the cylinders where they are at its time
(:meth:`husky_course.sim.world.World.obstacles_at`): per image for depth, per recorded sample for
contact.
"""

from __future__ import annotations

import numpy as np

from ..config import SimConfig
from .base import Simulator
from .camera import camera_positions, normalize_depth, pixel_tangents
from .world import World, obstacle_outline, pose_times, sample_times

_CHUNK = 512  # poses per vectorised block (bounds memory: chunk x columns x obstacles)


def _polygon_halfplanes() -> tuple[np.ndarray, np.ndarray]:
    """Outward unit normals ``(E, 2)`` and offsets ``(E,)`` of the unit-radius obstacle outline."""
    v = obstacle_outline()
    edge = np.roll(v, -1, axis=0) - v
    n = np.stack([edge[:, 1], -edge[:, 0]], axis=1)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return n, (n * v).sum(1)


_NORMALS, _OFFSETS = _polygon_halfplanes()


class FastSimulator(Simulator):
    """Vectorised numpy simulator; same interface and conventions as the PyBullet backend."""

    name = "fast"

    def __init__(self, config: SimConfig | None = None) -> None:
        super().__init__(config)
        self._u, self._v = pixel_tangents(self.config.camera)

    def _load(self, world: World) -> None:
        self._obs = np.asarray(world.obstacles, float)
        self._moves = len(world.moving) > 0

    def _obs_at(self, t: np.ndarray) -> np.ndarray:
        """Obstacles ``(B, n, 3)`` at times ``t (B,)``, or ``(1, n, 3)`` when nothing moves."""
        if not self._moves:
            return self._obs[None]
        return self._require_world().obstacles_at(t)

    # --- camera ----------------------------------------------------------------------------------
    def column_hits(self, poses: np.ndarray, t: np.ndarray | float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Nearest vertical surface per column, seen from ``poses (B, 3)`` at times ``t``.

        Returns
        -------
        t : ndarray, shape (B, size)
            View-axis depth of the first cylinder or wall hit by each column's ray (inf if none).
        kind : ndarray, shape (B, size)
            What was hit: ``0`` nothing, ``1`` a wall, ``2 + i`` obstacle ``i``.
        """
        world = self._require_world()
        poses = np.asarray(poses, float).reshape(-1, 3)
        cam = camera_positions(self.config.camera, poses)
        yaw = poses[:, 2:3]
        c, s = np.cos(yaw), np.sin(yaw)
        u = self._u[None]
        hx, hy = c - u * s, s + u * c  # (B, W) horizontal ray directions (forward component 1)
        t_obs = self._cylinder_hits(cam, hx, hy, self._obs_at(pose_times(t, len(poses))))
        # walls: inner faces at y = +-wall_y, limited to the walls' x extent
        t_wall = np.full(hx.shape, np.inf)
        x0, x1 = world.config.wall_x_range
        for side in (-1.0, 1.0):
            with np.errstate(divide="ignore", invalid="ignore"):
                t = (side * world.wall_y - cam[:, 1:2]) / hy
            x_hit = cam[:, 0:1] + t * hx
            ok = (t > 0) & (x_hit >= x0) & (x_hit <= x1)
            t_wall = np.minimum(t_wall, np.where(ok, t, np.inf))
        if self._obs.shape[0]:
            k_obs = np.argmin(t_obs, axis=-1)
            t_min = np.take_along_axis(t_obs, k_obs[..., None], axis=-1)[..., 0]
        else:
            k_obs = np.zeros(hx.shape, int)
            t_min = np.full(hx.shape, np.inf)
        kind = np.where(t_min < t_wall, 2 + k_obs, np.where(np.isfinite(t_wall), 1, 0))
        return np.minimum(t_min, t_wall), kind

    def visible_obstacles(self, pose: np.ndarray, t: float = 0.0) -> np.ndarray:
        """Indices of the obstacles the camera renders from ``pose``: the one definition of "in view".

        An obstacle is in view when it is the nearest surface of at least one image column within
        ``far``: this accounts for the camera's position and field of view, the obstacle's width
        (a thin one can fall between columns), occlusion by nearer obstacles and the far limit.
        """
        depth, kind = self.column_hits(np.asarray(pose, float)[None], t)
        seen = kind[0][(kind[0] >= 2) & (depth[0] <= self.config.camera.far)]
        return np.unique(seen - 2)

    def _cylinder_hits(self, cam: np.ndarray, hx: np.ndarray, hy: np.ndarray, obs: np.ndarray) -> np.ndarray:
        """Ray parameter ``(B, W, n_obs)`` of the first hit on each obstacle's render polygon
        (obstacles ``obs``: ``(B, n, 3)``, or ``(1, n, 3)`` shared by every pose)."""
        ox = cam[:, 0:1, None] - obs[:, None, :, 0]  # camera relative to obstacle centre
        oy = cam[:, 1:2, None] - obs[:, None, :, 1]
        # broad phase: the circumscribed circle |cam + t h - o| = r must be crossed
        a = (hx * hx + hy * hy)[..., None]
        b = hx[..., None] * ox + hy[..., None] * oy
        disc = b * b - a * (ox * ox + oy * oy - obs[:, None, :, 2] ** 2)
        out = np.full(disc.shape, np.inf)
        bi, wi, oi = np.nonzero(disc >= 0)
        if bi.size == 0:
            return out
        # narrow phase (Cyrus-Beck): clip the ray against the polygon's half-planes
        px, py = ox[bi, 0, oi], oy[bi, 0, oi]
        dx, dy = hx[bi, wi], hy[bi, wi]
        radius = self._obs[oi, 2, None]
        num = radius * _OFFSETS - (px[:, None] * _NORMALS[:, 0] + py[:, None] * _NORMALS[:, 1])
        den = dx[:, None] * _NORMALS[:, 0] + dy[:, None] * _NORMALS[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = num / den
        t_in = np.where(den < 0, t, -np.inf).max(1)
        t_out = np.where(den > 0, t, np.inf).min(1)
        parallel_out = ((den == 0) & (num < 0)).any(1)
        hit = (t_in <= t_out) & (t_in > 0) & ~parallel_out
        out[bi[hit], wi[hit], oi[hit]] = t_in[hit]
        return out

    def depth_metres(self, poses: np.ndarray, t: np.ndarray | float = 0.0) -> np.ndarray:
        """Depth along the view axis in metres ``(B, size, size)`` at times ``t``, clipped to [near, far]."""
        cfg = self.config.camera
        height = self._require_world().config.obstacle_height
        poses = np.asarray(poses, float).reshape(-1, 3)
        times = pose_times(t, len(poses))
        out = np.empty((len(poses), cfg.size, cfg.size))
        v = self._v[None, :, None]  # rows
        with np.errstate(divide="ignore"):
            t_ground = np.where(self._v < 0, -cfg.mount_height / self._v, np.inf)[None, :, None]
        for i in range(0, len(poses), _CHUNK):
            t_col, _ = self.column_hits(poses[i : i + _CHUNK], times[i : i + _CHUNK])
            t_col = t_col[:, None, :]
            with np.errstate(invalid="ignore"):
                below_top = cfg.mount_height + t_col * v <= height
            t = np.minimum(np.where(below_top, t_col, np.inf), t_ground)
            out[i : i + _CHUNK] = np.clip(t, cfg.near, cfg.far)
        return out

    def _depth(self, poses: np.ndarray, t: np.ndarray | float = 0.0) -> np.ndarray:
        return normalize_depth(self.depth_metres(poses, t), self.config.camera)

    def rgb(self, pose: np.ndarray, t: float = 0.0) -> np.ndarray:
        """A shaded RGB view: ground grey, walls blue-grey, obstacles orange, sky white."""
        cfg = self.config.camera
        pose = np.asarray(pose, float).reshape(1, 3)
        z = self.depth_metres(pose, t)[0]
        _, kind = self.column_hits(pose, t)
        with np.errstate(divide="ignore"):
            t_ground = np.where(self._v < 0, -cfg.mount_height / self._v, np.inf)[:, None]
        is_ground = np.isclose(z, np.minimum(t_ground, cfg.far)) & np.isfinite(t_ground)
        colour = np.where(kind[0] >= 2, 0, np.where(kind[0] == 1, 1, 2))[None].repeat(cfg.size, 0)
        palette = np.array([[217, 115, 51], [153, 153, 166], [255, 255, 255], [200, 200, 190]])
        colour = np.where(is_ground, 3, np.where(z >= cfg.far, 2, colour))
        shade = 1.0 - 0.5 * np.clip(z / cfg.far, 0, 1)[..., None]
        img = palette[colour] * np.where(colour[..., None] == 2, 1.0, shade)
        return img.astype(np.uint8)

    # --- collision -------------------------------------------------------------------------------
    def contact_along(self, path: np.ndarray, t: float = 0.0) -> int:
        hits = self.contacts(np.asarray(path, float)[None], t)[0]
        idx = np.flatnonzero(hits)
        return int(idx[0]) if idx.size else -1

    def contacts(self, paths: np.ndarray, t: np.ndarray | float = 0.0) -> np.ndarray:
        """Per-pose contact flags ``(B, S)`` for a batch of primitive paths ``(B, S, 3)`` started at
        times ``t`` (a number, or one per path).

        A broad phase keeps only the (path, obstacle) pairs whose bounding circles overlap (an
        obstacle's grown by the distance it can walk in half a step, the path's ``t`` at its
        middle), so the exact per-sample test runs on a few obstacles per path instead of all.
        """
        world = self._require_world()
        radius = world.config.robot_radius
        paths = np.asarray(paths, float)
        xy = paths[..., :2]
        hit = np.abs(xy[..., 1]) + radius > world.wall_y
        if self._obs.shape[0] and paths.shape[1]:
            lo, hi = xy.min(1), xy.max(1)  # (B, 2) bounding box of every path
            centre, half = (lo + hi) / 2.0, np.linalg.norm(hi - lo, axis=1) / 2.0
            times = pose_times(t, len(paths))
            mid = self._obs_at(times + 0.5)  # (B or 1, n, 3)
            walk = 0.5 * np.abs(world.speeds) if self._moves else 0.0  # type: ignore[arg-type]
            gap = np.linalg.norm(centre[:, None, :] - mid[..., :2], axis=-1)
            pb, po = np.nonzero(gap < half[:, None] + radius + self._obs[None, :, 2] + walk)
            if pb.size:
                if self._moves:  # each pair's obstacle at each sample's time
                    y = world.obstacle_y(po, sample_times(times[pb], paths.shape[1]))  # (pairs, S)
                    centres = np.stack([np.broadcast_to(self._obs[po, 0, None], y.shape), y], axis=-1)
                else:
                    centres = self._obs[po, None, :2]
                d2 = ((xy[pb] - centres) ** 2).sum(-1)  # (pairs, S)
                touch = d2 < (radius + self._obs[po, 2, None]) ** 2
                np.logical_or.at(hit, pb, touch)
        return hit
