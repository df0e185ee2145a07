"""A depth scan's pieces of surface: where one thing ends and the next begins, and where each is.

What every planner that reads pieces shares: the disc network's features
(:mod:`~husky_course.planners.discs`), the cut network (:mod:`~husky_course.planners.cuts`) and the
tracks of the moving course (:mod:`~husky_course.planners.motion`). It is a module of its own so
that the networks trained on these pieces depend on the cut alone: an edit of how tracks follow
pieces retrains no network that never reads a track.

* :func:`segments` cuts a scan (points in column order) into pieces of surface: neighbouring points
  closer than ``gap``, or than ``spacing`` times their forward distance (the camera's columns
  spread apart with distance), belong to the same piece (a cylinder's visible arc, a stretch of
  wall), and :func:`split_arcs` cuts a piece again where two arcs meet (two cylinders side by side);
* :func:`piece_centre` locates a piece: a circle fitted to its points, its radius held near the
  course's typical radius, its centre behind the points as seen from the camera (a piece over 1 m
  long is a wall, or several things: its mean). A cylinder's centre moves only with the cylinder,
  where the mean of its visible points also moves as the robot's viewpoint changes which columns
  hit it (``benchmarks/exp_moving_tracker.py`` measures both).
"""

from __future__ import annotations

import numpy as np


def segments(points: np.ndarray, gap: float = 0.3, spacing: float = 0.0) -> list[np.ndarray]:
    """Index arrays of the pieces of surface in a scan ``(m, 2)`` given in column order (see the module)."""
    if not len(points):
        return []
    step = np.linalg.norm(np.diff(points[:, :2], axis=0), axis=1)
    limit = np.maximum(gap, spacing * np.maximum(points[:-1, 0], points[1:, 0]))
    starts = np.r_[0, np.flatnonzero(step > limit) + 1]
    ends = np.r_[starts[1:], len(points)]
    return [part for a, b in zip(starts, ends, strict=True) for part in split_arcs(points[:, 0], a, b)]


def split_arcs(x: np.ndarray, a: int, b: int, prominence: float = 0.03) -> list[np.ndarray]:
    """Columns ``a:b`` of one piece, cut where two arcs meet.

    A cylinder's visible arc comes nearest the camera in its middle: along the columns its forward
    distance ``x`` falls, then rises. Where it rises and falls again by more than ``prominence``
    (a peak between two valleys), two cylinders side by side, or one partly behind the other,
    joined into one piece: cut after the peak (the first of two equal points). A wall along the
    course (``x`` rising or falling across the columns) has no such peak and stays whole.
    """
    xs = x[a:b]
    before = np.minimum.accumulate(xs)  # xs[: i + 1].min()
    after = np.minimum.accumulate(xs[::-1])[::-1]  # xs[i:].min()
    mid = xs[1:-1]
    prominent = np.minimum(mid - before[1:-1], mid - after[1:-1]) > prominence
    peak = (mid > xs[:-2]) & (mid >= xs[2:]) & prominent
    edges = [a, *(a + 2 + np.flatnonzero(peak)).tolist(), b]
    return [np.arange(lo, hi) for lo, hi in zip(edges[:-1], edges[1:], strict=True)]


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
    m = len(p)  # the system's rows: one per point, and the prior's on r (filled in place, not stacked
    jac, rhs = np.empty((m + 1, 3)), np.empty(m + 1)  # anew: the same numbers, 1.7 times as fast)
    jac[:m, 2], jac[m] = -1.0, (0.0, 0.0, 1.0)
    for _ in range(iterations):
        d = p - c
        n = np.hypot(d[:, 0], d[:, 1]) + 1e-9
        jac[:m, :2] = -d / n[:, None]
        rhs[:m], rhs[m] = n - r, r - radius
        step = np.linalg.lstsq(jac, -rhs, rcond=None)[0]
        c, r = c + step[:2], float(np.clip(r + step[2], 0.4 * radius, 2.0 * radius))
    return c
