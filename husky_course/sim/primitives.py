"""The 25 motion primitives, recorded once as dense pose sequences and played back.

The paper uses *record and playback*: each primitive is a smooth forward manoeuvre that brings the
robot back to its initial heading. We record each one as ``samples`` poses in the robot's own frame
and play it back kinematically from any start pose (as the lab's code does with
``resetBasePositionAndOrientation``), which avoids the Husky's skid-steer slip.

Primitive ``k`` is an S-curve ``x(s) = advance * s``, ``y(s) = d_k (1 - cos(pi s)) / 2``,
``s in [0, 1]``, with the lateral offsets ``d_k`` evenly spaced in ``[-spread, spread]``. Its heading
is tangent to the path, so it starts and ends at yaw 0 (relative), and the forward speed is
constant in ``x``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..checks import is_int
from ..config import PrimitiveConfig


class PrimitiveError(ValueError):
    """A primitive index outside the library."""


@dataclass(frozen=True)
class PrimitiveLibrary:
    """Recorded primitives.

    Attributes
    ----------
    offsets : ndarray, shape (n,)
        Lateral offset of each primitive's end point (m), left positive.
    local_paths : ndarray, shape (n, samples, 3)
        The recorded poses ``(x, y, yaw)`` relative to the start pose.
    """

    config: PrimitiveConfig
    offsets: np.ndarray
    local_paths: np.ndarray

    @property
    def n(self) -> int:
        """Number of primitives."""
        return int(self.offsets.shape[0])

    def check_index(self, index: object) -> int:
        """Return ``index`` as an int, or raise :class:`PrimitiveError` if it is not a primitive."""
        if not is_int(index):
            raise PrimitiveError(f"primitive index must be an integer, got {index!r}")
        if not 0 <= int(index) < self.n:
            raise PrimitiveError(f"primitive index {int(index)} out of range 0..{self.n - 1}")
        return int(index)

    def path_from(self, pose: np.ndarray, index: int) -> np.ndarray:
        """World poses ``(samples, 3)`` of primitive ``index`` played back from ``pose``."""
        return self.paths_from(np.asarray(pose, float)[None], np.array([self.check_index(index)]))[0]

    def paths_from(self, poses: np.ndarray, indices: np.ndarray) -> np.ndarray:
        """Vectorised :meth:`path_from`: ``poses (B, 3)``, ``indices (B,)`` -> ``(B, samples, 3)``."""
        poses = np.asarray(poses, float)
        if poses.shape[-1:] != (3,) or poses.ndim > 2:
            raise ValueError(f"a pose is (x, y, yaw): expected shape (3,) or (B, 3), got {poses.shape}")
        poses = poses.reshape(-1, 3)
        idx = np.asarray(indices)
        if idx.size and (not np.issubdtype(idx.dtype, np.integer) or idx.min() < 0 or idx.max() >= self.n):
            bad = idx[(idx < 0) | (idx >= self.n)] if np.issubdtype(idx.dtype, np.integer) else idx
            raise PrimitiveError(f"primitive index {bad.ravel()[0]!r} out of range 0..{self.n - 1}")
        if idx.shape != (len(poses),):
            raise ValueError(f"need one primitive index per pose: {idx.shape} indices for {len(poses)} poses")
        local = self.local_paths[idx]
        c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
        out = np.empty_like(local)
        out[..., 0] = poses[:, 0:1] + c * local[..., 0] - s * local[..., 1]
        out[..., 1] = poses[:, 1:2] + s * local[..., 0] + c * local[..., 1]
        out[..., 2] = poses[:, 2:3] + local[..., 2]
        return out

    def end_pose(self, pose: np.ndarray, index: int) -> np.ndarray:
        """The pose after applying primitive ``index`` from ``pose``."""
        return self.path_from(pose, index)[-1]

    def path_lengths(self) -> np.ndarray:
        """Arc length of every primitive (m)."""
        d = np.diff(self.local_paths[..., :2], axis=1)
        return np.linalg.norm(d, axis=-1).sum(axis=1)


def primitive_offsets(cfg: PrimitiveConfig) -> np.ndarray:
    """Lateral end offsets ``(n,)`` of the library's primitives, evenly spaced, right to left."""
    return np.linspace(-cfg.lateral_spread, cfg.lateral_spread, cfg.n)


def s_curve(offsets: np.ndarray, advance: float, s: np.ndarray) -> np.ndarray:
    """The primitives' S-curves at path parameters ``s``: poses ``(len(offsets), len(s), 3)``.

    ``x = advance s``, ``y = d (1 - cos(pi s)) / 2`` and the heading tangent to the path. This is
    the one place the formula is written: the library records it, planners sample it.
    """
    offsets = np.asarray(offsets, float)
    s = np.asarray(s, float)
    x = np.broadcast_to(advance * s, (len(offsets), len(s)))
    y = offsets[:, None] * (1.0 - np.cos(np.pi * s))[None] / 2.0
    dy_ds = offsets[:, None] * (np.pi / 2.0) * np.sin(np.pi * s)[None]
    yaw = np.arctan2(dy_ds, advance)
    return np.stack([x, y, yaw], axis=-1).astype(np.float64)


def make_library(cfg: PrimitiveConfig | None = None) -> PrimitiveLibrary:
    """Record the primitive library described by ``cfg``."""
    cfg = cfg or PrimitiveConfig()
    if cfg.n < 1 or cfg.samples < 2 or cfg.advance <= 0 or cfg.lateral_spread < 0:
        raise ValueError(f"invalid primitive config: {cfg}")
    offsets = primitive_offsets(cfg)
    paths = s_curve(offsets, cfg.advance, np.linspace(0.0, 1.0, cfg.samples))
    paths.setflags(write=False)
    offsets.setflags(write=False)
    return PrimitiveLibrary(cfg, offsets, paths)
