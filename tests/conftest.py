"""Shared fixtures: a small dataset built once per test session (quick profile, fast backend)."""

from __future__ import annotations

import os

import matplotlib
import pytest

from husky_course.config import get_profile

QUICK = get_profile("quick")  # resolved once, passed down

os.environ.setdefault("HUSKY_PROFILE", "quick")
# Headless plotting for the unit tests only. Not via MPLBACKEND: notebook kernels inherit the
# environment, and MPLBACKEND=Agg there would replace the inline backend and drop every figure.
matplotlib.use("Agg")


@pytest.fixture(scope="session")
def small_dataset_dir(tmp_path_factory: pytest.TempPathFactory):
    from husky_course.data.collect import collect

    out = tmp_path_factory.mktemp("ds") / "data"
    collect(out, QUICK, videos=120, seed=3, workers=1, progress=False)
    return out
