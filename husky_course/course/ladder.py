"""Chapter 8's ladder: from the mapping planner's raw scan points to perfect perception, a rung at a time.

Every rung replans at every step with the oracle's exact lattice search; what changes is what it
searches over (``benchmarks/exp_static_ladder.py`` runs it on 1,000 tuning worlds):

1. ``mapping``: the classical planner's raw scan points (each fattened by half the gap between
   columns), with its tuned margin of 0.02 m;
2. ``mapping, margin 0``: the same with the disc planner's margin, so that the rungs below differ
   from it only in the map;
3. ``discs, no unexplained points``: the disc planner (:mod:`husky_course.planners.discs`) keeping
   only its network's discs for the pieces it reads as cylinders;
4. ``discs``: the disc planner as configured (:class:`~husky_course.config.DiscConfig`: a cylinder
   piece's points that its disc does not explain stay in the map);
5. ``discs, read from the truth``: every piece read as the cylinder most of its columns hit,
   exactly (:class:`~husky_course.planners.reference.TrueDiscsPlanner`, privileged): what a perfect
   network would give this map;
6. ``seen so far``: every cylinder any image has rendered, exactly, and the walls
   (:class:`~husky_course.planners.reference.SeenObstaclesPlanner`, privileged);
7. ``oracle``: every cylinder.

Rungs 5 to 7 are references, not bounds on camera-based planners: each is optimistic about space
no image has shown, which a learned planner need not be.

Chapter 10's ladder (:func:`moving_ladder`) climbs from the moving course's disc planner, as it is,
through its own map told more and more of the truth
(:class:`~husky_course.planners.reference.ToldDiscsPlanner`: its first sights' motion, every disc's
motion, every cylinder seen so far exactly) to the perfect-perception reference that knows what
the last rung knows and plans with the oracle's search (``benchmarks/exp_moving_ladder.py`` splits
the rungs finer, on 300 tuning worlds).
"""

from __future__ import annotations

from ..config import Profile, with_world
from ..planners.base import Planner
from ..planners.registry import make_planner


def static_ladder(profile: Profile) -> list[tuple[str, Planner]]:
    """The ladder's rungs ``(name, planner)``, in order (module docstring); loads the disc network,
    never trains it."""
    margin = profile.discs.margin
    return [
        ("mapping", make_planner("mapping", config=profile.sim)),
        ("mapping, margin 0", make_planner("mapping", config=profile.sim, margin=margin)),
        ("discs, no unexplained points", make_planner("discs", profile=profile, unexplained=float("inf"))),
        ("discs", make_planner("discs", profile=profile)),
        ("discs, read from the truth", make_planner("true-discs", config=profile.sim, margin=margin)),
        ("seen so far", make_planner("seen-so-far")),
        ("oracle", make_planner("oracle")),
    ]


def moving_ladder(profile: Profile) -> list[tuple[str, Planner]]:
    """Chapter 10's rungs ``(name, planner)`` on the moving course, in order (module docstring);
    loads the disc network, never trains it."""
    from ..planners.reference import TOLD_RULES

    moving = with_world(profile, "moving")
    told = [(f"discs, told {rule}", make_planner("told-discs", profile=moving, rule=rule, config=moving.sim))
            for rule in TOLD_RULES]
    return [("discs", make_planner("discs", profile=moving, config=moving.sim)), *told,
            ("seen so far, with motion", make_planner("seen-motion"))]
