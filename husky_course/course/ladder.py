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
"""

from __future__ import annotations

from ..config import Profile
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
