"""husky_course: learning-based motion planning for a Husky robot with motion primitives.

The library reads as the paper's pipeline, one folder per stage, each importing only from the
stages before it (``tests/test_layout.py`` checks this):

``config``, ``checks``, ``progress`` (the floor: numbers, input checks, progress bars)
-> ``sim/`` (worlds, primitives, camera, the two backends, the lattice search, the Gymnasium env)
-> ``data/`` (collection, the dataset, splits, simulator labels, calibration, the artifact store)
-> ``models/`` -> ``training/`` -> ``planners/`` -> ``evaluation/``
-> ``course/`` (diagnosis, exercises) and ``ui/`` (plots, widgets) -> ``cli``.

The Gymnasium environment :data:`ENV_ID` (``HuskyNav-v0``) is registered without importing Gymnasium
here (``import husky_course.config`` does not need it): importing the package registers it when
Gymnasium is already imported (``import gymnasium`` first, as sorted imports put it), and importing
its module, ``husky_course.sim.env``, always does. Then ``gymnasium.make("HuskyNav-v0")`` works.
"""

from __future__ import annotations

import sys

__version__ = "0.1.0"

ENV_ID = "HuskyNav-v0"  #: the Gymnasium id of :class:`husky_course.sim.env.HuskyNavEnv`


def register_env() -> None:
    """Register :data:`ENV_ID` with Gymnasium (imported here, so only when called); idempotent."""
    from gymnasium.envs.registration import register, registry

    if ENV_ID not in registry:
        register(id=ENV_ID, entry_point="husky_course.sim.env:HuskyNavEnv")


if sys.modules.get("gymnasium") is not None:  # already loaded: registering costs nothing more
    register_env()
