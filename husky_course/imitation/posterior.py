"""The certificate's stochastic policy: a Gaussian over the memory student's last layer.

Chapter 9 certifies a *distribution* over policies, as the lab's PAC-Bayes planners do. Every
weight of the student is fixed except its output layer (hidden -> one value per primitive), whose
weights and biases ``w`` are drawn at the start of each episode from a diagonal Gaussian.

* **Prior** ``P0 = N(w0, s0^2 I)``: ``w0`` is the output layer DAgger trained on the student's own
  worlds (:mod:`husky_course.imitation.dagger`), ``s0 = prior_scale * rms(w0)``
  (:class:`~husky_course.config.GuaranteeConfig`). Both are fixed before any certificate world is
  seen, which is all the PAC-Bayes bound asks of a prior.
* **Posterior** ``P = N(mu, diag(s^2))``, fitted here on the certificate's training worlds ``S``:
  the student (at ``w0``) drives in the first ``finetune_worlds`` of them, every state it visits is
  labelled with the simulator's survival of each primitive (as in DAgger), and ``(mu, log s)``
  start at the prior and minimise, by Adam with the reparameterisation trick (one weight draw per
  state and step),

      E_{w ~ P}[ BCE(survival predicted with w, label) ] + KL(P || P0) / N,

  a heuristic surrogate of the bound (a training loss one can differentiate in place of the 0/1
  cost, plus the bound's price for moving away from the prior). The bound holds for whatever
  posterior this returns.

Everything is a pure function of the profile and the seeds (one torch thread, seeded generators).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch
import torch.nn.functional as F

from ..config import Profile
from ..data.collect import world_seed_for
from ..data.labels import survival_at
from ..models.memory import MemoryNet, get_last_layer, last_layer
from ..planners.memory import MemoryPlanner
from ..progress import tqdm
from ..training.inference import BATCH, single_thread
from .dagger import episode_steps, rollouts


@dataclass
class GaussianLayer:
    """A diagonal Gaussian over the output layer's flat weights, and the prior it was fitted against.

    Attributes
    ----------
    mean, log_std : ndarray, shape (d,)
        The posterior (``d`` = hidden * primitives + primitives).
    prior_mean : ndarray, shape (d,)
        The prior's centre, the DAgger-trained output layer.
    prior_std : float
        The prior's standard deviation (the same for every weight).
    losses : ndarray, shape (epochs,)
        The fitting objective per epoch (empty for the prior itself).
    """

    mean: np.ndarray
    log_std: np.ndarray
    prior_mean: np.ndarray
    prior_std: float
    losses: np.ndarray

    @property
    def std(self) -> np.ndarray:
        return np.exp(self.log_std)

    def kl(self) -> float:
        """``KL(P || P0)`` in nats (:func:`kl_to_prior` in float64)."""
        arrays = (self.mean, self.log_std, self.prior_mean)
        mu, log_s, mu0 = (torch.from_numpy(np.asarray(a, np.float64)) for a in arrays)
        kl = float(kl_to_prior(mu, log_s, mu0, self.prior_std))
        return max(kl, 0.0)  # >= 0 in exact arithmetic; float32 storage rounds

    def draw(self, seed: int, world_seed: int, draw: int) -> np.ndarray:
        """Weights of draw ``draw`` in world ``world_seed`` (float32, a pure function of the three)."""
        eps = np.random.default_rng([int(seed), int(world_seed), int(draw)]).standard_normal(self.mean.size)
        return (self.mean + self.std * eps).astype(np.float32)

    def arrays(self) -> dict[str, np.ndarray]:
        """What :func:`from_arrays` reads back (for an ``.npz``)."""
        return {
            "mean": self.mean, "log_std": self.log_std, "prior_mean": self.prior_mean,
            "prior_std": np.array(self.prior_std), "losses": self.losses,
        }

    @classmethod
    def from_arrays(cls, a: dict[str, np.ndarray]) -> GaussianLayer:
        return cls(a["mean"], a["log_std"], a["prior_mean"], float(a["prior_std"]), a["losses"])


def kl_to_prior(mu: torch.Tensor, log_s: torch.Tensor, mu0: torch.Tensor, s0: float) -> torch.Tensor:
    """``KL(N(mu, diag exp(log_s)^2) || N(mu0, s0^2 I))``: the closed form for diagonal Gaussians."""
    var_ratio = (torch.exp(2 * log_s) + (mu - mu0) ** 2) / (2 * s0**2)
    return torch.sum(math.log(s0) - log_s + var_ratio - 0.5)


def certificate_worlds(profile: Profile) -> np.ndarray:
    """World seeds ``(N,)`` of the certificate's training worlds (``GuaranteeConfig.collection_seed``).

    Raises ``ValueError`` when that collection seed is one the prior's training (DAgger), the dataset
    or the calibration draws worlds from: the prior must not have seen the certificate's worlds.
    """
    g = profile.guarantee
    taken = {
        "MemoryConfig.collection_seed (the prior's DAgger worlds)": profile.memory.collection_seed,
        "DataConfig.seed (the dataset)": profile.data.seed,
        "CalibrationConfig.seed": profile.calibration.seed,
    }
    for what, seed in taken.items():
        if g.collection_seed == seed:
            raise ValueError(
                f"GuaranteeConfig.collection_seed {seed} is also {what}: the certificate's training worlds "
                "must be worlds the prior never saw; choose a collection seed nothing else uses"
            )
    return np.array([world_seed_for(g.collection_seed, v) for v in range(g.worlds)], np.int64)


def prior(model: MemoryNet, profile: Profile) -> GaussianLayer:
    """The prior ``N(w0, s0^2 I)`` around the student's output layer (see the module docstring)."""
    w0 = get_last_layer(model).numpy()
    s0 = profile.guarantee.prior_scale * float(np.sqrt(np.mean(w0.astype(np.float64) ** 2)))
    return GaussianLayer(w0.copy(), np.full_like(w0, math.log(s0)), w0.copy(), s0, np.zeros(0))


