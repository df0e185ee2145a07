"""Chapter 9's certificate: the Gaussian over the student's output layer, its sampled costs, the artifact.

The mathematics of the bound is tested in ``test_pac_bayes.py``; here, the pieces that turn the
memory student into a certified stochastic policy (quick profile, built by ``train all``).
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import torch

from husky_course.config import get_profile
from husky_course.course import exercises
from husky_course.data.io import DatasetError
from husky_course.evaluation.certificate import (
    _blocks,
    _heldout_prefix,
    certificate_dir,
    load_certificate,
    sampled_costs,
)
from husky_course.evaluation.episodes import eval_world_seeds, run_episode
from husky_course.evaluation.pac_bayes import certificate, gaussian_kl, kl_inverse, pac_bayes_kl_bound
from husky_course.evaluation.statistics import clopper_pearson
from husky_course.imitation.dagger import round_worlds
from husky_course.imitation.posterior import GaussianLayer, _optimise, certificate_worlds, prior
from husky_course.models.memory import get_last_layer, set_last_layer
from husky_course.planners.memory import MemoryPlanner
from husky_course.sim.fast import FastSimulator
from husky_course.training.memory import load_memory
from husky_course.training.trainer import CheckpointError

QUICK = get_profile("quick")


@pytest.fixture(scope="module")
def student():
    return load_memory(QUICK)[0]


def test_the_gaussian_layer_kl_matches_the_closed_form_and_draws_are_pure(student):
    p0 = prior(student, QUICK)
    assert p0.kl() == pytest.approx(0.0, abs=1e-9)  # log s0 is stored in float32
    rng = np.random.default_rng(0)
    layer = replace(p0, mean=p0.mean + 0.01 * rng.standard_normal(p0.mean.size).astype(np.float32),
                    log_std=p0.log_std + 0.2 * rng.standard_normal(p0.mean.size).astype(np.float32))
    want = gaussian_kl(layer.mean, 2 * layer.log_std, layer.prior_mean,
                       np.full(p0.mean.size, 2 * math.log(layer.prior_std)))
    assert layer.kl() == pytest.approx(want, rel=1e-9)
    assert np.array_equal(layer.draw(0, 7, 0), layer.draw(0, 7, 0))
    assert not np.array_equal(layer.draw(0, 7, 0), layer.draw(0, 8, 0))
    assert not np.array_equal(layer.draw(0, 7, 0), layer.draw(0, 7, 1))
    back = GaussianLayer.from_arrays(layer.arrays())
    assert back.kl() == layer.kl() and np.array_equal(back.draw(1, 2, 3), layer.draw(1, 2, 3))


def test_the_output_layer_round_trips_and_bad_vectors_are_refused(student):
    w = get_last_layer(student)
    model = type(student)(student.horizon, student.map_cells)
    model.load_state_dict(student.state_dict())
    set_last_layer(model, w + 1.0)
    assert torch.equal(get_last_layer(model), w + 1.0)
    assert torch.equal(get_last_layer(student), w), "the student must be untouched"
    with pytest.raises(ValueError, match="vector of"):
        set_last_layer(model, w[:-1])


def test_fitting_pays_for_moving_away_from_the_prior():
    """On synthetic features, the posterior moves towards the data, less so the fewer the worlds."""
    gen = torch.Generator().manual_seed(0)
    h = torch.randn(2000, 8, generator=gen)
    w_true = torch.randn(3, 8, generator=gen)
    target = torch.sigmoid(h @ w_true.T)
    start = GaussianLayer(np.zeros(27, np.float32), np.full(27, math.log(0.1), np.float32),
                          np.zeros(27, np.float32), 0.1, np.zeros(0))
    moved = {}
    for worlds in (10, 100_000):
        profile = replace(QUICK, guarantee=replace(QUICK.guarantee, worlds=worlds))
        post = _optimise(h, target, start, 3, profile, progress=False)
        assert post.losses[-1] < post.losses[0]
        moved[worlds] = post.kl()
    assert 0 < moved[10] < moved[100_000], moved


def test_sampled_costs_are_the_deterministic_episodes_at_zero_deviation_for_any_workers(student):
    w0 = get_last_layer(student).numpy()
    frozen = GaussianLayer(w0, np.full_like(w0, -np.inf), w0, 1.0, np.zeros(0))
    seeds = eval_world_seeds(30, 1)
    args = (student, frozen, seeds, 1, QUICK.sim, QUICK.memory, 0)
    costs, prims = sampled_costs(*args, workers=1, progress=False)
    assert costs.shape == prims.shape == (1, 30) and costs.dtype == np.uint8
    planner, sim = MemoryPlanner(student, QUICK.sim, QUICK.memory), FastSimulator(QUICK.sim)
    episodes = [run_episode(planner, sim, int(s)) for s in seeds]
    assert costs[0].tolist() == [int(not e.success) for e in episodes]
    assert prims[0].tolist() == [e.n_prims for e in episodes]
    noisy = replace(frozen, log_std=np.full_like(w0, math.log(0.5)))
    one = sampled_costs(student, noisy, seeds, 2, QUICK.sim, QUICK.memory, 0, workers=1, progress=False)
    two = sampled_costs(student, noisy, seeds, 2, QUICK.sim, QUICK.memory, 0, workers=2, progress=False)
    assert np.array_equal(one[0], two[0]) and np.array_equal(one[1], two[1])
    assert torch.equal(get_last_layer(student), torch.from_numpy(w0)), "the student must be untouched"


def test_the_stored_certificate_is_consistent_with_its_costs():
    result = load_certificate(QUICK)
    g, cert = QUICK.guarantee, result.certificate
    assert result.train_costs.shape == (g.draws_per_world, g.worlds)
    assert result.heldout_costs.shape == (g.heldout_worlds,)
    again = certificate(result.train_costs, result.posterior.kl(), g.delta, g.delta_prime, draws="per_world")
    assert again == cert
    assert cert.sampled_cost <= cert.train_cost_bound <= cert.bound <= 1.0
    assert cert.confidence == pytest.approx(1 - g.delta - g.delta_prime)
    k, n = int(result.heldout_costs.sum()), g.heldout_worlds
    assert result.test_bound == clopper_pearson(k, n, cert.confidence, "upper")[1]
    stored = json.loads((Path(result.path) / f"certificate-set{g.heldout_set}-{n}.json").read_text())
    assert stored["certificate"]["bound"] == cert.bound and stored["heldout_cost"] == k / n
    unfitted = result.train_costs[0, g.finetune_worlds :]
    assert np.array_equal(result.unfitted_costs, unfitted)
    want = clopper_pearson(int(unfitted.sum()), unfitted.size, cert.confidence, "upper")[1]
    assert result.unfitted_bound == want
    assert len(set(certificate_worlds(QUICK)) & set(eval_world_seeds(n, g.heldout_set))) == 0


@pytest.mark.parametrize("name", ["quick", "full"])
def test_the_prior_never_saw_the_certificate_worlds(name):
    """The prior is the DAgger student: its worlds and the certificate's must not overlap."""
    profile = get_profile(name)
    dagger = {int(s) for r in range(profile.memory.rounds) for s in round_worlds(profile, r)}
    assert not dagger & set(certificate_worlds(profile).tolist())
    seed = profile.memory.collection_seed
    clash = replace(profile, guarantee=replace(profile.guarantee, collection_seed=seed))
    with pytest.raises(ValueError, match="never saw"):
        certificate_worlds(clash)


