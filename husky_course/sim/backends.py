"""Choose a simulator backend by name: ``"fast"`` (numpy) or ``"pybullet"`` (the reference).

PyBullet is imported only when the ``"pybullet"`` backend is built, so the course's fast path
(collection, training, evaluation) never loads it.
"""

from __future__ import annotations

from ..config import ConfigError, SimConfig
from .base import Simulator
from .fast import FastSimulator

BACKENDS = ("fast", "pybullet")


def check_backend(name: str) -> str:
    """Return ``name`` if it is a backend, else raise :class:`~husky_course.config.ConfigError`."""
    if name not in BACKENDS:
        raise ConfigError(f"unknown backend {name!r}: choose one of {', '.join(BACKENDS)}")
    return name


def make_simulator(backend: str = "fast", config: SimConfig | None = None) -> Simulator:
    """A new simulator of the named backend (use it as a context manager to close it)."""
    if check_backend(backend) == "fast":
        return FastSimulator(config)
    from .pybullet_backend import PyBulletSimulator

    return PyBulletSimulator(config)
