"""The side walls as the moving course's planners know them: where their faces are, and the walk of
a cylinder that bounces off them.

A walking cylinder of the moving course reflects off the side walls (a triangle wave in time,
:meth:`~husky_course.sim.world.World.obstacle_y`). Dead reckoning gives the robot its displacement,
not its place in the course (the start's ``y`` is unknown to it), so it reads the walls' faces off
what it has seen: the remembered points no disc explains (:class:`~husky_course.planners.discs.DiscMap`'s
wall points; the tracker's :class:`~husky_course.planners.motion.WalkingMap`: the points of pieces
over 1 m) that lie further than ``beyond`` to a side and crowd into one ``bin`` of lateral position
(a wall seen along the course puts many points on one line). The course's width gives the other
face. Until a face has been seen, nothing bounces (the faces are at infinity).
"""

from __future__ import annotations

import numpy as np

from ..config import WallsConfig

NO_WALLS = (-np.inf, np.inf)


def wall_faces(points: np.ndarray, width: float, previous: tuple[float, float] = NO_WALLS,
               config: WallsConfig | None = None) -> tuple[float, float]:
    """``(right, left)`` lateral positions of the walls' faces in the robot's frame, read off
    ``points`` ``(m, 2+)`` (robot frame; see the module), or ``previous`` when no face shows."""
    cfg = config or WallsConfig()
    y = np.asarray(points, float)[:, 1]

    def face(side: np.ndarray) -> float | None:
        if len(side) < cfg.points:
            return None
        bins = np.round(side / cfg.bin)
        values, counts = np.unique(bins, return_counts=True)
        best = int(np.argmax(counts))
        return float(np.median(side[bins == values[best]])) if counts[best] >= cfg.points else None

    left = face(y[y > cfg.beyond])
    if left is not None:
        return left - width, left
    right = face(y[y < -cfg.beyond])
    if right is not None:
        return right, right + width
    return previous


def bounced(y: np.ndarray | float, v: np.ndarray | float, t: np.ndarray | float, r: np.ndarray | float,
            faces: tuple[float, float]) -> np.ndarray:
    """Where a cylinder at ``y`` (radius ``r``) walking at ``v`` m per step is after ``t`` steps, reflecting
    off the faces (a cylinder outside them is first put against the nearer one); standing (``v == 0``)
    or with no faces known, ``y + v t``. Arrays broadcast together."""
    y, v, t, r = (np.asarray(a, float) for a in (y, v, t, r))
    straight = y + v * t
    if not np.isfinite(faces[0]) or not np.isfinite(faces[1]):
        return straight
    low, span = faces[0] + r, np.maximum(faces[1] - faces[0] - 2 * r, 1e-6)
    u = np.mod(np.clip(y, low, low + span) - low + v * t, 2 * span)
    return np.where(v == 0, straight, low + span - np.abs(u - span))


def walk_on(discs: np.ndarray, v: np.ndarray, faces: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """``(y, v)`` of ``discs`` ``(m, 3)`` walking at ``v`` ``(m,)`` one step on: where :func:`bounced`
    puts them, and their velocity turned if they bounced."""
    y, r = discs[:, 1], discs[:, 2]
    after = bounced(y, v, 1.0, r, faces)
    return after, np.where(v == 0, v, np.sign(bounced(y, v, 1.001, r, faces) - after) * np.abs(v))


def reflected_line(s: np.ndarray, y: np.ndarray, w: np.ndarray, faces: tuple[float, float], radius: float,
                   scale: float, gain: float) -> tuple[float, float] | None:
    """``(y at s = 0, velocity)`` of a cylinder's looks ``(s, y)`` (times ``s <= 0`` in steps, weights ``w``)
    read as a walk that bounced off a face between two looks, or ``None`` when no bounce fits better.

    A bounce folds a straight walk (:func:`bounced`): the looks before it, reflected about the face
    (less ``radius``, where the centre turns), lie on one line with the looks after it. Each face and
    each gap between looks is tried; a fold counts only where the unfolded line crosses the face within
    that gap (a quarter step either side) and walks away from it afterwards, and only where its
    weighted squared residual (over ``scale**2``, the sightings' error as :class:`~.motion.Tracks`
    judges it) is lower than the straight line's by more than ``gain``. ``y at s = 0`` is the unfolded
    line's, the velocity its slope (the walk after the last bounce). Three looks at least, both faces known.
    """
    if len(s) < 3 or not (np.isfinite(faces[0]) and np.isfinite(faces[1])):
        return None

    def fit(values: np.ndarray) -> tuple[float, float, float]:
        sm, ym = np.average(s, weights=w), np.average(values, weights=w)
        b = float(np.sum(w * (s - sm) * (values - ym)) / np.sum(w * (s - sm) ** 2))
        a = float(ym - b * sm)
        return a, b, float(np.sum(w * (values - a - b * s) ** 2)) / scale**2

    best, found = fit(y)[2] - gain, None
    for turn, away in ((faces[1] - radius, -1.0), (faces[0] + radius, 1.0)):
        for k in range(1, len(s)):
            a, b, chi = fit(np.r_[2 * turn - y[:k], y[k:]])
            if chi >= best or b * away <= 0:
                continue
            if s[k - 1] - 0.25 <= (turn - a) / b <= s[k] + 0.25:
                best, found = chi, (a, b)
    return found
