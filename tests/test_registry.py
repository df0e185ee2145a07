"""The registry knows every planner: each planner class the package defines is built by some name of
``planners/registry.py`` (the planners a student picks, the learned ones, or the references)."""

from __future__ import annotations

import importlib
import pkgutil

import pytest

import husky_course
from husky_course.planners.base import Planner
from husky_course.planners.registry import (
    LEARNED_PLANNERS,
    PLANNERS,
    REFERENCE_PLANNERS,
    make_planner,
    planner_classes,
)


def _import_everything() -> None:
    """Import every module of the package (but ``__main__``, which runs the command line)."""
    for info in pkgutil.walk_packages(husky_course.__path__, "husky_course."):
        if not info.name.endswith("__main__"):
            importlib.import_module(info.name)


def _planner_classes() -> set[type]:
    found, todo = set(), [Planner]
    while todo:
        for sub in todo.pop().__subclasses__():
            if sub not in found:
                found.add(sub)
                todo.append(sub)
    return found


def _unregistered(classes: set[type], known: dict[str, tuple[str, ...]]) -> list[str]:
    """Public planner classes of the package (private ones are helpers or bases) that no name builds."""
    paths = {p for ps in known.values() for p in ps}
    return sorted(
        f"{c.__module__}.{c.__qualname__}"
        for c in classes
        if c.__module__.startswith("husky_course.") and not c.__name__.startswith("_")
        and f"{c.__module__}.{c.__qualname__}" not in paths
    )


def test_every_planner_class_is_known_to_the_registry():
    _import_everything()
    missing = _unregistered(_planner_classes(), planner_classes())
    assert not missing, f"planner classes no name of planners/registry.py builds: {missing}"


def test_every_registered_class_exists():
    for name, paths in planner_classes().items():
        for path in paths:
            module, cls = path.rsplit(".", 1)
            assert issubclass(getattr(importlib.import_module(module), cls), Planner), (name, path)


def test_an_unregistered_planner_is_caught():
    class Stray(Planner):
        name = "stray"

    Stray.__module__, Stray.__qualname__ = "husky_course.planners.stray", "Stray"
    assert _unregistered({Stray}, planner_classes()) == ["husky_course.planners.stray.Stray"]
    Stray.__module__ = __name__  # a test's own planner is not the package's
    assert _unregistered({Stray}, planner_classes()) == []


def test_the_names_are_one_list_each():
    names = set(planner_classes())
    assert names == set(PLANNERS) | set(REFERENCE_PLANNERS)
    assert set(LEARNED_PLANNERS) <= set(PLANNERS) and not set(PLANNERS) & set(REFERENCE_PLANNERS)


@pytest.mark.parametrize("name", REFERENCE_PLANNERS)
def test_a_reference_is_built_by_name_and_is_privileged(name):
    planner = make_planner(name)
    assert planner.privileged
    cls = type(planner)
    assert f"{cls.__module__}.{cls.__qualname__}" in planner_classes()[name]


def test_a_reference_refuses_its_fixed_arguments():
    with pytest.raises(ValueError, match="fixed by its name"):
        make_planner("seen-now", memory=True)
    with pytest.raises(ValueError, match="bad arguments"):
        make_planner("snapshot", look_ahead=2)
