"""First sightings on the moving course (:mod:`husky_course.planners.arrivals`)."""

from __future__ import annotations

import numpy as np
import pytest

from husky_course.config import SimConfig, sim_for_world
from husky_course.planners.arrivals import Arrivals

MOVING = sim_for_world(SimConfig(), "moving")


def _half_occluded(config: SimConfig) -> np.ndarray:
    """A previous image: something 1 m ahead in the left half of the columns, nothing in the right."""
    size = config.camera.size
    return np.r_[np.full(size // 2, 1.0), np.full(size - size // 2, np.inf)]


def test_a_cylinder_where_free_space_was_seen_walked_in_from_the_hidden_side():
    arrivals = Arrivals(MOVING)
    arrivals.remember(_half_occluded(MOVING))
    (v,) = arrivals.speeds(np.array([[3.0, 0.0, 0.25]]))
    lo, hi = MOVING.world.speed_range
    # standing, and every walk from the right (the seen half), are ruled out: it came from the left,
    # so it walks towards -y, at the mean of the speeds left
    assert v == pytest.approx(-(lo + hi) / 2)


def test_dead_reckoning_carries_the_previous_image():
    arrivals = Arrivals(MOVING)
    arrivals.remember(_half_occluded(MOVING))
    arrivals.move(1.0, 0.0)  # the robot advanced 1 m: the same place is now 1 m nearer
    moved = arrivals.speeds(np.array([[2.0, 0.0, 0.25]]))
    fresh = Arrivals(MOVING)
    fresh.remember(_half_occluded(MOVING))
    assert moved == pytest.approx(fresh.speeds(np.array([[3.0, 0.0, 0.25]])))
    assert moved[0] != 0


def test_standing_stays_possible_behind_an_occluder_or_beyond_the_far_plane():
    arrivals = Arrivals(MOVING)
    arrivals.remember(np.full(MOVING.camera.size, 1.0))  # a wall 1 m ahead hid everything
    far = MOVING.camera.far + MOVING.camera.mount_forward + 1.0
    discs = np.array([[3.0, 0.0, 0.25], [3.0, 1.0, 0.25]])
    assert np.all(arrivals.speeds(discs) == 0)
    arrivals.remember(np.full(MOVING.camera.size, np.inf))  # nothing seen, and the cylinder beyond far
    assert arrivals.speeds(np.array([[far, 0.0, 0.25]]))[0] == 0


def test_seen_through_both_ways_or_no_previous_image_or_static_course_stands():
    arrivals = Arrivals(MOVING)
    disc = np.array([[3.0, 0.0, 0.25]])
    assert arrivals.speeds(disc)[0] == 0  # no previous image yet
    arrivals.remember(np.full(MOVING.camera.size, np.inf))  # free everywhere: every hypothesis out
    assert arrivals.speeds(disc)[0] == 0
    static = Arrivals(SimConfig())
    static.remember(_half_occluded(SimConfig()))
    assert static.speeds(disc)[0] == 0
