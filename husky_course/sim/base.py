"""The simulator interface that both backends implement.

A simulator holds one :class:`~husky_course.sim.world.World` at a time and answers two questions:
what does the onboard camera see from a pose (:meth:`Simulator.depth`), and does playing a
primitive back from a pose touch an obstacle (:meth:`Simulator.apply`). The primitive library,
the playback and the collision rule live here, so the backends differ only in geometry queries.

Every query takes the time ``t`` in primitive steps (default 0; see :mod:`husky_course.sim.world`):
an image at time ``t`` sees the cylinders where they are at ``t``, and a primitive started at ``t``
is checked sample by sample against the cylinders at ``t + s / (S - 1)``. Static worlds ignore it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config import SimConfig
from .primitives import PrimitiveLibrary, make_library
from .sensing import executed_path, noisy_depth
from .world import World, make_world, pose_times


@dataclass(frozen=True)
class StepResult:
    """Outcome of playing one primitive back.

    Attributes
    ----------
    collided : bool
        Whether the robot's collision cylinder touched an obstacle or wall along the path.
    pose : ndarray, shape (3,)
        Where the robot ends: the primitive's end pose if safe, otherwise the last recorded pose
        before the first contact.
    path : ndarray, shape (samples, 3)
        The recorded poses that were played back.
    """

    collided: bool
    pose: np.ndarray
    path: np.ndarray


class Simulator:
    """Base class: primitive playback and the collision rule. Backends fill in the geometry."""

    name = "base"

    def __init__(self, config: SimConfig | None = None) -> None:
        self.config = config or SimConfig()
        self.library: PrimitiveLibrary = make_library(self.config.primitives)
        self.world: World | None = None

    # --- world -------------------------------------------------------------------------------
    def load(self, world: World | int) -> World:
        """Load ``world`` (or the world of an integer seed) and return it."""
        if not isinstance(world, World):
            world = make_world(world, self.config.world)
        self.world = world
        self._load(world)
        return world

    def _require_world(self) -> World:
        if self.world is None:
            raise RuntimeError("no world loaded: call load(world_or_seed) first")
        return self.world

    # --- queries backends implement ------------------------------------------------------------
    def _load(self, world: World) -> None:
        raise NotImplementedError

    def _depth(self, poses: np.ndarray, t: np.ndarray | float = 0.0) -> np.ndarray:
        """The renderer's normalised depth images (what :meth:`depth` reports under ideal sensing)."""
        raise NotImplementedError

    def depth(self, poses: np.ndarray, t: np.ndarray | float = 0.0) -> np.ndarray:
        """Normalised depth images ``(B, size, size)`` float32 in [0, 1] for robot poses ``(B, 3)``
        at times ``t`` (a number, or one per pose), as the camera reports them: the renderer's
        under ideal sensing, else with the sensor's noise (:mod:`husky_course.sim.sensing`)."""
        images = self._depth(poses, t)
        sensing = self.config.sensing
        if sensing.camera_ideal:
            return images
        poses = np.asarray(poses, float).reshape(-1, 3)
        world = self._require_world()
        return noisy_depth(images, poses, pose_times(t, len(poses)), world.seed, sensing, self.config.camera)

    def rgb(self, pose: np.ndarray, t: float = 0.0) -> np.ndarray:
        """An RGB view ``(size, size, 3)`` uint8 from the onboard camera at time ``t``, for display."""
        raise NotImplementedError

    def contact_along(self, path: np.ndarray, t: float = 0.0) -> int:
        """Index of the first pose of ``path (S, 3)`` whose collision cylinder touches, or -1; the
        path is a primitive started at time ``t`` (its samples at ``t + s / (S - 1)``)."""
        raise NotImplementedError

    def close(self) -> None:
        """Release backend resources (safe to call twice)."""

    # --- shared logic --------------------------------------------------------------------------
    def play(self, pose: np.ndarray, index: int, t: float = 0.0) -> StepResult:
        """Play primitive ``index`` back from ``pose`` exactly as the library says (the nominal path,
        whatever the wheels do): what a planner that trusts the library predicts. Under ideal wheels
        it is :meth:`apply`."""
        self._require_world()
        return self._outcome(self.library.path_from(pose, index), t)

    def _outcome(self, path: np.ndarray, t: float) -> StepResult:
        hit = self.contact_along(path, t)
        if hit < 0:
            return StepResult(False, path[-1].copy(), path)
        return StepResult(True, path[max(hit - 1, 0)].copy(), path)

    def apply(self, pose: np.ndarray, index: int, t: float = 0.0) -> StepResult:
        """Play primitive ``index`` back from ``pose``, starting at time ``t``, against the loaded world
        (the path the wheels execute: the library's under ideal sensing, :mod:`husky_course.sim.sensing`)."""
        world = self._require_world()
        return self._outcome(executed_path(self.library, pose, index, self.config.sensing, world.seed, t), t)

    def __enter__(self) -> Simulator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
