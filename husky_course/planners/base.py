"""The planner protocol: choose the next motion primitive from the onboard depth image.

Every planner follows one protocol, used by :func:`husky_course.evaluation.episodes.run_episode`:
``reset(sim, pose)`` at the start of an episode, then per step ``act(obs, pose) -> index`` and
``observe(action, next_obs)`` (``next_obs`` is ``None`` after a collision). ``act`` leaves the
per-primitive scores it used in ``last_scores`` (shape ``(n,)``, *lower is better*) for plots.

Only the oracle (:mod:`~husky_course.planners.oracle`) may use the simulator or the true pose; the
others see depth images. The non-learned planners live in :mod:`~husky_course.planners.classic`,
the learned ones in :mod:`~husky_course.planners.learned`, and
:mod:`~husky_course.planners.registry` builds any of them by name.
"""

from __future__ import annotations

import numpy as np

from ..checks import is_int
from ..config import SimConfig
from ..sim.base import Simulator

_CAMERA_SIZE = SimConfig().camera.size


class PlannerError(ValueError):
    """An unknown planner, a bad planner argument, or a planner that cannot be built."""


def check_observation(obs: object, size: int = _CAMERA_SIZE) -> np.ndarray:
    """Return ``obs`` as a float32 ``(size, size)`` depth image in [0, 1], or raise ``ValueError``."""
    if not isinstance(obs, np.ndarray):
        raise ValueError(f"observation must be a numpy array, got {type(obs).__name__}")
    if obs.shape != (size, size):
        raise ValueError(f"observation must have shape ({size}, {size}), got {obs.shape}")
    if not np.issubdtype(obs.dtype, np.floating):
        raise ValueError(f"observation must be a float depth image (float32), got dtype {obs.dtype}")
    if not np.isfinite(obs).all():
        raise ValueError("observation contains NaN or inf values")
    if obs.min() < 0.0 or obs.max() > 1.0:
        raise ValueError(f"observation must be normalised depth in [0, 1], got [{obs.min()}, {obs.max()}]")
    return obs.astype(np.float32, copy=False)


def check_look_ahead(k: object) -> int:
    """Return the look-ahead ``k`` as an int >= 0, or raise :class:`PlannerError`."""
    if not is_int(k) or k < 0:  # type: ignore[operator]
        raise PlannerError(f"look_ahead must be a non-negative integer, got {k!r}")
    return int(k)


class Planner:
    """Base class. Subclasses implement :meth:`act` and may override :meth:`reset`/:meth:`observe`."""

    name: str = "base"

    def __init__(self) -> None:
        self.last_scores: np.ndarray | None = None

    def reset(self, sim: Simulator, pose: np.ndarray) -> None:
        """Start an episode in ``sim``'s loaded world at ``pose`` (only the oracle may keep ``sim``)."""
        self.last_scores = None

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        """The primitive index to apply, given the depth image ``obs`` (and, for the oracle, ``pose``)."""
        raise NotImplementedError

    def observe(self, action: int, obs_next: np.ndarray | None) -> None:
        """Hook called after each step with the next image (``None`` after a collision)."""
