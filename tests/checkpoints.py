"""The quick profile's trained planners for the tests, or a failure that names the commands building them.

``make test`` trains every checkpoint before pytest runs; a test never trains. A plain ``pytest`` run
without them must not pass without checking any behaviour, so a missing checkpoint fails (never skips)
with the commands to run, in CI and on a laptop alike.
"""

from __future__ import annotations

import pytest

from husky_course.config import Profile, get_profile
from husky_course.planners.base import Planner, PlannerError
from husky_course.planners.registry import make_planner

QUICK = get_profile("quick")
BUILD = ("`python -m husky_course train all --profile quick` (and, for chapter 10's student, "
         "`python -m husky_course train memory --world moving --profile quick`; for chapter 11's disc "
         "network, `python -m husky_course train discs --sensing realistic --profile quick`)")


def trained(name: str, profile: Profile = QUICK) -> Planner:
    """The learned planner ``name`` from its stored checkpoints, or a test failure naming the command."""
    try:
        return make_planner(name, profile=profile)
    except PlannerError as exc:
        pytest.fail(f"the quick profile's trained {name!r} planner is missing ({exc}); build the "
                    f"checkpoints with {BUILD}, or run `make test`, which does it first", pytrace=False)
