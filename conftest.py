"""pytest's ``--keep-executed``: nbval's chapter executions become the browser test's book.

See ``tests/executed_book.py``. Without the option nothing here changes a run. Also: which tests share
a process, in which order, under ``pytest -n N --dist loadfile`` (:func:`pytest_xdist_make_scheduler`).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent / "tests"))
import executed_book  # noqa: E402

STATIC_ENV = "HUSKY_STATIC_WIDGETS"  # husky_course.progress.STATIC_ENV (the library is not imported here)


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--keep-executed", action="store_true", default=False,
        help="run nbval's kernels in the book's mode (HUSKY_STATIC_WIDGETS=1) and keep each chapter "
        "whose cells all passed, outputs included, in _build/executed/ for the browser test's book",
    )


#: the scope of pytest-xdist's scheduling that holds every chapter and, after them, the browser test
CHAPTERS_SCOPE = "the chapters, then the book built from them"


def _scope(nodeid: str) -> str:
    file = nodeid.split("::")[0]
    return CHAPTERS_SCOPE if file.startswith("notebooks/") or file == "tests/test_browser.py" else file


@pytest.hookimpl(optionalhook=True)  # a hook of pytest-xdist's, when it is installed
def pytest_xdist_make_scheduler(config: pytest.Config, log: object) -> object | None:
    """Under ``-n N --dist loadfile``, a file's tests stay in one process, in order, and so do all the
    chapters, in their order, followed by ``tests/test_browser.py``.

    In one process, chapters 10 and 11 read chapter 8's evaluations from the store instead of each
    computing them again beside it, and the browser test's book (built from the chapters nbval just
    executed, ``tests/executed_book.py``) comes after the last chapter, while the other process still
    runs the unit tests.
    """
    if config.getvalue("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class ChaptersInOrder(LoadFileScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return _scope(nodeid)

    return ChaptersInOrder(config, log)


def _nbval_cell(item: pytest.Item) -> bool:
    return type(item).__name__ == "IPyNbCell" and item.config.getoption("--keep-executed")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_setup(item: pytest.Item):
    """The notebook's kernel starts in the first cell's setup: in the book's mode, for it alone."""
    if not _nbval_cell(item):
        yield
        return
    before = os.environ.get(STATIC_ENV)
    os.environ[STATIC_ENV] = "1"
    try:
        yield
    finally:
        if before is None:
            os.environ.pop(STATIC_ENV, None)
        else:
            os.environ[STATIC_ENV] = before


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):
    """Collect each cell's outputs; after the last cell, write the chapter if every cell passed."""
    outcome = yield
    if not _nbval_cell(item) or call.when != "call":
        return
    notebook = item.parent
    record = notebook.__dict__.setdefault("_husky_outputs", {"outputs": {}, "failed": False})
    report = outcome.get_result()
    record["failed"] |= not report.passed
    record["outputs"][item.cell_num] = list(item.test_outputs or [])
    cells = sum(c.cell_type == "code" for c in notebook.nb.cells)
    source = Path(str(notebook.fspath))
    target = executed_book.EXECUTED / source.name
    if item.cell_num == cells - 1:
        if record["failed"] or len(record["outputs"]) != cells:
            target.unlink(missing_ok=True)  # never a book from a chapter that failed
        else:
            library = item.config.stash.setdefault(_LIBRARY, executed_book.build_fingerprint())
            executed_book.write_executed(source, record["outputs"], library)


_LIBRARY = pytest.StashKey[str]()
