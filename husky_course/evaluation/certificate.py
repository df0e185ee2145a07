"""Chapter 9's certificate as an artifact: the posterior, its sampled costs, the bound, the held-out check.

Built once by :func:`get_certificate` (``python -m husky_course train certificate``), in resumable
pieces under ``artifacts/<profile>/models/certificate-<hash>/`` (the hash covers everything but the
held-out worlds, so measuring on more held-out worlds reuses the rest):

1. ``posterior.npz`` -- the Gaussian over the student's output layer
   (:func:`husky_course.imitation.posterior.fit_posterior`);
2. ``train_<k>.npz`` -- blocks of :data:`BLOCK` worlds: the costs of weight vectors drawn from it
   on the ``N`` certificate training worlds (``draws_per_world`` fresh draws per world);
3. ``heldout-set<s>/block_<k>.npz`` -- one draw per world on the evaluation worlds of evaluation
   set ``s``: the cost the certificate is about, measured (a longer run reuses the first blocks);
4. ``certificate-set<s>-<n>.json`` -- the numbers, with ``n`` held-out worlds.

Every block stores its world seeds and is checked against them when read. A cost is 1 when the
robot does not cross (in an episode, a collision), else 0. Draw ``d`` in world ``w`` uses weights
:meth:`~husky_course.imitation.posterior.GaussianLayer.draw` ``(seed, w, d)``, so every cost is a
pure function of the world and the draw, on either engine and for any number of workers (on one
kind of hardware with the same library versions: float rounding may differ across CPUs).
:func:`load_certificate` never builds.
"""

from __future__ import annotations

import copy
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from ..config import EvalPlan, MemoryConfig, Profile, SimConfig, to_dict, world_flag
from ..data.code import code_fingerprint
from ..data.io import DatasetError, atomic_save_npz, atomic_write_bytes, load_npz
from ..data.store import model_dir
from ..engines import ENGINE, map_tasks
from ..imitation.posterior import GaussianLayer, certificate_worlds, fit_posterior
from ..models.memory import MemoryNet, set_last_layer
from ..planners.memory import MemoryPlanner
from ..progress import announce_build
from ..sim.fast import FastSimulator
from ..training.memory import final_fingerprint, load_memory
from ..training.trainer import CheckpointError
from .episodes import eval_world_seeds, run_episode
from .pac_bayes import Certificate, certificate, check_confidence
from .statistics import clopper_pearson

BLOCK = 1_000  #: worlds per stored block (the unit of resumable work)
FORMAT = 2
KEY_FILE = "key.json"  #: the fingerprint the directory's name hashes, as built


@dataclass
class CertificateResult:
    """Everything chapter 9 shows.

    Attributes
    ----------
    certificate : Certificate
        The PAC-Bayes bound on the posterior's expected cost, from the training worlds alone.
    posterior : GaussianLayer
        The certified distribution over the output layer (and its prior).
    train_costs, train_prims : ndarray, shape (draws_per_world, N)
        Cost (1 = did not cross) and primitives applied of every draw on every training world.
    heldout_costs, heldout_prims : ndarray, shape (heldout_worlds,)
        The same on the held-out evaluation worlds (one draw each).
    heldout_cost : float
        The measured expected cost on held-out worlds.
    heldout_ci95 : (float, float)
        Its exact two-sided 95% interval.
    test_bound : float
        The Clopper-Pearson upper bound on the cost from the held-out worlds, at the certificate's
        own confidence (the test-set bound the course had before).
    unfitted_costs : ndarray, shape (N - finetune_worlds,)
        First-draw costs on the training worlds the posterior was *not* fitted on (all but the first
        ``finetune_worlds``): independent of the posterior, so held-out worlds in all but name.
    unfitted_bound : float
        Their Clopper-Pearson bound at the certificate's confidence: a test-set bound that spends
        no extra worlds.
    path : str
        The artifact's directory.
    """

    certificate: Certificate
    posterior: GaussianLayer
    train_costs: np.ndarray
    train_prims: np.ndarray
    heldout_costs: np.ndarray
    heldout_prims: np.ndarray
    heldout_cost: float
    heldout_ci95: tuple[float, float]
    test_bound: float
    unfitted_costs: np.ndarray
    unfitted_bound: float
    path: str

    def to_json(self) -> dict:
        """The numbers (no arrays)."""
        return {
            "certificate": self.certificate.to_json(),
            "kl": self.posterior.kl(),
            "prior_std": self.posterior.prior_std,
            "posterior_std_mean": float(self.posterior.std.mean()),
            "train_mean_prims": float(self.train_prims.mean()),
            "heldout_worlds": int(self.heldout_costs.size),
            "heldout_cost": self.heldout_cost,
            "heldout_ci95": list(self.heldout_ci95),
            "heldout_mean_prims": float(self.heldout_prims.mean()),
            "test_bound": self.test_bound,
            "unfitted_worlds": int(self.unfitted_costs.size),
            "unfitted_cost": float(self.unfitted_costs.mean()) if self.unfitted_costs.size else None,
            "unfitted_bound": self.unfitted_bound,
        }


