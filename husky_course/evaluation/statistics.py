"""Exact binomial statistics for success and collision rates (no scipy needed).

:func:`clopper_pearson` gives the exact interval of a binomial proportion: what a collision
*certificate* on held-out worlds is made of.
"""

from __future__ import annotations

import math
from typing import Any

from ..checks import check_int


def _binom_cdf(k: int, n: int, p: float) -> float:
    """P(X <= k) for X ~ Binomial(n, p), summed exactly in log space."""
    if k < 0:
        return 0.0
    if k >= n or p <= 0.0:
        return 1.0
    if p >= 1.0:
        return 0.0
    lp, lq = math.log(p), math.log1p(-p)
    logs = [
        math.lgamma(n + 1) - math.lgamma(i + 1) - math.lgamma(n - i + 1) + i * lp + (n - i) * lq
        for i in range(k + 1)
    ]
    top = max(logs)
    return min(1.0, math.exp(top) * math.fsum(math.exp(v - top) for v in logs))


def _solve_p(f: Any, target: float) -> float:
    """The p in [0, 1] with ``f(p) = target`` for a decreasing ``f``, by bisection."""
    lo, hi = 0.0, 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if f(mid) > target:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-15:
            break
    return 0.5 * (lo + hi)


def clopper_pearson(
    k: int, n: int, confidence: float = 0.95, alternative: str = "two-sided"
) -> tuple[float, float]:
    """Exact (Clopper-Pearson) confidence interval for a binomial proportion ``k / n``.

    Parameters
    ----------
    k, n : int
        Successes (or collisions) and trials, ``0 <= k <= n``, ``n >= 1``.
    confidence : float
        Confidence level in (0, 1).
    alternative : {"two-sided", "upper", "lower"}
        ``"upper"`` gives the one-sided bound ``(0, hi)`` with ``P(X <= k; hi) = 1 - confidence``;
        ``"lower"`` gives ``(lo, 1)``; ``"two-sided"`` splits ``1 - confidence`` between the tails.

    Returns
    -------
    (lo, hi) : tuple of float
    """
    k = check_int(k, "k", 0, 10**9)
    n = check_int(n, "n", max(k, 1), 10**9)
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1), got {confidence!r}")
    if alternative not in ("two-sided", "upper", "lower"):
        raise ValueError(f"alternative must be 'two-sided', 'upper' or 'lower', got {alternative!r}")
    alpha = 1.0 - confidence
    tail = alpha / 2 if alternative == "two-sided" else alpha
    lo, hi = 0.0, 1.0
    if alternative != "lower" and k < n:  # P(X <= k; hi) = tail
        hi = _solve_p(lambda p: _binom_cdf(k, n, p), tail)
    if alternative != "upper" and k > 0:  # P(X >= k; lo) = tail
        lo = _solve_p(lambda p: _binom_cdf(k - 1, n, p), 1.0 - tail)
    return lo, hi
