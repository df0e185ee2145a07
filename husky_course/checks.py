"""Input checks shared by every stage, so each bad input gets the same clear message.

Integers arrive from users (CLI flags, notebook arguments, Gymnasium actions) as Python ints,
numpy integers, bools or floats; :func:`check_int` accepts the first two and refuses the rest,
with the name of what was being set and the allowed range.
"""

from __future__ import annotations

import numpy as np


def is_int(value: object) -> bool:
    """True for Python and numpy integers, False for bools, floats and everything else."""
    return not isinstance(value, (bool, np.bool_)) and isinstance(value, (int, np.integer))


def check_int(
    value: object,
    what: str,
    lo: int | None = None,
    hi: int | None = None,
    error: type[Exception] = ValueError,
) -> int:
    """Return ``value`` as an ``int`` if it is an integer in ``[lo, hi]``, else raise ``error``.

    Parameters
    ----------
    value : object
        What the caller passed.
    what : str
        Its name in the message, e.g. ``"the number of evaluation worlds"``.
    lo, hi : int, optional
        Inclusive bounds; ``None`` leaves that side open.
    error : exception class
        Raised on a bad value (``ValueError`` unless the stage has its own error type).
    """
    if not is_int(value):
        raise error(f"{what} must be an integer, got {value!r}")
    v = int(value)  # type: ignore[call-overload]
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        if hi is None:
            raise error(f"{what} must be >= {lo}, got {v}")
        if lo is None:
            raise error(f"{what} must be <= {hi}, got {v}")
        raise error(f"{what} must be in {lo}..{hi}, got {v}")
    return v
