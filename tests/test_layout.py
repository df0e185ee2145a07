"""The package reads as the pipeline: one-way imports between stages, no circles, no hidden deps.

Stages, lowest first (a module may import from its own stage or a lower one, never a higher one):
the floor (``config``, ``checks``, ``progress``) -> ``sim`` -> ``data`` -> ``models`` ->
``training`` -> ``planners`` -> ``imitation`` -> ``evaluation`` -> ``course`` / ``ui`` -> ``cli``.
"""

from __future__ import annotations

import ast
import importlib.metadata
import re
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


def _declared() -> set[str]:
    deps = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    return {re.split(r"[<>=!~\[; ]", d, maxsplit=1)[0].lower().replace("_", "-") for d in deps}


def _missing(declared: set[str]) -> dict[str, list[str]]:
    """Third-party modules the package imports whose distribution is not in ``declared``."""
    third_party = set()
    for path in MODULES.values():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                third_party |= {a.name.split(".")[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                third_party.add(node.module.split(".")[0])
    third_party -= set(sys.stdlib_module_names) | {"husky_course"}
    dists = importlib.metadata.packages_distributions()
    needed = {m: {d.lower().replace("_", "-") for d in dists.get(m, [m])} for m in third_party}
    if any(m == "torch" for m in third_party):  # SummaryWriter, imported inside torch at run time
        needed["tensorboard (torch.utils.tensorboard)"] = {"tensorboard"}
    return {m: sorted(d) for m, d in needed.items() if not d & declared}


def test_runtime_imports_are_declared_dependencies():
    """An install of the package alone (``pip install .``) must bring everything it imports."""
    missing = _missing(_declared())
    assert not missing, f"imported but not in pyproject's dependencies: {missing}"


def test_a_missing_dependency_is_caught():
    assert "torch" in _missing(_declared() - {"torch"})
