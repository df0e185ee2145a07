"""Progress bars that suit where the code runs.

In a live Jupyter kernel a bar is an ipywidget (``tqdm.auto``). Where widgets cannot render (the
built book read offline, CI, ``HUSKY_STATIC_WIDGETS=1``) it is a plain text bar on stderr, which
the book leaves out, so no page holds an empty widget box.
"""

from __future__ import annotations

import os
from typing import Any


def static_mode() -> bool:
    """True when interactive widgets must not be emitted (``HUSKY_STATIC_WIDGETS`` or ``CI`` set)."""
    return bool(os.environ.get("HUSKY_STATIC_WIDGETS") or os.environ.get("CI"))


def tqdm(*args: Any, **kwargs: Any) -> Any:
    """``tqdm.auto.tqdm``, or the text ``tqdm.tqdm`` in :func:`static_mode`."""
    if static_mode():
        from tqdm import tqdm as text_bar

        return text_bar(*args, **kwargs)
    from tqdm.auto import tqdm as auto_bar

    return auto_bar(*args, **kwargs)
