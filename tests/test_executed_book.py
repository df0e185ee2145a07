"""``--keep-executed``: nbval's runs of the chapters become the browser test's book, never a stale one.

A scratch notebook under ``_build/`` (git-ignored) is run by nbval in a child pytest with the
option: its kernel sees ``HUSKY_STATIC_WIDGETS=1`` while the pytest process does not afterwards, its
outputs are kept with a stamp, the stamp goes stale when the notebook changes, and a notebook with
a failing cell is not kept.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import nbformat
import pytest
from executed_book import EXECUTED, REPO, fresh_executions, output_of, stage_book

SCRATCH = REPO / "_build" / "keep-executed-test"


def notebook(path: Path, *cells: str) -> Path:
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(c) for c in cells])
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    path.parent.mkdir(parents=True, exist_ok=True)
    nbformat.write(nb, path)
    return path


def run_nbval(path: Path) -> subprocess.CompletedProcess:
    after = "import os; print('pytest sees', os.environ.get('HUSKY_STATIC_WIDGETS'))"
    check = SCRATCH / "test_after.py"
    check.write_text(f"def test_after():\n    {after}\n")
    return subprocess.run(
        [sys.executable, "-m", "pytest", str(path), str(check), "--nbval-lax", "--keep-executed", "-s",
         "-p", "no:cacheprovider", "-q", "--rootdir", str(REPO)],
        cwd=REPO, capture_output=True, text=True, timeout=300, check=False,
    )


@pytest.fixture
def scratch():
    SCRATCH.mkdir(parents=True, exist_ok=True)
    yield SCRATCH
    for name in ("keep_ok.ipynb", "keep_fails.ipynb"):
        (EXECUTED / name).unlink(missing_ok=True)
    import shutil

    shutil.rmtree(SCRATCH, ignore_errors=True)


def test_a_passing_notebook_is_kept_with_its_outputs_and_stamp(scratch, monkeypatch):
    monkeypatch.delenv("HUSKY_STATIC_WIDGETS", raising=False)
    shows = "import os\nprint(os.environ.get('HUSKY_STATIC_WIDGETS'))"
    source = notebook(scratch / "keep_ok.ipynb", shows, "1 + 1")
    proc = run_nbval(source)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert "pytest sees None" in proc.stdout  # the switch was the kernel's alone
    kept = EXECUTED / source.name
    nb = nbformat.read(kept, as_version=4)
    first, second = (c["outputs"] for c in nb["cells"])
    assert first == [{"output_type": "stream", "name": "stdout", "text": "1\n"}]  # static in the kernel
    assert second[0]["data"]["text/plain"] == "2" and second[0]["output_type"] == "execute_result"
    assert fresh_executions([source]) == {source: kept}
    staged = stage_book(scratch / "staged", {source: kept})
    assert "execute_notebooks: 'off'" in (staged / "_config.yml").read_text()
    assert (staged / source.relative_to(REPO)).read_text() == kept.read_text()
    notebook(source, "print('edited')")  # the chapter changed: its execution is stale
    assert fresh_executions([source]) is None


def test_a_failing_notebook_is_not_kept(scratch):
    source = notebook(scratch / "keep_fails.ipynb", "x = 1", "raise RuntimeError('no')", "x")
    (EXECUTED / source.name).parent.mkdir(parents=True, exist_ok=True)
    (EXECUTED / source.name).write_text("{}")  # an older run's, now stale
    proc = run_nbval(source)
    assert proc.returncode == 1, proc.stdout[-2000:]
    assert not (EXECUTED / source.name).exists()
    assert fresh_executions([source]) is None


def test_unknown_outputs_are_refused():
    with pytest.raises(ValueError, match="unknown type"):
        output_of({"output_type": "update_display_data"})
