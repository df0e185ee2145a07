"""The onboard depth camera: its geometry, shared by both simulator backends.

The camera sits ``mount_forward`` metres ahead of the robot's base centre at ``mount_height`` above
the ground and looks along the robot's heading with no pitch or roll. It is a pinhole camera with a
square image and the same field of view vertically and horizontally.

Pixel convention (matched to PyBullet's TinyRenderer, checked in ``tests/test_fast_vs_pybullet.py``):
row 0 is the *top* of the image, column 0 the *left*; TinyRenderer samples pixel ``(i, j)`` at the
integer position ``i, j`` of its raster, whose rows run bottom-up, so the ray through pixel
``(i, j)`` has tangents ``u_j = t (1 - 2 j / W)`` (left) and ``v_i = t (1 - 2 (i + 1) / H)`` (up)
with ``t = tan(fov / 2)``.
"""

from __future__ import annotations

import numpy as np

from ..config import CameraConfig


def pixel_tangents(cfg: CameraConfig) -> tuple[np.ndarray, np.ndarray]:
    """Tangents of the pixel rays: ``u`` per column (left +), ``v`` per row (up +).

    A ray through pixel ``(i, j)`` has direction ``(1, u[j], v[i])`` in the camera's
    (forward, left, up) frame, so the parameter along it *is* the depth along the view axis.
    """
    t = np.tan(np.radians(cfg.fov_deg) / 2.0)
    j = np.arange(cfg.size)
    u = t * (1.0 - 2.0 * j / cfg.size)
    v = t * (1.0 - 2.0 * (j + 1) / cfg.size)
    return u, v


def horizon_rows(cfg: CameraConfig, band: int = 3) -> slice:
    """The ``band`` rows at and just above the horizon (row ``size / 2 - 1`` looks exactly along it).

    With a level camera these rows show vertical surfaces (obstacles, walls) or nothing, never the
    ground, so their depth is the distance to what stands in each column.
    """
    top = cfg.size // 2
    return slice(top - band, top)


def camera_positions(cfg: CameraConfig, poses: np.ndarray) -> np.ndarray:
    """World positions ``(B, 3)`` of the camera for robot poses ``(B, 3)``."""
    poses = np.asarray(poses, float).reshape(-1, 3)
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    return np.stack(
        [
            poses[:, 0] + cfg.mount_forward * c,
            poses[:, 1] + cfg.mount_forward * s,
            np.full(len(poses), cfg.mount_height),
        ],
        axis=1,
    )


def linearize_depth_buffer(buffer: np.ndarray, cfg: CameraConfig) -> np.ndarray:
    """OpenGL depth-buffer values in [0, 1] -> depth along the view axis in metres."""
    near, far = cfg.near, cfg.far
    if near <= 0:
        raise ValueError("camera near plane must be > 0 (near = 0 makes the depth NaN)")
    return far * near / (far - (far - near) * np.asarray(buffer, np.float64))


def normalize_depth(z: np.ndarray, cfg: CameraConfig) -> np.ndarray:
    """Metres -> [0, 1]: ``(z - near) / (far - near)``, clipped; 1 means 'nothing within far'."""
    out = (np.asarray(z, np.float64) - cfg.near) / (cfg.far - cfg.near)
    return np.clip(out, 0.0, 1.0).astype(np.float32)


def denormalize_depth(d: np.ndarray, cfg: CameraConfig) -> np.ndarray:
    """[0, 1] -> metres (the inverse of :func:`normalize_depth` inside the clip range)."""
    return cfg.near + np.asarray(d, np.float64) * (cfg.far - cfg.near)
