"""Lateral motion from two successive scans: what the moving-course student infers with its memory.

Nothing privileged: the robot keeps the previous image's scan (the points of
:class:`~husky_course.planners.perception.DepthScan`), moves it into the current frame by dead
reckoning, and compares it with the current scan.

* :func:`segments` cuts a scan (points in column order) into pieces of surface: neighbouring points
  closer than ``gap`` belong to the same piece (a cylinder's visible arc, a stretch of wall);
* :func:`lateral_velocities` matches each current piece to the previous piece nearest in ``y``
  among those at about the same forward distance (cylinders move only across the course) and
  within one step's walk, and gives every point of the piece the lateral displacement of the two
  pieces' centres (0 where nothing matches: a piece seen for the first time);
* the moving-course student then reads where the current points will be one and two steps later if
  they keep walking (:meth:`husky_course.planners.memory.MemoryPlanner.prepare`).

A piece's centre moves with what is visible of it, so partial occlusion shows as motion: an
estimate, which the network learns to trust as far as it deserves.
"""

from __future__ import annotations

import numpy as np


def segments(points: np.ndarray, gap: float = 0.3) -> list[np.ndarray]:
    """Index arrays of the pieces of surface in a scan ``(m, 2)`` given in column order."""
    if not len(points):
        return []
    jumps = np.linalg.norm(np.diff(points[:, :2], axis=0), axis=1) > gap
    starts = np.r_[0, np.flatnonzero(jumps) + 1]
    ends = np.r_[starts[1:], len(points)]
    return [np.arange(a, b) for a, b in zip(starts, ends, strict=True)]


def lateral_velocities(
    previous: np.ndarray, current: np.ndarray, max_step: float, x_gate: float = 0.5, gap: float = 0.3
) -> np.ndarray:
    """Estimated lateral displacement per step ``(m,)`` of every point of ``current`` (see the module).

    ``previous`` and ``current`` are scans in the *current* robot frame; ``max_step`` bounds how far
    a piece can move across in one step (a match further away is no match).
    """
    v = np.zeros(len(current))
    before = segments(previous, gap)
    if not before or not len(current):
        return v
    centres = np.array([previous[idx, :2].mean(0) for idx in before])
    for idx in segments(current, gap):
        cx, cy = current[idx, :2].mean(0)
        ok = np.abs(centres[:, 0] - cx) < x_gate
        dy = cy - centres[:, 1]
        ok &= np.abs(dy) <= max_step
        if ok.any():
            v[idx] = dy[ok][np.argmin(np.abs(dy[ok]))]
    return v
