"""Tables, figures and widgets the chapters display."""

from __future__ import annotations

import pytest

from husky_course.ui.plotting import markdown_table


def test_markdown_table_from_mappings():
    text = markdown_table([{"model": "joint", "AUC": 0.96123}, {"model": "paper", "AUC": 0.8651}])
    assert text.splitlines() == [
        "| model | AUC |",
        "|---|---|",
        "| joint | 0.961 |",
        "| paper | 0.865 |",
    ]


def test_markdown_table_from_sequences_with_header_and_digits():
    text = markdown_table([["a", 1, 0.5]], header=["name", "n", "x"], digits=1)
    assert text.splitlines()[-1] == "| a | 1 | 0.5 |"


@pytest.mark.parametrize(
    "rows, header, message",
    [
        ([], None, "at least one row"),
        ([["a", 1]], None, "needs a header"),
        ([["a", 1], ["b"]], ["name", "n"], "every row needs 2 cells"),
    ],
)
def test_markdown_table_bad_input(rows, header, message):
    with pytest.raises(ValueError, match=message):
        markdown_table(rows, header=header)


def _recording_figure(calls):
    import matplotlib.pyplot as plt

    def figure(**kw):
        calls.append(kw)
        return plt.figure()

    return figure


def test_widget_offline_draws_the_static_figure_once(monkeypatch):
    from husky_course.ui import widgets

    monkeypatch.setenv("HUSKY_STATIC_WIDGETS", "1")
    calls = []
    widgets.interactive_figure(
        _recording_figure(calls),
        [[widgets.Control("seed", "world", 3, (0, 9)), widgets.Control("name", "planner", "b", ("a", "b"))]],
    )
    assert calls == [{"seed": 3, "name": "b"}]


def test_widget_live_redraws_with_the_controls_values(monkeypatch):
    import IPython.display

    from husky_course.ui import widgets

    monkeypatch.setattr(widgets, "widgets_live", lambda: True)
    shown = []
    monkeypatch.setattr(IPython.display, "display", lambda *objs: shown.extend(objs))
    calls = []
    widgets.interactive_figure(
        _recording_figure(calls),
        [
            [widgets.Control("seed", "world", 3, (0, 9))],
            [widgets.Control("name", "planner", "b", ("a", "b"))],
        ],
    )
    (box,) = shown
    seed, name = box.children[0].children[0], box.children[1].children[0]
    assert (seed.min, seed.max, name.options) == (0, 9, ("a", "b"))
    seed.value = 7
    name.value = "a"
    assert calls == [{"seed": 3, "name": "b"}, {"seed": 7, "name": "b"}, {"seed": 7, "name": "a"}]


def test_widget_offline_with_frames_is_a_player_over_them(monkeypatch):
    """Offline with ``frames``: one figure per frame, shown as a self-contained ``to_jshtml`` player."""
    import IPython.display

    from husky_course.ui import widgets

    monkeypatch.setenv("HUSKY_STATIC_WIDGETS", "1")
    shown = []
    monkeypatch.setattr(IPython.display, "display", lambda *objs: shown.extend(objs))
    calls = []
    widgets.interactive_figure(
        _recording_figure(calls),
        [[widgets.Control("seed", "world", 3, (0, 9)), widgets.Control("name", "planner", "b", ("a", "b"))]],
        frames=[{"seed": 1}, {"seed": 2}, {"name": "a"}],
    )
    assert calls == [{"seed": 1, "name": "b"}, {"seed": 2, "name": "b"}, {"seed": 3, "name": "a"}]
    (html,) = shown
    page = html.data
    assert 'class="animation"' in page and 'type="range"' in page
    assert page.count("data:image/png;base64,") == 3  # one embedded frame each, no CDN
    assert "http://" not in page and "https://" not in page  # offline: not even the icons' CDN
