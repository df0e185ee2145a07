"""Build any planner by name: the one place that knows every planner.

The non-learned planners are imported here directly; the learned ones (which need torch and
trained checkpoints) are imported when one is asked for, so ``evaluate --planner heuristic``
never loads torch. Nothing below imports this module, so there is no import circle.
"""

from __future__ import annotations

from typing import Any

from .base import Planner, PlannerError
from .classic import HeuristicPlanner, RandomPlanner
from .mapping import MappingPlanner
from .oracle import OraclePlanner
from .tracking import TrackingPlanner

PLANNERS = (
    "random", "heuristic", "mapping", "tracking", "lookahead", "rnn", "distilled", "memory", "discs",
    "oracle",
)
LEARNED_PLANNERS = ("lookahead", "rnn", "distilled", "memory", "discs")
_CLASSES: dict[str, type[Planner]] = {
    "random": RandomPlanner,
    "heuristic": HeuristicPlanner,
    "mapping": MappingPlanner,
    "tracking": TrackingPlanner,
    "oracle": OraclePlanner,
}


def make_planner(name: str, **kwargs: Any) -> Planner:
    """Build the planner ``name`` (one of :data:`PLANNERS`) with keyword arguments ``kwargs``.

    Learned planners need ``profile=`` (a :class:`~husky_course.config.Profile`) and trained
    checkpoints; :class:`PlannerError` says so when either is missing.
    """
    if name in LEARNED_PLANNERS:
        if "profile" not in kwargs:
            raise PlannerError(
                f"planner {name!r} is learned: pass profile= (husky_course.config.get_profile()) so its "
                "trained checkpoints can be found"
            )
        try:
            from .learned import make_learned_planner
        except ImportError as exc:
            raise PlannerError(
                f"planner {name!r} is learned: it needs torch and trained checkpoints, which are not "
                f"available ({exc})"
            ) from exc
        return make_learned_planner(name, **kwargs)
    if name not in _CLASSES:
        raise PlannerError(f"unknown planner {name!r}: choose one of {', '.join(PLANNERS)}")
    try:
        return _CLASSES[name](**kwargs)
    except TypeError as exc:
        raise PlannerError(f"bad arguments for planner {name!r}: {exc}") from exc
