"""Build any planner by name: the one place that knows every planner.

The non-learned planners are imported here directly; the learned ones (which need torch and
trained checkpoints) and the references are imported when one is asked for, so ``evaluate
--planner heuristic`` never loads torch. Nothing below imports this module, so there is no import
circle.

:data:`PLANNERS` are the planners a student picks, ranks and runs from the command line (the
oracle among them, as the bound of every planner). :data:`REFERENCE_PLANNERS` are the analysis
tools of :mod:`~husky_course.planners.reference`: privileged (perfect perception of what the camera
has shown), references rather than bounds, never candidates; :func:`make_planner` builds them too,
but no list a student picks from names them. :func:`planner_classes` says which classes each name
builds, so a test can check that no planner class lives outside this registry.
"""

from __future__ import annotations

import importlib
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
#: The classes each learned planner may be (``module:Class`` in this package), imported on demand.
_LEARNED_CLASSES: dict[str, tuple[str, ...]] = {
    "lookahead": ("learned:LookaheadPlanner",),
    "rnn": ("learned:RNNPlanner",),
    "distilled": ("learned:DistilledPlanner",),
    "memory": ("memory:MemoryPlanner",),
    "discs": ("discs:DiscPlanner", "moving_discs:DiscTrackingPlanner"),  # the latter on the moving course
}
#: Analysis-only references (privileged): name -> (class in :mod:`.reference`, its fixed arguments).
_REFERENCES: dict[str, tuple[str, dict[str, Any]]] = {
    "seen-now": ("SeenObstaclesPlanner", {"memory": False}),
    "seen-so-far": ("SeenObstaclesPlanner", {"memory": True}),
    "seen-motion": ("SeenMotionPlanner", {}),
    "second-look": ("SecondLookPlanner", {}),
    "snapshot": ("SnapshotPlanner", {}),
    "true-discs": ("TrueDiscsPlanner", {}),
    "told-discs": ("ToldDiscsPlanner", {}),
}
REFERENCE_PLANNERS = tuple(_REFERENCES)


def planner_classes() -> dict[str, tuple[str, ...]]:
    """Every name :func:`make_planner` knows -> the classes it may build, as ``module.Class`` paths."""
    out = {name: (f"{cls.__module__}.{cls.__qualname__}",) for name, cls in _CLASSES.items()}
    for name, paths in _LEARNED_CLASSES.items():
        out[name] = tuple(f"{__package__}.{path.replace(':', '.')}" for path in paths)
    for name, (cls, _) in _REFERENCES.items():
        out[name] = (f"{__package__}.reference.{cls}",)
    return out


def _make_reference(name: str, **kwargs: Any) -> Planner:
    """The reference ``name`` (analysis only, privileged) with keyword arguments ``kwargs``."""
    cls, fixed = _REFERENCES[name]
    try:
        module = importlib.import_module(".reference", __package__)
    except ImportError as exc:  # the true-discs reference is a disc planner: it needs torch
        raise PlannerError(f"reference planner {name!r} is not available ({exc})") from exc
    clash = sorted(set(fixed) & set(kwargs))
    if clash:
        raise PlannerError(f"bad arguments for planner {name!r}: {', '.join(clash)} is fixed by its name")
    try:
        return getattr(module, cls)(**fixed, **kwargs)
    except TypeError as exc:
        raise PlannerError(f"bad arguments for planner {name!r}: {exc}") from exc


def make_planner(name: str, **kwargs: Any) -> Planner:
    """Build the planner ``name`` (one of :data:`PLANNERS` or :data:`REFERENCE_PLANNERS`) with
    keyword arguments ``kwargs``.

    Learned planners need ``profile=`` (a :class:`~husky_course.config.Profile`) and trained
    checkpoints; :class:`PlannerError` says so when either is missing. A reference is privileged:
    run it with :func:`~husky_course.evaluation.episodes.run_episode` or ``evaluate``, which hand it
    the simulator.
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
    if name in _REFERENCES:
        return _make_reference(name, **kwargs)
    if name not in _CLASSES:
        raise PlannerError(
            f"unknown planner {name!r}: choose one of {', '.join(PLANNERS)} (or, for analysis only, a "
            f"privileged reference: {', '.join(REFERENCE_PLANNERS)})"
        )
    try:
        return _CLASSES[name](**kwargs)
    except TypeError as exc:
        raise PlannerError(f"bad arguments for planner {name!r}: {exc}") from exc
