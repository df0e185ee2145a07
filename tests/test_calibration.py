"""The calibration behind the paper's 4.4 primitives per video (``husky_course.data.calibration``)."""

from __future__ import annotations

import numpy as np
import pytest

from husky_course.config import get_profile
from husky_course.data.calibration import best_range, calibrate, mean_interval, video_lengths
from husky_course.data.collect import collect
from husky_course.data.dataset import load_dataset, stats

QUICK = get_profile("quick")


def test_calibration_reproduces_the_dataset_and_pins_the_quick_mean(tmp_path):
    """The calibration counts exactly the videos collection records; the quick mean is pinned."""
    ds = load_dataset(collect(tmp_path / "ds", QUICK, videos=60, seed=2, progress=False))
    np.testing.assert_array_equal(video_lengths(QUICK.sim, 60, 2), ds.lengths)
    assert stats(ds)["mean_primitives_per_video"] == pytest.approx(ds.lengths.mean())
    quick = video_lengths(QUICK.sim, QUICK.data.videos, QUICK.data.seed)
    assert quick.mean() == pytest.approx(4.476)  # the quick dataset's mean (1,000 videos, seed 0)
    mean, lo, hi = mean_interval(quick)
    assert lo <= QUICK.calibration.target <= hi  # consistent with the paper's 4.4


def test_calibration_sweep_chooses_the_configured_radius_range():
    rows = calibrate(QUICK.sim, QUICK.calibration, progress=False)
    means = [r.mean for r in rows]
    assert means == sorted(means, reverse=True)  # bigger obstacles, shorter videos
    best = best_range(rows, QUICK.calibration.target)
    assert best.radius_range == QUICK.sim.world.radius_range
    assert best.lo <= QUICK.calibration.target <= best.hi
