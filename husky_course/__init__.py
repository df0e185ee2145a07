"""husky_course: learning-based motion planning for a Husky robot with motion primitives.

The library reads as the paper's pipeline, one folder per stage, each importing only from the
stages before it (``tests/test_layout.py`` checks this):

``config``, ``checks``, ``progress`` (the floor: numbers, input checks, progress bars)
-> ``sim/`` (worlds, primitives, camera, the two backends, the lattice search, the Gymnasium env)
-> ``data/`` (collection, the dataset, splits, simulator labels, calibration, the artifact store)
-> ``models/`` -> ``training/`` -> ``planners/`` -> ``evaluation/``
-> ``course/`` (diagnosis, exercises) and ``ui/`` (plots, widgets) -> ``cli``.

Importing the package registers the Gymnasium environment ``HuskyNav-v0``.
"""

from __future__ import annotations

__version__ = "0.1.0"

from gymnasium.envs.registration import register, registry  # noqa: E402

if "HuskyNav-v0" not in registry:
    register(id="HuskyNav-v0", entry_point="husky_course.sim.env:HuskyNavEnv")
