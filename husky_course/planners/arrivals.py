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

:meth:`Arrivals.read` adds the evidence of the last few images' columns (``images`` of them): a
hypothesis places the cylinder ``age`` steps back at ``age`` times its walk, which predicts the depth
of every column its circle covers in that image. A column that saw *through* that circle rules the
hypothesis out; one whose depth lies within ``evidence_tolerance`` of it *matches* (a nearer depth
hides it: no evidence). Among the hypotheses left, those with the most matching columns (one at
least) decide: a walk one way (their mean), or standing; else the rule above stands. Chosen on the
tuning set (evaluation set 1, full profile, the disc planner; ``benchmarks/exp_moving_evidence.py``):
on worlds 0-999 / 1,000-1,999 / 2,000-2,999 the rule above crossed 0.780 / 0.776 / 0.795, with the
previous image's evidence 0.794 / 0.788 / 0.802, with the last three images' 0.798 / 0.793 / 0.811.

:meth:`Arrivals.weights` gives, for a first sight both rules leave standing undecided, the course's
motion model over the hypotheses no column saw through: what the disc planner draws its walk from
at every decision (:class:`~husky_course.config.ArrivalsConfig`'s ``samples``; the measurements are
there).
"""

from __future__ import annotations

import numpy as np

from ..config import ArrivalsConfig, SimConfig
from ..sim.camera import pixel_tangents


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
    images : int
        Previous images whose columns :meth:`read` weighs (0: the previous image's centre column only).
    evidence_tolerance : float
        Metres within which a column's depth matches a hypothesised circle (and beyond which it
        saw through it), in :meth:`read`.
    """

    def __init__(self, config: SimConfig, tolerance: float = ArrivalsConfig.tolerance,
                 hypotheses: int = ArrivalsConfig.hypotheses, images: int = ArrivalsConfig.images,
                 evidence_tolerance: float = ArrivalsConfig.evidence_tolerance) -> None:
        if images < 0 or evidence_tolerance <= 0:
            raise ValueError(f"need images >= 0, evidence_tolerance > 0; got {images}, {evidence_tolerance}")
        self.camera = config.camera
        self.half = float(np.tan(np.radians(self.camera.fov_deg) / 2))
        self.u = pixel_tangents(self.camera)[0]  #: each column's lateral tangent
        self.images, self.evidence_tolerance = int(images), float(evidence_tolerance)
        lo, hi = getattr(config.world, "speed_range", (0.0, 0.0))
        walks = np.linspace(lo, hi, hypotheses) if hi > 0 else np.empty(0)
        self.hypotheses = np.r_[0.0, walks, -walks]  #: velocities (m per step); standing first
        self.tolerance = float(tolerance)
        self.reset()

    def reset(self) -> None:
        """Forget the previous images (a new episode)."""
        self.depth: np.ndarray | None = None
        self.shift = np.zeros(2)
        self.history: list[tuple[np.ndarray, np.ndarray]] = []  #: ``(depth, shift)``, newest first

    def remember(self, depth: np.ndarray) -> None:
        """Keep this image's per-column depth ``(size,)`` (``inf`` where nothing is seen)."""
        self.depth, self.shift = np.asarray(depth, float).copy(), np.zeros(2)
        self.history = [(self.depth, self.shift), *self.history][: max(self.images, 1)]

    def move(self, dx: float, dy: float) -> None:
        """Dead reckoning: the robot moved by ``(dx, dy)`` since the remembered images."""
        for _, shift in self.history:  # the newest's shift is :attr:`shift`
            shift += (dx, dy)

    def read(self, discs: np.ndarray) -> np.ndarray:
        """Velocity ``(k,)`` of first-sight cylinders ``discs (k, 3)``: :meth:`speeds`, overruled by
        :meth:`evidence` where the last :attr:`images` images' columns decide (see the module)."""
        out = self.speeds(discs)
        told = self.evidence(discs)
        return np.where(np.isnan(told), out, told)

    def evidence(self, discs: np.ndarray) -> np.ndarray:
        """Velocity ``(k,)`` of ``discs (k, 3)`` that the last :attr:`images` images' columns decide,
        ``nan`` where they do not (see the module)."""
        discs = np.asarray(discs, float).reshape(-1, 3)
        out = np.full(len(discs), np.nan)
        if not self.images or len(self.hypotheses) < 2:
            return out
        through, match = self.columns(discs)
        for k in range(len(discs)):
            left = through[k] == 0
            if not left.any() or match[k, left].max() < 1:
                continue
            best = self.hypotheses[left & (match[k] == match[k, left].max())]
            if np.all(best > 0) or np.all(best < 0):
                out[k] = float(best.mean())
            elif np.all(best == 0):
                out[k] = 0.0
        return out

    def columns(self, discs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(through, match)``, each ``(k, hypotheses)``: per disc of ``discs (k, 3)`` and hypothesis,
        the columns of the last :attr:`images` images that saw through its circle, and that matched it."""
        discs = np.asarray(discs, float).reshape(-1, 3)
        tol, far, h = self.evidence_tolerance, self.camera.far, self.hypotheses
        through, match = np.zeros((len(discs), len(h)), int), np.zeros((len(discs), len(h)), int)
        for k, (x, y, r) in enumerate(discs):
            for age, (depth, shift) in enumerate(self.history[: self.images], start=1):
                front = self.front(x + shift[0], y + shift[1] - h * age, r)  # (hypotheses, size)
                near = front < far - tol
                with np.errstate(invalid="ignore"):  # inf - inf off the circle: masked by ``near``
                    through[k] += np.sum(near & (depth > front + tol), axis=1)
                    match[k] += np.sum(near & (np.abs(depth - front) <= tol), axis=1)
        return through, match

    def weights(self, discs: np.ndarray, fraction: float) -> np.ndarray:
        """``(k, hypotheses)``: for each first-sight disc of ``discs (k, 3)`` that :meth:`read` leaves
        standing undecided (neither the columns' evidence nor the centre rule decides), the course's
        motion model (standing ``1 - fraction``, each walk an equal share of ``fraction``) over the
        hypotheses no column of the last :attr:`images` images saw through, normalised; a row of
        zeros where :meth:`read`'s velocity stands (decided, or every hypothesis seen through)."""
        discs = np.asarray(discs, float).reshape(-1, 3)
        h = self.hypotheses
        out = np.zeros((len(discs), len(h)))
        if len(h) < 2 or not len(discs) or fraction <= 0:
            return out
        prior = np.r_[1.0 - fraction, np.full(len(h) - 1, fraction / (len(h) - 1))]
        left = self.columns(discs)[0] == 0 if self.images else np.ones(out.shape, bool)
        open_ = np.isnan(self.evidence(discs)) & (self.speeds(discs) == 0) & left.any(1)
        w = prior * left
        out[open_] = w[open_] / w[open_].sum(1, keepdims=True)
        return out

    def front(self, x: float, y: np.ndarray, r: float) -> np.ndarray:
        """Depth ``(len(y), size)`` at which each column's ray meets the circle of radius ``r`` centred
        at ``(x, y_i)`` (robot frame), ``inf`` where it misses."""
        u, cx = self.u[None], x - self.camera.mount_forward
        y = np.asarray(y, float)[:, None]
        a, b, c = 1.0 + u**2, cx + u * y, cx**2 + y**2 - r**2
        root = b**2 - a * c
        d = (b - np.sqrt(np.maximum(root, 0.0))) / a
        return np.where((root > 0) & (d > 0), d, np.inf)

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
