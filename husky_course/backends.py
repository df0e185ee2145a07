"""Choose a simulator backend by name: ``"fast"`` (numpy) or ``"pybullet"`` (the reference)."""

from __future__ import annotations

from .config import ConfigError, SimConfig
from .fast_sim import FastSimulator
from .pybullet_sim import PyBulletSimulator
from .sim import Simulator

BACKENDS: dict[str, type[Simulator]] = {"fast": FastSimulator, "pybullet": PyBulletSimulator}


def check_backend(name: str) -> str:
    """Return ``name`` if it is a backend, else raise :class:`~husky_course.config.ConfigError`."""
    if name not in BACKENDS:
        raise ConfigError(f"unknown backend {name!r}: choose one of {', '.join(BACKENDS)}")
    return name


def make_simulator(backend: str = "fast", config: SimConfig | None = None) -> Simulator:
    """A new simulator of the named backend (use it as a context manager to close it)."""
    return BACKENDS[check_backend(backend)](config)
