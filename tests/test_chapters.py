"""Chapter sources and the notebooks students open stay one thing.

Each ``chapters/NN_name.py`` (jupytext percent format, the source ruff checks) is paired with
``notebooks/NN_name.ipynb`` (what students open, nbval tests and the book executes). These tests
fail when a pair drifts apart (run ``make sync``), when a notebook carries outputs other than
those nbval checks, or when a chapter is missing from the book's table of contents.
"""

from __future__ import annotations

import copy
from pathlib import Path

import jupytext
import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[1]
CHAPTERS = sorted((ROOT / "chapters").glob("*.py"))
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
CHECKED = "NBVAL_CHECK_OUTPUT"


def _cells(nb) -> list[tuple[str, str]]:
    return [(c.cell_type, c.source.strip()) for c in nb.cells]


def _differences(source: Path, notebook: Path) -> list[str]:
    """Where the jupytext source and the notebook disagree (empty when in sync)."""
    a = _cells(jupytext.read(source))
    b = _cells(nbformat.read(notebook, as_version=4))
    out = [f"{len(a)} cells in {source.name}, {len(b)} in {notebook.name}"] if len(a) != len(b) else []
    for i, (x, y) in enumerate(zip(a, b, strict=False)):
        if x != y:
            out.append(f"cell {i}: {x[0]} {x[1][:60]!r} != {y[0]} {y[1][:60]!r}")
    return out


def test_every_chapter_has_its_notebook():
    assert CHAPTERS, "no chapter sources found"
    assert [p.stem for p in CHAPTERS] == [p.stem for p in NOTEBOOKS]


@pytest.mark.parametrize("source", CHAPTERS, ids=lambda p: p.stem)
def test_pair_in_sync(source):
    diff = _differences(source, ROOT / "notebooks" / f"{source.stem}.ipynb")
    assert not diff, f"{source.name} and its notebook differ (run `make sync`):\n" + "\n".join(diff[:10])


def test_a_drifted_pair_is_caught(tmp_path):
    nb = jupytext.read(CHAPTERS[0])
    changed = copy.deepcopy(nb)
    changed.cells[1].source += "\nprint('edited in Jupyter only')"
    nbformat.write(changed, tmp_path / "drifted.ipynb")
    assert _differences(CHAPTERS[0], tmp_path / "drifted.ipynb")


@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebooks_are_committed_without_outputs_except_checked_cells(notebook):
    nb = nbformat.read(notebook, as_version=4)
    assert "widgets" not in nb.metadata, "live widget state is committed"
    for i, cell in enumerate(nb.cells):
        assert "execution" not in cell.metadata, f"cell {i} carries execution timestamps"
        if cell.cell_type == "code" and CHECKED not in cell.source:
            assert not cell.outputs and cell.execution_count is None, f"cell {i} has outputs committed"


def test_every_notebook_is_in_the_book():
    toc = (ROOT / "_toc.yml").read_text()
    missing = [p.stem for p in NOTEBOOKS if f"notebooks/{p.stem}" not in toc]
    assert not missing, f"chapters missing from _toc.yml: {missing}"
