"""Cell constructors shared by the chapter sources."""

from __future__ import annotations

import nbformat as nbf


def md(text: str):
    """A markdown cell."""
    return nbf.v4.new_markdown_cell(text.strip())


def code(text: str):
    """A code cell."""
    return nbf.v4.new_code_cell(text.strip())
