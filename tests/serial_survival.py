"""The survival labels computed the plain way, one image after another in this process: the reference
the tests hold ``husky_course.data.labels.survival_steps_parallel`` (chunks, on any engine) to."""

from __future__ import annotations

import numpy as np

from husky_course.config import SimConfig
from husky_course.data.dataset import Dataset
from husky_course.data.labels import best_continuations
from husky_course.sim.fast import FastSimulator


def survival_steps(ds: Dataset, horizon: int, idx: np.ndarray, config: SimConfig | None = None) -> np.ndarray:
    """Steps (0..``horizon``) the best continuation starting with each primitive survives from each
    image ``idx`` (at its pose and time), ``(len(idx), 25)`` int8."""
    sim = FastSimulator(config)
    out = np.zeros((len(idx), sim.library.n), np.int8)
    for row, i in enumerate(np.asarray(idx)):
        seed = int(ds.world_seeds[ds.episode[i]])
        if sim.world is None or sim.world.seed != seed:
            sim.load(seed)
        out[row] = best_continuations(sim, np.asarray(ds.poses[i], float), horizon, float(ds.step[i]))
    return out