def test_more_heldout_worlds_reuse_the_stored_blocks(tmp_path):
    """The held-out worlds are not in the artifact's key: a longer run starts from the stored blocks."""
    small = replace(QUICK, guarantee=replace(QUICK.guarantee, heldout_worlds=10))
    assert certificate_dir(small) == certificate_dir(QUICK)
    other_set = replace(QUICK, guarantee=replace(QUICK.guarantee, heldout_set=5))
    assert certificate_dir(other_set) == certificate_dir(QUICK)
    assert _heldout_prefix(Path("r"), other_set) != _heldout_prefix(Path("r"), QUICK)


def test_a_block_of_other_worlds_is_refused(tmp_path):
    seeds = np.arange(5, dtype=np.int64)
    _blocks(tmp_path / "train", seeds, lambda w, _: (np.zeros((1, len(w)), np.uint8),) * 2)
    with pytest.raises(DatasetError, match="other worlds"):
        _blocks(tmp_path / "train", seeds + 1, None)


def test_bad_confidence_and_too_few_worlds_are_refused():
    with pytest.raises(ValueError, match="below 1"):
        certificate(np.zeros((1, 10)), 0.0, delta=0.6, delta_prime=0.5)
    with pytest.raises(ValueError, match="at least 8"):
        pac_bayes_kl_bound(0.1, 0.0, 7, 0.01)


def test_load_never_builds(tmp_path, monkeypatch):
    monkeypatch.setenv("HUSKY_ARTIFACTS", str(tmp_path))
    with pytest.raises(CheckpointError, match="train certificate"):
        load_certificate(QUICK)
    assert not any(tmp_path.iterdir())


def test_chapter_9_exercise_checks():
    assert exercises.check_kl_inverse(0.1, 0.02, kl_inverse(0.1, 0.02))
    with pytest.raises(AssertionError, match="below q"):
        exercises.check_kl_inverse(0.1, 0.02, 0.05)
    with pytest.raises(AssertionError):
        exercises.check_kl_inverse(0.1, 0.02, kl_inverse(0.1, 0.04))
    n = next(n for n in range(8, 100_000) if pac_bayes_kl_bound(0.2, 20, n, 0.009) <= 0.25)
    assert exercises.check_worlds_for_pac_bayes(0.2, 20, 0.25, n, 0.009)
    with pytest.raises(AssertionError, match="more worlds"):
        exercises.check_worlds_for_pac_bayes(0.2, 20, 0.25, n - 1, 0.009)
    with pytest.raises(AssertionError, match="fewest"):
        exercises.check_worlds_for_pac_bayes(0.2, 20, 0.25, n + 1, 0.009)


def test_cli_certify_prints_the_stored_certificate_and_refuses_bad_sizes(capsys):
    from husky_course.cli import main

    assert main(["certify", "--profile", "quick", "--worlds", "0"]) == 2
    assert "--worlds" in capsys.readouterr().err
    assert main(["certify", "--profile", "quick", "--no-progress"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed["certificate"]["bound"] == load_certificate(QUICK).certificate.bound