#: what computes the certificate (with its imports: the posterior, the student planner, episodes)
CERTIFICATE_CODE = (__name__,)


def certificate_fingerprint(profile: Profile) -> dict:
    """What determines the certificate: the student, the guarantee config (but its held-out worlds),
    the simulator, the format and the code that computes it (:data:`CERTIFICATE_CODE`)."""
    guarantee = {k: v for k, v in to_dict(profile.guarantee).items() if not k.startswith("heldout_")}
    return {"format": FORMAT, "block": BLOCK, "student": final_fingerprint(profile),
            "guarantee": guarantee, "sim": to_dict(profile.sim), "code": code_fingerprint(*CERTIFICATE_CODE)}


def certificate_dir(profile: Profile) -> Path:
    """Where the certificate's pieces live (it may not exist yet)."""
    return model_dir("certificate", certificate_fingerprint(profile), profile)


def _cost_task(shared: tuple, job: tuple) -> tuple[np.ndarray, np.ndarray]:
    """A task: costs and primitives ``(draws, len(worlds))`` of sampled weights in a chunk of worlds."""
    model, layer, sim_config, memory_config, seed = shared
    world_seeds, draws = job
    model = copy.deepcopy(model)  # the weights are overwritten per draw; never touch the caller's
    planner = MemoryPlanner(model, sim_config, memory_config)
    costs = np.zeros((draws, len(world_seeds)), np.uint8)
    prims = np.zeros((draws, len(world_seeds)), np.uint8)
    with FastSimulator(sim_config) as sim:
        for j, world_seed in enumerate(world_seeds):
            for d in range(draws):
                set_last_layer(model, torch.from_numpy(layer.draw(seed, int(world_seed), d)))
                episode = run_episode(planner, sim, int(world_seed), sim_config.max_primitives)
                costs[d, j] = not episode.success
                prims[d, j] = episode.n_prims
    return costs, prims


def sampled_costs(
    model: MemoryNet,
    layer: GaussianLayer,
    world_seeds: np.ndarray,
    draws: int,
    sim: SimConfig,
    memory: MemoryConfig,
    seed: int,
    engine: str | None = None,
    workers: int = EvalPlan.workers,
    progress: bool = True,
    desc: str = "sampled policies",
) -> tuple[np.ndarray, np.ndarray]:
    """Costs and primitives ``(draws, len(world_seeds))`` uint8 of weights drawn from ``layer``."""
    world_seeds = np.asarray(world_seeds, np.int64)
    size = ENGINE.worlds_per_task
    chunks = [world_seeds[i : i + size] for i in range(0, len(world_seeds), size)]
    parts = map_tasks(
        _cost_task,
        [(c, int(draws)) for c in chunks],
        engine=engine,
        workers=workers,
        shared=(model, layer, sim, memory, int(seed)),
        desc=desc,
        unit="world",
        sizes=[len(c) for c in chunks],
        progress=progress,
    )
    return np.concatenate([p[0] for p in parts], 1), np.concatenate([p[1] for p in parts], 1)


def _blocks(prefix: Path, seeds: np.ndarray, build: object) -> tuple[np.ndarray, np.ndarray]:
    """Costs over ``seeds`` in stored blocks ``<prefix>_<k>.npz`` of :data:`BLOCK` worlds.

    A missing block is built by ``build(world_seeds, description)``; a stored one must hold exactly
    the world seeds it is read for.
    """
    costs, prims = [], []
    for k, i in enumerate(range(0, len(seeds), BLOCK)):
        path = prefix.parent / f"{prefix.name}_{k:03d}.npz"
        want = seeds[i : i + BLOCK]
        if not path.is_file():
            c, p = build(want, f"{prefix.name} worlds {i}-{i + len(want)}")  # type: ignore[operator]
            atomic_save_npz(path, {"costs": c, "prims": p, "world_seeds": want})
        block = load_npz(path)
        if not np.array_equal(block.get("world_seeds", np.zeros(0)), want):
            raise DatasetError(f"{path} holds other worlds than expected; delete it and rerun")
        costs.append(block["costs"])
        prims.append(block["prims"])
    return np.concatenate(costs, 1), np.concatenate(prims, 1)


