"""The planner protocol: choose the next motion primitive from the onboard depth image.

Every planner follows one protocol, used by :func:`husky_course.evaluation.episodes.run_episode`:
``reset(start)`` at the start of an episode (an :class:`EpisodeStart`), then per step
``act(obs, pose) -> index`` and ``observe(action, next_obs)`` (``next_obs`` is ``None`` after a
collision). ``act`` leaves the per-primitive scores it used in ``last_scores`` (shape ``(n,)``,
*lower is better*) for plots.

**Privileged information.** A planner declares ``privileged = True`` to be given the simulator
(with the world loaded) and the true pose: only the oracle (:mod:`~husky_course.planners.oracle`)
and the references of :mod:`~husky_course.planners.reference` (analysis only, never in a table of
camera-based planners) do. Every other planner receives, and can only receive, what the robot
has: its depth images, the primitives it applied (through :meth:`Planner.observe`) and its own
primitive library (the motion it knows it makes); ``start.sim``, ``start.pose`` and ``act``'s
``pose`` are ``None``. ``tests/test_privileged.py`` checks this. The non-learned planners live in
:mod:`~husky_course.planners.classic`,
the learned ones in :mod:`~husky_course.planners.learned`, and
:mod:`~husky_course.planners.registry` builds any of them by name.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

from ..checks import is_int
from ..config import SimConfig
from ..sim.base import Simulator
from ..sim.primitives import PrimitiveLibrary

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


def episode_key(world_seed: int) -> int:
    """An opaque 63-bit number per world, to seed a planner's own randomness.

    A planner must not get the world seed itself: :func:`husky_course.sim.world.make_world` would
    rebuild the whole world from it. A hash gives the same per-episode reproducibility and says
    nothing about the world.
    """
    digest = hashlib.sha256(f"husky-episode-{int(world_seed)}".encode()).digest()
    return int.from_bytes(digest[:8], "little") >> 1


@dataclass(frozen=True)
class EpisodeStart:
    """What a planner is told when an episode starts.

    Attributes
    ----------
    library : PrimitiveLibrary
        The robot's own primitives: it knows how each one moves it (dead reckoning).
    max_primitives : int
        Primitives in a full episode (the course is crossed after this many).
    key : int
        An opaque per-episode number (:func:`episode_key`) for a planner's own randomness.
    sim, pose :
        The simulator with the world loaded and the true start pose: given to privileged
        planners only, ``None`` for every other.
    """

    library: PrimitiveLibrary
    max_primitives: int
    key: int
    sim: Simulator | None = None
    pose: np.ndarray | None = None


def episode_start(
    planner: Planner, sim: Simulator, world_seed: int, pose: np.ndarray, max_primitives: int
) -> EpisodeStart:
    """What ``planner`` may know at the start of an episode in ``sim``'s loaded world at ``pose``.

    The simulator and the pose go to privileged planners (the oracle) only.
    """
    privileged = planner.privileged
    return EpisodeStart(
        library=sim.library,
        max_primitives=int(max_primitives),
        key=episode_key(int(world_seed)),
        sim=sim if privileged else None,
        pose=np.array(pose, float) if privileged else None,
    )


class Planner:
    """Base class. Subclasses implement :meth:`act` and may override :meth:`reset`/:meth:`observe`."""

    name: str = "base"
    #: True only for planners allowed the simulator and the true pose (the oracle)
    privileged: bool = False

    def __init__(self) -> None:
        self.last_scores: np.ndarray | None = None

    def reset(self, start: EpisodeStart) -> None:
        """Start an episode (see :class:`EpisodeStart`; ``sim``/``pose`` only if privileged)."""
        self.last_scores = None

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        """The primitive index to apply, given the depth image ``obs`` (``pose``: privileged only)."""
        raise NotImplementedError

    def observe(self, action: int, obs_next: np.ndarray | None) -> None:
        """Hook called after each step with the next image (``None`` after a collision)."""


def survival_scores(s: np.ndarray, smooth: int) -> np.ndarray:
    """Scores (lower is better) from predicted survival ``s``: survive longest, and among ties take
    the middle of the widest free corridor (neighbours within ``smooth`` also predicted safe)."""
    k = 2 * smooth + 1
    padded = np.pad(s, smooth, mode="constant", constant_values=0.0)
    neighbourhood = np.convolve(padded, np.ones(k) / k, mode="valid")
    return -(s + 0.5 * neighbourhood)


def search_start(pose: np.ndarray, sim: Simulator) -> np.ndarray:
    """Where a privileged planner's lattice search starts: the true pose, its heading set to the
    library's 0 under slipping wheels (chapter 11: a few degrees the lattice, whose headings are 0
    between primitives, leaves out)."""
    here = np.asarray(pose, float).copy()
    if not sim.config.sensing.wheels_ideal:
        here[2] = 0.0
    return here
