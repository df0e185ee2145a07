"""PAC-Bayes certificates: the kl inverse against brute force, the whole bound on a known toy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from husky_course.evaluation.pac_bayes import (
    bernoulli_kl,
    certificate,
    gaussian_kl,
    kl_inverse,
    pac_bayes_kl_bound,
    sample_convergence_bound,
)


def brute_force_kl_inverse(q: float, c: float, step: float = 1e-6) -> float:
    """The largest grid point p >= q with kl(q || p) <= c, computed independently (vectorised)."""
    p = np.arange(q, 1.0 + step, step).clip(max=1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(q > 0, q * np.log(q / p), 0.0)
        b = np.where(q < 1, (1 - q) * np.log((1 - q) / (1 - p)), 0.0)
    kl = np.nan_to_num(a + b, nan=np.inf, posinf=np.inf)
    return float(p[kl <= c].max())


@pytest.mark.parametrize(
    ("q", "c"),
    [(0.0, 0.01), (0.05, 0.002), (0.2, 0.05), (0.5, 0.1), (0.9, 0.01), (0.3, 0.0), (0.99, 5.0), (1.0, 0.3)],
)
def test_kl_inverse_matches_brute_force(q, c):
    got = kl_inverse(q, c)
    want = brute_force_kl_inverse(q, c)
    assert want - 1e-9 <= got <= want + 2e-6  # the grid's step; bisection never rounds down
    assert bernoulli_kl(q, min(got, 1.0)) <= c + 1e-6 or got == 1.0


def test_kl_inverse_is_monotone_and_bad_input_is_refused():
    qs = np.linspace(0, 0.9, 10)
    assert all(kl_inverse(a, 0.05) <= kl_inverse(b, 0.05) for a, b in zip(qs, qs[1:], strict=False))
    cs = np.linspace(0, 1, 10)
    assert all(kl_inverse(0.2, a) <= kl_inverse(0.2, b) for a, b in zip(cs, cs[1:], strict=False))
    for q, c in ((-0.1, 0.1), (1.1, 0.1), (float("nan"), 0.1), (0.2, -1.0), (0.2, float("nan"))):
        with pytest.raises(ValueError):
            kl_inverse(q, c)


def test_gaussian_kl_known_values():
    assert gaussian_kl(np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)) == 0.0
    # KL(N(1, 1) || N(0, 1)) = 1/2 per dimension; KL(N(0, e) || N(0, 1)) = (e - 1 - 1) / 2
    assert gaussian_kl(np.ones(4), np.zeros(4), np.zeros(4), np.zeros(4)) == pytest.approx(2.0)
    assert gaussian_kl([0.0], [1.0], [0.0], [0.0]) == pytest.approx((math.e - 2.0) / 2)
    with pytest.raises(ValueError):
        gaussian_kl(np.zeros(2), np.zeros(3), np.zeros(2), np.zeros(2))


def test_the_certificate_holds_on_a_toy_whose_true_cost_is_known():
    """Policies are weights theta; a world is u ~ U(0, 1); cost(theta, u) = 1[u < sigmoid(theta)].

    The posterior N(mu, s^2) has true cost E[sigmoid(theta)] (quadrature). Over many independent
    draws of training worlds and policy samples, the certificate at confidence 0.9 must hold in at
    least 90% of them (it holds in all, being conservative), and it must not be vacuous.
    """
    mu_q, s_q, mu_p, s_p = -1.5, 0.3, 0.0, 1.0  # posterior and prior (prior fixed in advance)
    grid = np.linspace(-8, 8, 200_001)
    density = np.exp(-0.5 * ((grid - mu_q) / s_q) ** 2) / (s_q * math.sqrt(2 * math.pi))
    true_cost = float(np.trapezoid(density / (1 + np.exp(-grid)), grid))
    kl = gaussian_kl([mu_q], [2 * math.log(s_q)], [mu_p], [2 * math.log(s_p)])
    rng = np.random.default_rng(0)
    n_worlds, n_policies, trials = 2000, 200, 100
    held, bounds = 0, []
    for _ in range(trials):
        u = rng.random(n_worlds)
        theta = rng.normal(mu_q, s_q, n_policies)
        costs = (u[None, :] < 1 / (1 + np.exp(-theta[:, None]))).astype(float)
        cert = certificate(costs, kl, delta=0.05, delta_prime=0.05)
        bounds.append(cert.bound)
        held += cert.bound >= true_cost
        assert cert.sampled_cost <= cert.train_cost_bound <= cert.bound
    assert held / trials >= 0.9, f"held in {held}/{trials} trials"
    assert np.median(bounds) < true_cost + 0.15, f"vacuous: median bound {np.median(bounds)} vs {true_cost}"


def test_more_worlds_tighten_the_bound_and_kl_loosens_it():
    assert pac_bayes_kl_bound(0.1, 1.0, 10_000, 0.01) < pac_bayes_kl_bound(0.1, 1.0, 1_000, 0.01)
    assert pac_bayes_kl_bound(0.1, 10.0, 1_000, 0.01) > pac_bayes_kl_bound(0.1, 1.0, 1_000, 0.01)
    assert sample_convergence_bound(0.1, 100, 0.01) > 0.1
    with pytest.raises(ValueError):
        pac_bayes_kl_bound(0.1, -1.0, 100, 0.01)
    with pytest.raises(ValueError):
        certificate(np.array([[0.5, 1.5]]), 1.0)


def test_per_world_draws_bound_the_training_cost_and_the_true_cost():
    """One weight vector per world (the course's protocol, ``draws="per_world"``).

    On fixed worlds u_i, C_S = mean_i P(theta > logit u_i) exactly; the sample-convergence bound at
    delta' = 0.2 must cover it in at least 80% of independent weight draws (it covers far more: the
    constant is the lab's two-sided one), and the whole certificate must cover the true cost.
    """
    mu_q, s_q = -1.5, 0.3
    kl = gaussian_kl([mu_q], [2 * math.log(s_q)], [0.0], [0.0])
    rng = np.random.default_rng(1)
    n_worlds, trials = 2000, 300
    u = rng.random(n_worlds)
    logit = np.log(u / (1 - u))
    train_cost = float(np.mean([0.5 * math.erfc((x - mu_q) / (s_q * math.sqrt(2))) for x in logit]))
    covered = 0
    for _ in range(trials):
        theta = rng.normal(mu_q, s_q, n_worlds)
        costs = (u < 1 / (1 + np.exp(-theta)))[None, :].astype(float)
        cert = certificate(costs, kl, delta=0.05, delta_prime=0.2, draws="per_world")
        covered += cert.train_cost_bound >= train_cost
        assert cert.draws == "per_world" and cert.n_policies == 1 and cert.n_worlds == n_worlds
    assert covered / trials >= 0.8, f"covered in {covered}/{trials}"
    # per-world draws are far tighter than one shared vector for the same number of episodes
    shared = certificate(costs, kl, delta=0.05, delta_prime=0.2)
    assert cert.train_cost_bound < shared.train_cost_bound
    with pytest.raises(ValueError, match="draws"):
        certificate(costs, kl, draws="each")
