"""Progress bars that suit where the code runs.

In a live Jupyter kernel a bar is an ipywidget (``tqdm.auto``). Where widgets cannot render (the
built book read offline) it is a plain text bar on stderr, which the book leaves out, so no page
holds an empty widget box. One switch says so, set explicitly where it is wanted (``make book``,
the browser test's book build): ``HUSKY_STATIC_WIDGETS=1``. Nothing else changes the library's
behaviour, ``CI`` included, so a CI run executes the chapters as a student's kernel does.
"""

from __future__ import annotations

import os
import sys
from typing import Any

#: the one switch for static widgets and text progress bars (``1``; unset, empty or ``0``: live)
STATIC_ENV = "HUSKY_STATIC_WIDGETS"


def static_mode() -> bool:
    """True when interactive widgets must not be emitted: ``HUSKY_STATIC_WIDGETS`` set, not ``0``."""
    return os.environ.get(STATIC_ENV, "").strip().lower() not in ("", "0", "false", "no")


def _in_kernel() -> bool:
    """Whether this code runs in a Jupyter kernel (an IPython shell with a kernel attached)."""
    ipython = sys.modules.get("IPython")
    shell = ipython.get_ipython() if ipython is not None else None
    return getattr(shell, "kernel", None) is not None


def announce_build(what: str, profile_name: str, command: str) -> None:
    """One line before an artifact is built: what, roughly how long, and how to build it ahead.

    ``command`` is the CLI subcommand that builds it (``"train joint"``, ``"collect"``).

    A notebook that finds an artifact missing says so before its progress bar starts, so that a
    student knows why a cell takes minutes (and a teacher how to avoid it before class). In a
    notebook the line goes to stdout (stderr would be drawn as an error); elsewhere to stderr, so
    that a command's stdout stays what it prints (the CLI's JSON).
    """
    from .config import get_profile  # the floor: config has no imports from here

    minutes = get_profile(profile_name).minutes_to_build(what)
    if minutes is None:
        how_long = "time not measured"
    else:
        how_long = ("under a minute" if minutes < 1 else f"about {minutes:g} min") + " on 2 CPU cores"
    print(
        f"Building {what} ({profile_name} profile): not in the artifact store yet, {how_long}; "
        f"later runs load it. Ahead of time: `python -m husky_course {command} --profile {profile_name}`.",
        file=sys.stdout if _in_kernel() else sys.stderr,
        flush=True,
    )


def tqdm(*args: Any, **kwargs: Any) -> Any:
    """``tqdm.auto.tqdm``, or the text ``tqdm.tqdm`` in :func:`static_mode`."""
    if static_mode():
        from tqdm import tqdm as text_bar

        return text_bar(*args, **kwargs)
    from tqdm.auto import tqdm as auto_bar

    return auto_bar(*args, **kwargs)
