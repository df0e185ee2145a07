"""PAC-Bayes generalization certificates, as in the lab's vision-based planning work.

A *stochastic* policy is a distribution ``P`` over network weights; at the start of an episode one
weight vector is drawn from ``P`` and the robot drives with it. Its cost ``C(P)`` is the expected
cost (here: 1 when the robot does not cross the course, which in the course's episodes means a
collision, 0 when it crosses) over the unknown
distribution of worlds. From ``N`` training worlds drawn from that distribution and a prior ``P0``
chosen *before* seeing them, the PAC-Bayes-kl bound (Maurer's form, the one the lab uses) says
that with probability at least ``1 - delta`` over the worlds, for every ``P`` at once,

    kl( C_S(P) || C(P) ) <= ( KL(P || P0) + log(2 sqrt(N) / delta) ) / N,

where ``C_S(P)`` is the average cost on the training worlds and ``kl`` the KL divergence between
Bernoulli distributions. Inverting ``kl`` in its second argument (:func:`kl_inverse`) turns this
into an upper bound on ``C(P)``.

``C_S(P)`` is itself an expectation over weights; it is estimated from weight vectors drawn from
``P`` (sample convergence). The lab draws ``L`` vectors and runs each on all ``N`` worlds: their
average costs are ``L`` independent values in ``[0, 1]`` with mean ``C_S(P)``, so with probability
at least ``1 - delta_prime``, ``C_S(P) <= kl_inverse(C_hat, log(2 / delta_prime) / L)``. The
course instead draws a fresh vector for every (world, draw) pair (``draws="per_world"``): then all
``L * N`` costs are independent (given the worlds), each in ``[0, 1]``, and their mean's expectation
is ``C_S(P)``; Hoeffding's inequality in its kl form holds for independent variables that are not
identically distributed, so the same bound holds with ``L * N`` in place of ``L`` -- far tighter
for the same number of episodes. Both bounds together hold with probability at least
``1 - delta - delta_prime`` (:func:`certificate`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..checks import is_int

#: Maurer's bound, with its ``2 sqrt(N)`` constant, is proven for at least this many worlds
MIN_WORLDS = 8


def bernoulli_kl(q: float, p: float) -> float:
    """``kl(q || p)`` between Bernoulli(q) and Bernoulli(p), in nats (``0 log 0 = 0``)."""
    for name, v in (("q", q), ("p", p)):
        if not 0.0 <= v <= 1.0 or math.isnan(v):
            raise ValueError(f"{name} must be a probability in [0, 1], got {v}")
    total = 0.0
    for a, b in ((q, p), (1.0 - q, 1.0 - p)):
        if a > 0.0:
            if b <= 0.0:
                return math.inf
            total += a * math.log(a / b)
    return max(total, 0.0)


def kl_inverse(q: float, c: float, tol: float = 1e-12) -> float:
    """The largest ``p`` in ``[q, 1]`` with ``kl(q || p) <= c``, by bisection.

    ``kl(q || p)`` is continuous and increasing in ``p`` on ``[q, 1]`` (from 0 at ``p = q``), so
    the set of feasible ``p`` is an interval ``[q, p*]`` and bisection finds ``p*`` to ``tol``.
    The answer returned is the upper end of the last bracket, so it never falls below ``p*``:
    a bound computed with it stays a bound.
    """
    if not 0.0 <= q <= 1.0 or math.isnan(q):
        raise ValueError(f"q must be a probability in [0, 1], got {q}")
    if not c >= 0.0:  # also catches NaN
        raise ValueError(f"c must be >= 0, got {c}")
    if q >= 1.0 or bernoulli_kl(q, 1.0) <= c:
        return 1.0
    lo, hi = q, 1.0  # kl(q || lo) <= c < kl(q || hi)
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if bernoulli_kl(q, mid) <= c:
            lo = mid
        else:
            hi = mid
    return hi


def gaussian_kl(
    mu_q: np.ndarray, logvar_q: np.ndarray, mu_p: np.ndarray, logvar_p: np.ndarray
) -> float:
    """``KL(Q || P)`` between diagonal Gaussians given by means and log-variances (nats)."""
    arrays = [np.asarray(a, np.float64) for a in (mu_q, logvar_q, mu_p, logvar_p)]
    if len({a.shape for a in arrays}) != 1:
        raise ValueError(f"means and log-variances must have one shape, got {[a.shape for a in arrays]}")
    mq, lq, mp, lp = arrays
    return float(0.5 * np.sum(lp - lq + (np.exp(lq) + (mq - mp) ** 2) / np.exp(lp) - 1.0))


def pac_bayes_kl_bound(train_cost: float, kl: float, n_worlds: int, delta: float) -> float:
    """Upper bound on ``C(P)`` from its training cost ``C_S(P)``, ``KL(P || P0)`` and ``N`` worlds.

    Maurer's constant ``2 sqrt(N)`` is proven for ``N >= 8``; fewer worlds are refused.
    """
    _check(n_worlds, delta)
    if n_worlds < MIN_WORLDS:
        raise ValueError(f"the PAC-Bayes-kl bound needs at least {MIN_WORLDS} worlds, got {n_worlds}")
    if kl < 0:
        raise ValueError(f"KL(P || P0) must be >= 0, got {kl}")
    return kl_inverse(train_cost, (kl + math.log(2.0 * math.sqrt(n_worlds) / delta)) / n_worlds)


def sample_convergence_bound(sampled_cost: float, n_policies: int, delta_prime: float) -> float:
    """Upper bound on ``C_S(P)`` from the average cost of ``L`` weight vectors drawn from ``P``."""
    _check(n_policies, delta_prime)
    return kl_inverse(sampled_cost, math.log(2.0 / delta_prime) / n_policies)


@dataclass(frozen=True)
class Certificate:
    """A PAC-Bayes certificate and the numbers it was made of (all costs in [0, 1])."""

    sampled_cost: float  #: average training cost of the sampled policies
    train_cost_bound: float  #: sample-convergence bound on C_S(P)
    bound: float  #: the certificate: C(P) <= bound with probability >= confidence
    kl: float
    n_worlds: int
    n_policies: int  #: "shared": weight vectors in all; "per_world": vectors drawn per world
    delta: float
    delta_prime: float
    draws: str = "shared"  #: "shared" (the lab's: each vector on every world) or "per_world"

    @property
    def confidence(self) -> float:
        return 1.0 - self.delta - self.delta_prime

    def to_json(self) -> dict:
        return {**asdict(self), "confidence": self.confidence}


def certificate(
    costs: np.ndarray, kl: float, delta: float = 0.009, delta_prime: float = 0.001, draws: str = "shared"
) -> Certificate:
    """The certificate from a ``(L, N)`` array of costs on ``N`` worlds.

    ``draws="shared"``: row ``l`` is one weight vector run on every world (the lab's protocol,
    ``L`` independent samples); ``draws="per_world"``: every entry had its own vector (``L * N``
    independent samples; see the module docstring).
    """
    if draws not in ("shared", "per_world"):
        raise ValueError(f"draws must be 'shared' or 'per_world', got {draws!r}")
    check_confidence(delta, delta_prime)
    costs = np.asarray(costs, np.float64)
    if costs.ndim != 2 or costs.size == 0:
        raise ValueError(f"costs must be a non-empty (policies, worlds) array, got shape {costs.shape}")
    if np.isnan(costs).any() or costs.min() < 0.0 or costs.max() > 1.0:
        raise ValueError("costs must lie in [0, 1]")
    n_policies, n_worlds = costs.shape
    sampled = float(costs.mean())
    samples = n_policies if draws == "shared" else n_policies * n_worlds
    train_bound = sample_convergence_bound(sampled, samples, delta_prime)
    return Certificate(
        sampled_cost=sampled,
        train_cost_bound=train_bound,
        bound=pac_bayes_kl_bound(train_bound, kl, n_worlds, delta),
        kl=float(kl),
        n_worlds=n_worlds,
        n_policies=n_policies,
        delta=delta,
        delta_prime=delta_prime,
        draws=draws,
    )


def check_confidence(delta: float, delta_prime: float) -> None:
    """Refuse ``delta``, ``delta_prime`` outside (0, 1) or summing to 1 or more (no confidence left)."""
    for d in (delta, delta_prime):
        if not 0.0 < d < 1.0:
            raise ValueError(f"a confidence parameter must lie in (0, 1), got {d}")
    if not delta + delta_prime < 1.0:
        raise ValueError(f"delta + delta_prime must be below 1 (the confidence), got {delta} + {delta_prime}")


def _check(n: int, delta: float) -> None:
    if not is_int(n) or n < 1:
        raise ValueError(f"the number of samples must be a positive integer, got {n}")
    if not 0.0 < delta < 1.0:
        raise ValueError(f"a confidence parameter must lie in (0, 1), got {delta}")