def _features(model: MemoryNet, image: np.ndarray, grid: np.ndarray) -> torch.Tensor:
    out = []
    for i in range(0, len(image), BATCH):
        x = torch.from_numpy(image[i : i + BATCH].astype(np.float32))
        g = torch.from_numpy(grid[i : i + BATCH])
        with torch.no_grad():
            out.append(model.hidden(x, g))
    return torch.cat(out)


def fit_posterior(model: MemoryNet, profile: Profile, progress: bool = True) -> GaussianLayer:
    """Fit the posterior on the first ``finetune_worlds`` certificate worlds (see the module docstring).

    ``model`` is the trained student; its weights are left unchanged (it is put in evaluation mode).
    """
    g, mem = profile.guarantee, profile.memory
    if not 1 <= g.finetune_worlds <= g.worlds:
        raise ValueError(f"finetune_worlds must lie in 1..worlds ({g.worlds}), got {g.finetune_worlds}")
    start = prior(model, profile)
    seeds = certificate_worlds(profile)[: g.finetune_worlds]
    student = MemoryPlanner(model, profile.sim, mem)
    with single_thread():
        data, _ = rollouts(student, seeds, False, profile, progress)
    labels = survival_at(
        data["world_seed"], data["pose"], mem.label_horizon, profile.sim, progress=progress,
        times=episode_steps(data["world_seed"]),
    )
    with single_thread():
        h = _features(model.eval(), data["image"], data["map"])
        target = torch.from_numpy(labels.astype(np.float32) / mem.label_horizon)
        return _optimise(h, target, start, last_layer(model).out_features, profile, progress)


def _optimise(
    h: torch.Tensor, target: torch.Tensor, start: GaussianLayer, n_out: int, profile: Profile, progress: bool
) -> GaussianLayer:
    """Adam on ``E_w[BCE] + KL / N`` from the prior (reparameterised, one draw per state)."""
    g = profile.guarantee
    gen = torch.Generator().manual_seed(g.seed)
    mu = torch.tensor(start.mean, dtype=torch.float32, requires_grad=True)
    log_s = torch.tensor(start.log_std, dtype=torch.float32, requires_grad=True)
    mu0 = torch.tensor(start.prior_mean, dtype=torch.float32)
    s0 = float(start.prior_std)
    opt = torch.optim.Adam([mu, log_s], lr=g.train.lr)
    n_hidden = h.shape[1]
    n_w = n_out * n_hidden
    losses = []
    for _ in tqdm(range(g.train.epochs), desc="posterior", disable=not progress):
        order = torch.randperm(len(h), generator=gen)
        total, count = 0.0, 0
        for i in range(0, len(h), g.train.batch_size):
            rows = order[i : i + g.train.batch_size]
            eps = torch.randn(len(rows), mu.numel(), generator=gen)
            w = mu + torch.exp(log_s) * eps  # (B, d): one weight vector per state
            weight = w[:, :n_w].view(-1, n_out, n_hidden)
            logits = torch.einsum("bh,boh->bo", h[rows], weight) + w[:, n_w:]
            kl = kl_to_prior(mu, log_s, mu0, s0)
            loss = F.binary_cross_entropy_with_logits(logits, target[rows]) + kl / g.worlds
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += float(loss.detach()) * len(rows)
            count += len(rows)
        losses.append(total / count)
    return GaussianLayer(
        mu.detach().numpy().copy(),
        log_s.detach().numpy().copy(),
        start.prior_mean,
        s0,
        np.asarray(losses, np.float64),
    )
