"""husky_course: learning-based motion planning for a Husky robot with motion primitives.

The library follows the course's pipeline, one module per stage:
``config`` -> ``world``/``primitives``/``camera`` -> ``sim`` (``fast_sim``, ``pybullet_sim``,
``backends``) -> ``env`` -> ``collect``/``dataset`` -> ``artifacts``, with ``plotting`` and
``widgets`` on top. Importing the package registers the Gymnasium environment ``HuskyNav-v0``.
"""

from __future__ import annotations

__version__ = "0.1.0"

from gymnasium.envs.registration import register, registry  # noqa: E402

if "HuskyNav-v0" not in registry:
    register(id="HuskyNav-v0", entry_point="husky_course.env:HuskyNavEnv")
