"""Every widget of the library in live mode, as a student's kernel shows it: controls moved, redrawn.

``make test`` runs the chapters once, in the book's mode (``tests/executed_book.py``); the code that
only a live kernel runs is the ipywidgets branch of :func:`husky_course.ui.widgets.interactive_figure`
and the widgets built on it. Here each of the chapters' widgets (chapter 1's world explorer,
chapter 7's planner stepper and primitive explorer) is built live with the controls the chapter
gives it, each control is moved, and every redraw must draw a figure with content.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import pytest

from husky_course.planners.registry import make_planner
from husky_course.ui import widgets


@pytest.fixture
def live(monkeypatch):
    """Live mode: the widgets shown and every figure drawn (its axes and their images) recorded."""
    import IPython.display

    monkeypatch.delenv("HUSKY_STATIC_WIDGETS", raising=False)
    monkeypatch.setattr(widgets, "widgets_live", lambda: True)
    shown, drawn = [], []
    monkeypatch.setattr(IPython.display, "display", lambda *objs: shown.extend(objs))

    def show(*args, **kwargs):
        fig = plt.gcf()
        drawn.append(sum(len(ax.images) + len(ax.lines) + len(ax.patches) for ax in fig.axes))

    monkeypatch.setattr(plt, "show", show)
    return shown, drawn


def controls(box) -> dict:
    """The controls of a widget's box by description (rows of controls, then the output)."""
    return {c.description: c for row in box.children[:-1] for c in row.children}


def test_world_explorer_live(live):
    shown, drawn = live
    widgets.world_explorer(default_seed=0)
    (box,) = shown
    seed = controls(box)["world seed"]
    seed.value = 5
    assert len(drawn) == 2 and min(drawn) > 0, drawn


def test_planner_stepper_live(live):
    shown, drawn = live
    widgets.planner_stepper(lambda name, k: make_planner(name), ("random", "heuristic"), 0, "heuristic")
    (box,) = shown
    c = controls(box)
    c["step"].value = 1
    c["planner"].value = "random"
    c["world"].value = 2
    assert len(drawn) == 4 and min(drawn) > 0, drawn


def test_primitive_explorer_live(live):
    shown, drawn = live
    widgets.primitive_explorer(object(), default_seed=0, default_primitive=3)  # a model with no decoder
    (box,) = shown
    c = controls(box)
    c["primitive"].value = 20
    c["world"].value = 1
    assert len(drawn) == 3 and min(drawn) > 0, drawn
