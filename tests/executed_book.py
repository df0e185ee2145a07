"""The chapters run once in ``make test``: nbval executes them, and the browser test's book reuses it.

``make test`` runs ``pytest notebooks tests --nbval-lax --keep-executed`` (the root ``conftest.py``).
With ``--keep-executed``, nbval's kernels run in the book's mode (``HUSKY_STATIC_WIDGETS=1``, set
for the kernels only: the unit tests after them see the environment they were given), and every
chapter whose cells all passed is written, with the outputs nbval received, to
``_build/executed/<name>.ipynb``, stamped with what those outputs depend on (:func:`stamp`: the
library, the setup, the notebook's own bytes, the profile). ``tests/test_browser.py`` then builds
the book from those notebooks without executing anything (:func:`stage_book`), when every chapter
of the table of contents has a fresh one; otherwise it executes the chapters itself, as before.

The live widgets a student's kernel shows are not lost from the tests: ``tests/test_jupyterlab.py``
runs chapter 1 through JupyterLab's UI and moves its live slider, and ``tests/test_widgets_live.py``
runs every widget of the library (the world explorer of chapter 1, the planner stepper and the
primitive explorer of chapter 7) in live mode, controls moved and redrawn. Those are the only code
paths where the two modes differ (:mod:`husky_course.ui.widgets`, :mod:`husky_course.progress`).
"""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
EXECUTED = REPO / "_build" / "executed"
PROFILE = "quick"
KEY = "husky_executed"  #: the notebook-metadata field that holds the stamp


def build_fingerprint() -> str:
    """What notebook outputs depend on besides the notebooks' code: the library and the setup."""
    digest = hashlib.sha256()
    files = sorted((REPO / "husky_course").rglob("*.py"))
    files += [REPO / name for name in ("requirements.txt", "pyproject.toml", "_config.yml")]
    for path in files:
        if path.is_file():
            digest.update(str(path.relative_to(REPO)).encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def stamp(source: Path, library: str | None = None) -> dict:
    """What an execution of ``source`` depends on: its bytes, the library and setup, the profile."""
    return {
        "source_sha256": hashlib.sha256(source.read_bytes()).hexdigest(),
        "library": library or build_fingerprint(),
        "profile": PROFILE,
        "static_widgets": True,
    }


def output_of(out: dict) -> dict:
    """One nbval output (a ``NotebookNode`` holding an iopub message) as an nbformat output."""
    kind = out["output_type"]
    if kind == "stream":
        return {"output_type": "stream", "name": out["name"], "text": out["text"]}
    if kind in ("display_data", "execute_result"):
        made = {"output_type": kind, "data": dict(out["data"]), "metadata": dict(out.get("metadata", {}))}
        if kind == "execute_result":
            made["execution_count"] = out.get("execution_count")
        return made
    if kind == "error":
        return {"output_type": "error", "ename": out["ename"], "evalue": out["evalue"],
                "traceback": list(out["traceback"])}
    raise ValueError(f"an output of unknown type {kind!r}")


def write_executed(source: Path, outputs: dict[int, list], library: str) -> Path:
    """``source`` with ``outputs[i]`` (nbval's) as the outputs of its ``i``-th code cell, stamped."""
    import nbformat

    nb = nbformat.read(source, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    if set(outputs) != set(range(len(code))):
        raise ValueError(f"{source.name}: outputs for cells {sorted(outputs)}, not all {len(code)}")
    for i, cell in enumerate(code):
        cell.outputs = [nbformat.from_dict(output_of(o)) for o in outputs[i]]
        cell.execution_count = i + 1
    nb.metadata[KEY] = stamp(source, library)
    # what an executing kernel records and nbval's outputs lack: the book's highlighter needs it
    nb.metadata.setdefault("language_info", {"name": "python", "pygments_lexer": "ipython3"})
    nbformat.validate(nb)
    EXECUTED.mkdir(parents=True, exist_ok=True)
    target = EXECUTED / source.name
    tmp = target.with_suffix(".tmp")
    tmp.write_text(nbformat.writes(nb))
    tmp.replace(target)  # a killed run never leaves half a notebook
    return target


def fresh_executions(sources: list[Path]) -> dict[Path, Path] | None:
    """The executed notebook of every source, when each is there and stamped as today's; else None."""
    library = build_fingerprint()
    found = {}
    for source in sources:
        executed = EXECUTED / source.name
        if not executed.is_file():
            return None
        meta = json.loads(executed.read_text()).get("metadata", {}).get(KEY)
        if meta != stamp(source, library):
            return None
        found[source] = executed
    return found


def stage_book(root: Path, executions: dict[Path, Path]) -> Path:
    """A copy of the book's sources in ``root`` with the executed notebooks, set not to execute."""
    import yaml

    shutil.rmtree(root, ignore_errors=True)
    root.mkdir(parents=True)
    shutil.copy(REPO / "_toc.yml", root / "_toc.yml")
    shutil.copytree(REPO / "book", root / "book")
    config = yaml.safe_load((REPO / "_config.yml").read_text())
    config.setdefault("execute", {})["execute_notebooks"] = "off"
    (root / "_config.yml").write_text(yaml.safe_dump(config, sort_keys=False))
    for source, executed in executions.items():
        target = root / source.relative_to(REPO)
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(executed, target)
    return root
