"""The calibration behind the paper's one hard number: 4.4 primitives per random-policy video.

The paper fixes the course (10 x 10 m, 20 cylinders) and the random policy, and reports that its
videos last 4.4 primitives on average (the colliding one counted), but not the obstacle radii.
:func:`calibrate` re-runs the sweep that chose them: for each candidate radius range it plays
random-policy videos (no images are rendered: only their lengths count) in worlds of a seed other
than the dataset's and reports the mean length with a 95% interval. The range whose interval
holds the target, nearest to it, is the one the config uses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..checks import check_int
from ..config import CalibrationConfig, SimConfig
from ..progress import tqdm
from ..sim.fast import FastSimulator
from .collect import play_video, world_seed_for

#: two-sided 95% normal quantile (the means are over hundreds of videos)
Z95 = 1.959963984540054


def video_lengths(config: SimConfig, videos: int, seed: int) -> np.ndarray:
    """Primitives applied per random-policy video (the colliding one counted), ``(videos,)``.

    The videos are exactly those :func:`~husky_course.data.collect.collect` would record for
    collection ``seed`` (same worlds, same primitives), without their images.
    """
    videos = check_int(videos, "the number of calibration videos", 1)
    world_seed_for(check_int(seed, "the calibration seed", 0), videos - 1)  # range check
    sim = FastSimulator(config)
    return np.array(
        [int(play_video(sim, seed, v, config.max_primitives, render=False)["lengths"][0])
         for v in range(videos)]
    )


@dataclass(frozen=True)
class CalibrationRow:
    """One candidate radius range and the random policy's mean video length under it."""

    radius_range: tuple[float, float]
    videos: int
    mean: float
    lo: float  #: 95% interval (normal approximation) on the mean
    hi: float

    def row(self) -> dict:
        """A table row."""
        r0, r1 = self.radius_range
        return {
            "obstacle radius (m)": f"[{r0:.2f}, {r1:.2f}]",
            "videos": self.videos,
            "mean primitives per video": self.mean,
            "95% interval": f"[{self.lo:.2f}, {self.hi:.2f}]",
        }


def mean_interval(lengths: np.ndarray) -> tuple[float, float, float]:
    """``(mean, lo, hi)``: the mean of ``lengths`` and its 95% normal-approximation interval."""
    lengths = np.asarray(lengths, float)
    if lengths.size < 2:
        raise ValueError(f"need at least 2 videos for an interval, got {lengths.size}")
    mean = float(lengths.mean())
    half = Z95 * float(lengths.std(ddof=1)) / math.sqrt(lengths.size)
    return mean, mean - half, mean + half


def calibrate(sim: SimConfig, cal: CalibrationConfig, progress: bool = True) -> list[CalibrationRow]:
    """The sweep: one :class:`CalibrationRow` per candidate in ``cal.radius_ranges``."""
    rows = []
    for radius_range in tqdm(cal.radius_ranges, desc="calibration", disable=not progress):
        config = replace(sim, world=replace(sim.world, radius_range=tuple(radius_range)))
        mean, lo, hi = mean_interval(video_lengths(config, cal.videos, cal.seed))
        rows.append(CalibrationRow(tuple(radius_range), cal.videos, mean, lo, hi))  # type: ignore[arg-type]
    return rows


def best_range(rows: list[CalibrationRow], target: float) -> CalibrationRow:
    """The row whose mean is nearest ``target`` (ties: the first)."""
    if not rows:
        raise ValueError("no calibration rows to choose from")
    return min(rows, key=lambda r: abs(r.mean - target))
