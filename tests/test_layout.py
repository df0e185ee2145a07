"""The package reads as the pipeline: one-way imports between stages, no circles, no hidden deps.

Stages, lowest first (a module may import from its own stage or a lower one, never a higher one):
the floor (``config``, ``checks``, ``progress``, ``device``, ``engines``) -> ``sim`` -> ``data`` ->
``models`` -> ``training`` -> ``planners`` -> ``imitation`` -> ``evaluation`` -> ``course`` / ``ui`` ->
``cli``.
"""

from __future__ import annotations

import ast
import importlib.metadata
import re
import subprocess
import sys
from pathlib import Path

import pytest
import tomllib

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "husky_course"
STAGES = {
    "__init__": 0,
    "config": 0,
    "checks": 0,
    "progress": 0,
    "device": 0,
    "engines": 0,
    "sim": 1,
    "data": 2,
    "models": 3,
    "training": 4,
    "planners": 5,
    "imitation": 6,
    "evaluation": 7,
    "course": 8,
    "ui": 8,
    "cli": 9,
    "__main__": 10,
}
MAX_LINES = 400


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path) -> set[str]:
    """Package modules that ``path`` imports (relative imports resolved), at any depth."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            if mod.startswith("husky_course"):
                for alias in node.names:  # `from husky_course.x import y` may name a module y
                    sub = f"{mod}.{alias.name}"
                    found.add(sub if (ROOT / (sub.replace(".", "/") + ".py")).is_file() else mod)
        elif isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.startswith("husky_course")}
    return found


MODULES = {_module_name(p): p for p in sorted(PKG.rglob("*.py"))}
GRAPH = {name: {m for m in _imports(path) if m in MODULES and m != name} for name, path in MODULES.items()}


def _stage(module: str) -> int:
    parts = module.split(".")
    return STAGES[parts[1] if len(parts) > 1 else "__init__"]


def test_every_module_belongs_to_a_stage():
    unknown = sorted({m.split(".")[1] for m in MODULES if "." in m} - set(STAGES))
    assert not unknown, f"modules outside the pipeline's stages: {unknown}"


def _upward(graph: dict[str, set[str]]) -> list[str]:
    return [
        f"{a} (stage {_stage(a)}) imports {b} (stage {_stage(b)})"
        for a, deps in graph.items()
        for b in deps
        if _stage(b) > _stage(a) and b != "husky_course"
    ]


def test_imports_flow_one_way():
    upward = _upward(GRAPH)
    assert not upward, "imports against the pipeline's direction:\n" + "\n".join(upward)


def test_an_upward_import_is_caught():
    assert _upward({"husky_course.sim.fast": {"husky_course.training.trainer"}}) != []


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    return out


def test_no_import_circles():
    graph = {k: v - {"husky_course"} for k, v in GRAPH.items()}  # the package root only registers the env
    assert _cycles(graph) == []


def test_the_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


@pytest.mark.parametrize("name", sorted(MODULES))
def test_modules_stay_readable(name):
    lines = len(MODULES[name].read_text().splitlines())
    assert lines <= MAX_LINES, f"{name} has {lines} lines (> {MAX_LINES}): split it by job"


def _names(deps: list[str]) -> set[str]:
    return {re.split(r"[<>=!~\[; ]", d, maxsplit=1)[0].lower().replace("_", "-") for d in deps}


def _declared() -> set[str]:
    return _names(tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"])


def _extras() -> set[str]:
    """Distributions of the optional extras (``pip install -e .[ray]``), e.g. ``ray``."""
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"].get("optional-dependencies", {})
    return _names([d for deps in extras.values() for d in deps])


def _top_names(node: ast.AST) -> set[str]:
    if isinstance(node, ast.Import):
        return {a.name.split(".")[0] for a in node.names}
    if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
        return {node.module.split(".")[0]}
    return set()


def _imported(source: str) -> tuple[set[str], set[str]]:
    """Top-level names of what ``source`` imports: ``(anywhere, at import time)``.

    An import inside a function runs only when the function is called (lazy); every other one
    runs when the module is imported.
    """
    tree = ast.parse(source)
    functions = [f for f in ast.walk(tree) if isinstance(f, ast.FunctionDef | ast.AsyncFunctionDef)]
    lazy = {id(n) for f in functions for n in ast.walk(f)}
    found, eager = set(), set()
    for node in ast.walk(tree):
        names = _top_names(node)
        found |= names
        if id(node) not in lazy:
            eager |= names
    return found, eager


def _missing(declared: set[str], extras: frozenset[str] | set[str] = frozenset(), sources=None) -> dict:
    """Third-party modules the package imports whose distribution is not declared.

    A module imported when the package is imported must be in ``declared`` (the dependencies);
    one imported only inside functions may instead be in ``extras`` (an optional extra such as
    ``ray``, whose absence is reported when that code runs).
    """
    sources = [p.read_text() for p in MODULES.values()] if sources is None else sources
    anywhere, eager = set(), set()
    for source in sources:
        found, at_import = _imported(source)
        anywhere |= found
        eager |= at_import
    anywhere -= set(sys.stdlib_module_names) | {"husky_course"}
    dists = importlib.metadata.packages_distributions()

    def dists_of(m: str) -> set[str]:
        return {d.lower().replace("_", "-") for d in dists.get(m, [m])}

    allowed = {m: declared if m in eager else declared | set(extras) for m in anywhere}
    missing = {m: dists_of(m) for m in anywhere if not dists_of(m) & allowed[m]}
    if any(m == "torch" for m in anywhere) and "tensorboard" not in declared:  # SummaryWriter, inside torch
        missing["tensorboard (torch.utils.tensorboard)"] = {"tensorboard"}
    return {m: sorted(d) for m, d in missing.items()}


def test_runtime_imports_are_declared_dependencies():
    """An install of the package alone (``pip install .``) must bring everything it imports at
    import time; an optional extra (``.[ray]``) may be imported only inside functions."""
    missing = _missing(_declared(), _extras())
    assert not missing, f"imported but not in pyproject's dependencies (or, lazily, its extras): {missing}"
    assert "ray" in _extras()


def test_a_missing_dependency_is_caught():
    assert "torch" in _missing(_declared() - {"torch"})
    assert "ray" in _missing(_declared())  # the Ray engine imports ray (lazily): only an extra
    lazy, eager = "def f():\n    import ray\n", "import ray\n"
    assert _missing(_declared(), _extras(), [lazy]) == {}
    assert "ray" in _missing(_declared(), _extras(), [eager])  # an extra imported at import time


def test_import_husky_course_does_not_need_ray():
    code = "import sys, husky_course.engines, husky_course.cli; assert 'ray' not in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


def test_import_husky_course_does_not_need_gymnasium():
    """Gymnasium is needed by the environment only: the package and its config import without it."""
    blocked = "import sys; sys.modules['gymnasium'] = None; import husky_course.config, husky_course.cli"
    subprocess.run([sys.executable, "-c", blocked], check=True, cwd=ROOT)
    code = "import sys, husky_course.config; assert 'gymnasium' not in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


@pytest.mark.parametrize(
    "imports",
    [
        "import gymnasium, husky_course.config",  # gymnasium first (sorted imports, chapter 1)
        "import husky_course.config, gymnasium, husky_course.sim.env",  # the env's module registers it
    ],
)
def test_gymnasium_make_finds_the_environment(imports):
    code = f"{imports}; gymnasium.make('HuskyNav-v0').close()"
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)
