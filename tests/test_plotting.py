"""Tables and figures the chapters display."""

from __future__ import annotations

import pytest

from husky_course.plotting import markdown_table


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