def _heldout_prefix(run: Path, profile: Profile) -> Path:
    return run / f"heldout-set{profile.guarantee.heldout_set}" / "block"


def _json_path(run: Path, profile: Profile) -> Path:
    g = profile.guarantee
    return run / f"certificate-set{g.heldout_set}-{g.heldout_worlds}.json"


def _result(
    profile: Profile, run: Path, layer: GaussianLayer, train: tuple, heldout: tuple
) -> CertificateResult:
    g = profile.guarantee
    cert = certificate(train[0], layer.kl(), g.delta, g.delta_prime, draws="per_world")
    h_costs, h_prims = heldout[0][0], heldout[1][0]
    k, n = int(h_costs.sum()), int(h_costs.size)
    unfitted = train[0][0, g.finetune_worlds :]
    k_u, n_u = int(unfitted.sum()), int(unfitted.size)
    return CertificateResult(
        certificate=cert,
        posterior=layer,
        train_costs=train[0],
        train_prims=train[1],
        heldout_costs=h_costs,
        heldout_prims=h_prims,
        heldout_cost=k / n,
        heldout_ci95=clopper_pearson(k, n, 0.95),
        test_bound=clopper_pearson(k, n, cert.confidence, "upper")[1],
        unfitted_costs=unfitted,
        unfitted_bound=clopper_pearson(k_u, n_u, cert.confidence, "upper")[1] if n_u else 1.0,
        path=str(run),
    )


def get_certificate(
    profile: Profile, progress: bool = True, engine: str | None = None, workers: int = EvalPlan.workers
) -> CertificateResult:
    """The certificate, built where missing (needs the trained memory student; see the module docstring)."""
    g = profile.guarantee
    run = certificate_dir(profile)
    if not _json_path(run, profile).is_file():
        announce_build("certificate", profile.name, f"train certificate{world_flag(profile.sim)}")
    model, _, _ = load_memory(profile)
    check_confidence(g.delta, g.delta_prime)  # before any work
    run.mkdir(parents=True, exist_ok=True)
    if not (run / KEY_FILE).is_file():  # its guarantee config, for `clean` (a `certify` scale is kept)
        atomic_write_bytes(run / KEY_FILE, json.dumps(certificate_fingerprint(profile), indent=1).encode())
    post_path = run / "posterior.npz"
    if not post_path.is_file():
        atomic_save_npz(post_path, fit_posterior(model, profile, progress).arrays())
    layer = GaussianLayer.from_arrays(load_npz(post_path))

    def costs_of(draws: int) -> object:
        return lambda chunk, desc: sampled_costs(
            model, layer, chunk, draws, profile.sim, profile.memory, g.seed, engine, workers, progress, desc
        )

    train = _blocks(run / "train", certificate_worlds(profile), costs_of(g.draws_per_world))
    prefix = _heldout_prefix(run, profile)
    prefix.parent.mkdir(exist_ok=True)
    heldout = _blocks(prefix, eval_world_seeds(g.heldout_worlds, g.heldout_set), costs_of(1))
    result = _result(profile, run, layer, train, heldout)
    if not _json_path(run, profile).is_file():
        atomic_write_bytes(_json_path(run, profile), json.dumps(result.to_json(), indent=1).encode())
    return result


def load_certificate(profile: Profile) -> CertificateResult:
    """The built certificate; never builds (the error names the command that does)."""
    g = profile.guarantee
    run = certificate_dir(profile)
    if not _json_path(run, profile).is_file():
        raise CheckpointError(
            f"no certificate for profile {profile.name!r} in the artifact store (expected {run}); build it "
            f"with `python -m husky_course train certificate "
            f"--profile {profile.name}{world_flag(profile.sim)}`"
        )
    layer = GaussianLayer.from_arrays(load_npz(run / "posterior.npz"))

    def missing(*_: object) -> None:
        raise DatasetError(f"{run} is incomplete; delete it and build it again")

    train = _blocks(run / "train", certificate_worlds(profile), missing)
    heldout_seeds = eval_world_seeds(g.heldout_worlds, g.heldout_set)
    heldout = _blocks(_heldout_prefix(run, profile), heldout_seeds, missing)
    return _result(profile, run, layer, train, heldout)
