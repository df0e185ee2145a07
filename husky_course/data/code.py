"""Fingerprints of the library's *code*: what every artifact key holds besides its configs and inputs.

An artifact is rebuilt exactly when the code that made it changes. :func:`code_fingerprint` hashes
the modules that make an artifact together with every ``husky_course`` module they import, at any
depth (the imports are read with :mod:`ast`, never executed, so a key can name a module of a
higher stage without importing it). Each module enters as its syntax tree with every docstring
(and every other bare string statement) removed, dumped without line numbers: a comment, a
docstring or a reformatting changes no fingerprint; a changed statement, name or constant does.

Two modules never enter: ``husky_course.config`` (the package, with its modules), because every
key already holds the config *values* its artifact was built under (an edit there either changes
those values, and so the keys, or changes nothing an artifact depends on), and
``husky_course.progress``, which only draws progress bars and prints what is being built.
:func:`library_fingerprint` (the book's execution cache, ``make book``) covers every module, these
two included.

Fingerprints are cached per process and per ``root``: tests point ``root`` at an edited copy of
the package.
"""

from __future__ import annotations

import ast
import functools
import hashlib
from pathlib import Path

PACKAGE = "husky_course"
#: modules whose edits reach the keys through config values or not at all (module docstring)
NEUTRAL = frozenset({f"{PACKAGE}.config", f"{PACKAGE}.progress"})


def package_root() -> Path:
    """The installed package's directory (``.../husky_course``)."""
    return Path(__file__).resolve().parents[1]


def module_path(name: str, root: Path | None = None) -> Path | None:
    """The file of module ``name`` (``husky_course.x.y``) under ``root``, or None if there is none."""
    parts = name.split(".")
    if parts[0] != PACKAGE:
        return None
    base = (root or package_root()).joinpath(*parts[1:])
    for path in (base.with_suffix(".py") if len(parts) > 1 else None, base / "__init__.py"):
        if path is not None and path.is_file():
            return path
    return None


class _DropStrings(ast.NodeTransformer):
    """Removes docstrings and other bare string statements (they do nothing when run)."""

    def generic_visit(self, node: ast.AST) -> ast.AST:
        super().generic_visit(node)
        for field in ("body", "orelse", "finalbody"):
            body = getattr(node, field, None)
            if isinstance(body, list) and body and isinstance(body[0], ast.stmt):
                kept = [s for s in body if not (isinstance(s, ast.Expr) and isinstance(s.value, ast.Constant)
                                                and isinstance(s.value.value, str))]
                setattr(node, field, kept or ([ast.Pass()] if field == "body" else []))
        return node


@functools.cache
def _parsed(path: Path) -> tuple[str, frozenset[str]]:
    """``(normalised source, package modules imported)`` of the module at ``path``."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    return ast.dump(_DropStrings().visit(tree), include_attributes=False), frozenset(_raw_imports(tree))


def _raw_imports(tree: ast.AST) -> set[str]:
    """Imported names as written: ``(level, module, alias)`` joined as ``"level|module|alias"``."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            found |= {f"{node.level}|{node.module or ''}|{a.name}" for a in node.names}
        elif isinstance(node, ast.Import):
            found |= {f"0|{a.name}|" for a in node.names}
    return found


def imports(name: str, root: Path | None = None) -> set[str]:
    """The ``husky_course`` modules that module ``name`` imports (relative imports resolved)."""
    path = module_path(name, root)
    if path is None:
        raise ValueError(f"no module {name!r} in {root or package_root()}")
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found = set()
    for raw in _parsed(path)[1]:
        level, module, alias = raw.split("|")
        if int(level):
            base = package.split(".")[: len(package.split(".")) - (int(level) - 1)]
            module = ".".join(base + ([module] if module else []))
        if module != PACKAGE and not module.startswith(PACKAGE + "."):
            continue
        sub = f"{module}.{alias}" if alias else module  # `from pkg import mod` names a module
        found.add(sub if alias and module_path(sub, root) is not None else module)
    return {m for m in found if module_path(m, root) is not None}


def closure(*modules: str, root: Path | None = None, neutral: frozenset[str] = NEUTRAL) -> list[str]:
    """``modules`` and every package module they import at any depth, sorted, less ``neutral``."""
    def is_neutral(m: str) -> bool:  # a neutral package's modules are neutral too
        return any(m == n or m.startswith(n + ".") for n in neutral)

    todo, seen = [m for m in modules if not is_neutral(m)], set()
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        todo += [m for m in imports(name, root) if not is_neutral(m) and m not in seen]
    return sorted(seen)


@functools.cache
def code_fingerprint(*modules: str, root: Path | None = None) -> str:
    """A short sha256 of the normalised code of ``modules`` and their imports (module docstring).

    Raises
    ------
    ValueError
        When a module named is not in the package.
    """
    return _digest(closure(*modules, root=root), root)


@functools.cache
def module_fingerprint(name: str, root: Path | None = None) -> str:
    """The fingerprint of module ``name`` alone, its imports not followed (for a module that gathers
    several builders, each of which names the modules it needs)."""
    return _digest([name], root)


@functools.cache
def library_fingerprint(root: Path | None = None) -> str:
    """:func:`code_fingerprint` of every module of the package, ``config`` and ``progress`` included."""
    base = root or package_root()
    names = []
    for path in sorted(base.rglob("*.py")):
        parts = path.relative_to(base).with_suffix("").parts
        names.append(".".join((PACKAGE, *(parts[:-1] if parts[-1] == "__init__" else parts))))
    return _digest(sorted(names), root)


def _digest(names: list[str], root: Path | None) -> str:
    h = hashlib.sha256()
    for name in names:
        path = module_path(name, root)
        if path is None:
            raise ValueError(f"no module {name!r} in {root or package_root()}")
        h.update(f"{name}\0{_parsed(path)[0]}\0".encode())
    return h.hexdigest()[:16]
