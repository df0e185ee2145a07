"""The learned planners: Algorithm 1 on the joint model, and the RNN look-ahead.

:class:`LookaheadPlanner` is the paper's Algorithm 1 (Section 3.5) as printed::

    z = Encoder(I_t); scores = 0; weight = 1
    for i = 0 .. look_ahead:
        for prim in library:                       # batched: all primitives in one call
            I' = Decoder(z, prim); z_list[prim] = Encoder(I')
            scores[prim] += weight * Reward(...)
        z = z_list[argmin(scores)]; weight /= 2
    apply argmin(scores)

The paper's reward net gave one probability per *image*; our joint model gives one per image and
*primitive*, so ``Reward`` needs a reading. Two are offered (``reward=``):

* ``"applied"`` (default): the probability that ``prim`` collides from ``z``, which is what the
  reward net's label meant (the label of image ``t`` is the fate of the primitive applied at ``t``);
* ``"next_image"``: the line as printed, ``Reward(z_list[prim])``, where the image-only reward net
  is the mean over the 25 primitives of the predicted image's collision probabilities (the chance
  that a random next primitive collides, which is what the paper's reward net estimated).

:class:`RNNPlanner` scores whole primitive sequences with the RNN look-ahead: every sequence of
length ``depth`` when ``depth <= 2``, otherwise ``samples`` random sequences (random shooting) plus
the 25 constant ones. A sequence's risk is the probability that any of its steps collides,
``1 - prod(1 - p_k)``; the planner applies the first primitive of the least risky sequence.

:class:`DistilledPlanner` goes beyond the paper: the same encoder, trained on what the simulator
says about *every* primitive (how many steps its best continuation survives), not on the one
primitive the random policy happened to apply.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from ..config import EvalPlan, Profile, check_profile, world_kind
from ..models.rnn import RNNLookahead
from ..models.safety import JointModel, SurvivalNet
from ..training import builders
from ..training.cuts import load_cuts
from ..training.discs import load_discs
from ..training.inference import model_device, single_thread
from ..training.memory import load_memory
from ..training.trainer import CheckpointError
from .base import Planner, PlannerError, check_look_ahead, check_observation, survival_scores
from .cuts import PieceCutter

REWARDS = ("applied", "next_image")


def _image(obs: np.ndarray, size: int, device: torch.device | None = None) -> torch.Tensor:
    return torch.from_numpy(check_observation(obs, size))[None].to(device or "cpu")


def to_device(planner: Planner, device: torch.device | str) -> Planner:
    """Move a learned planner's network to ``device`` (``evaluate --device``); others are unchanged."""
    model = getattr(planner, "model", None)
    if isinstance(model, torch.nn.Module):
        model.to(device)
    return planner


def _n_primitives(model: torch.nn.Module) -> int:
    return int(model.spec.n_primitives)  # type: ignore[union-attr]


@torch.no_grad()
def algorithm1(model: JointModel, obs: np.ndarray, look_ahead: int, reward: str = "applied") -> np.ndarray:
    """Algorithm 1's final ``prim_scores`` (lower is better), batched over the 25 primitives."""
    model.eval()
    n, dev = _n_primitives(model), model_device(model)
    prims = torch.arange(n, device=dev)
    z = model.encoder.unchecked(_image(obs, model.encoder.size, dev)[:, None])  # _image has validated it
    scores = torch.zeros(n, device=dev)
    weight = 1.0
    for i in range(look_ahead + 1):
        if reward == "applied":
            scores += weight * torch.sigmoid(model.safety_logits(z))[0]
            if i == look_ahead:
                break  # the latent after the last step would never be scored
            best = int(torch.argmin(scores))
            z = model.encoder.unchecked(model.decoder(z, prims[best : best + 1])[:, None])
        else:
            z_list = model.encoder.unchecked(model.decoder(z.expand(n, -1), prims)[:, None])
            scores += weight * torch.sigmoid(model.safety_logits(z_list)).mean(1)
            best = int(torch.argmin(scores))
            z = z_list[best : best + 1]
        weight /= 2.0
    return scores.cpu().numpy()


@torch.no_grad()
def algorithm1_reference(
    model: JointModel, obs: np.ndarray, look_ahead: int, reward: str = "applied"
) -> np.ndarray:
    """Algorithm 1 line by line, one primitive at a time (slow; the tests compare against it)."""
    model.eval()
    n = _n_primitives(model)
    z = model.encoder(_image(obs, model.encoder.size))
    scores = [0.0] * n
    weight = 1.0
    for _ in range(look_ahead + 1):
        z_list = {}
        for prim in range(n):
            a = torch.tensor([prim])
            z_list[prim] = model.encoder(model.decoder(z, a))
            if reward == "applied":
                r = float(torch.sigmoid(model.safety_logits(z))[0, prim])
            else:
                r = float(torch.sigmoid(model.safety_logits(z_list[prim])).mean())
            scores[prim] += weight * r
        prim_min = int(np.argmin(scores))
        z = z_list[prim_min]
        weight /= 2.0
    return np.array(scores, np.float32)


class LookaheadPlanner(Planner):
    """Algorithm 1 on the joint model (see the module docstring)."""

    name = "lookahead"

    def __init__(
        self, model: JointModel, look_ahead: int = EvalPlan.look_ahead, reward: str = "applied"
    ) -> None:
        super().__init__()
        if reward not in REWARDS:
            raise PlannerError(f"unknown reward reading {reward!r}: choose one of {', '.join(REWARDS)}")
        self.model = model.eval()
        self.look_ahead = check_look_ahead(look_ahead)
        self.reward = reward

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        with single_thread():
            self.last_scores = algorithm1(self.model, obs, self.look_ahead, self.reward)
        return int(np.argmin(self.last_scores))


class RNNPlanner(Planner):
    """Random shooting with the RNN look-ahead (see the module docstring)."""

    name = "rnn"

    def __init__(self, model: RNNLookahead, look_ahead: int = EvalPlan.look_ahead, samples: int = 1000,
                 seed: int = 0) -> None:
        super().__init__()
        self.model = model.eval()
        self.depth = check_look_ahead(look_ahead) + 1  # look_ahead 0 = judge the next step only
        if samples < 1:
            raise PlannerError(f"samples must be >= 1, got {samples}")
        n = self.n = _n_primitives(model)
        if self.depth <= 2:
            grid = np.stack(np.meshgrid(*[np.arange(n)] * self.depth, indexing="ij"), -1).reshape(
                -1, self.depth
            )
        else:
            rng = np.random.default_rng(seed)
            grid = np.concatenate(
                [np.repeat(np.arange(n)[:, None], self.depth, 1), rng.integers(0, n, (samples, self.depth))]
            )
        self.sequences = torch.from_numpy(grid.astype(np.int64))

    @torch.no_grad()
    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        with single_thread():
            return self._act(obs)

    def _act(self, obs: np.ndarray) -> int:
        dev = model_device(self.model)
        sequences = self.sequences.to(dev)  # no copy on the CPU
        h = self.model.start(_image(obs, self.model.size, dev))
        _, col = self.model.rollout(h.expand(len(sequences), -1), sequences, images=False)
        risk = (1.0 - torch.prod(1.0 - torch.sigmoid(col), dim=1)).cpu()
        first = self.sequences[:, 0]
        scores = torch.full((self.n,), float("inf"))
        scores = scores.scatter_reduce(0, first, risk, reduce="amin")
        self.last_scores = scores.numpy()
        return int(torch.argmin(scores))


class DistilledPlanner(Planner):
    """The oracle distilled into a network: pick the primitive predicted to survive longest.

    Ties (several primitives predicted to survive the whole horizon) go to the one whose
    neighbours in the library are also predicted safe: the middle of the widest free corridor.
    """

    name = "distilled"

    def __init__(self, model: SurvivalNet, smooth: int = 2) -> None:
        super().__init__()
        self.model = model.eval()
        self.smooth = int(smooth)

    @torch.no_grad()
    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        with single_thread():
            image = _image(obs, self.model.encoder.size, model_device(self.model))
            s = self.model.survival(image)[0].cpu().numpy()
        self.last_scores = survival_scores(s, self.smooth)
        return int(np.argmin(self.last_scores))


#: learned planner -> the model it runs on
MODEL_OF = {
    "lookahead": "joint", "rnn": "rnn", "distilled": "distilled", "memory": "memory", "discs": "discs",
}


def disc_cutter(profile: Profile, moving: bool, threshold: float | None = None) -> PieceCutter | None:
    """The disc planner's cut network at ``threshold`` (default: the profile's on the ``moving`` course,
    ``profile.discs.cut``, and none on the static one; 0: none), loaded (never trained: ``python -m
    husky_course train cuts`` trains it after the disc network,
    :func:`husky_course.imitation.cuts.get_cuts`)."""
    if threshold is None:
        threshold = profile.discs.cut if moving else 0.0
    return PieceCutter(load_cuts(profile)[0], float(threshold)) if threshold > 0 else None


def make_learned_planner(
    name: str, profile: Profile, look_ahead: int | None = None, train: bool = False, **kwargs: Any
) -> Planner:
    """Build a learned planner from the profile's checkpoints.

    With ``train=False`` (the CLI's default) nothing is built: a missing checkpoint is an error
    naming the command that trains it. ``train=True`` builds what is missing (with progress bars),
    except the memory student, which DAgger trains (:func:`husky_course.imitation.dagger.get_memory`),
    and the disc network (:func:`husky_course.imitation.discs.get_discs`). ``look_ahead`` defaults to
    the profile's (``profile.eval.look_ahead``).
    """
    profile = check_profile(profile)
    look_ahead = check_look_ahead(profile.eval.look_ahead if look_ahead is None else look_ahead)
    if name not in MODEL_OF:
        raise PlannerError(f"{name!r} is not a learned planner: choose one of {', '.join(MODEL_OF)}")
    try:
        if name == "memory":  # trained by DAgger, above the planners: here it is only loaded
            from .memory import MemoryPlanner

            return MemoryPlanner(load_memory(profile)[0], profile.sim, profile.memory, **kwargs)
        if name == "discs":  # trained on simulated views read by the planner's perception: only loaded here
            from .discs import DiscPlanner
            from .moving_discs import DiscTrackingPlanner

            d = profile.discs
            config = kwargs.pop("config", profile.sim)  # the course it runs on: discs walk on the moving one
            settings = {"grow": d.grow, "margin": d.margin, "unexplained": d.unexplained, **kwargs}
            moving = world_kind(config) == "moving"
            cls = DiscTrackingPlanner if moving else DiscPlanner
            discs = load_discs(profile)[0]  # named first when missing: the cut network reads with it
            cutter = disc_cutter(profile, moving, settings.pop("cut", None))
            return cls(discs, config, cutter=cutter, **settings)
        if train:
            model = builders.BUILDERS[MODEL_OF[name]](profile, True).model
        else:
            model = builders.load(MODEL_OF[name], profile).model
        if name == "lookahead":
            return LookaheadPlanner(model, look_ahead, **kwargs)  # type: ignore[arg-type]
        if name == "rnn":
            return RNNPlanner(model, look_ahead, **kwargs)  # type: ignore[arg-type]
        return DistilledPlanner(model, **kwargs)  # type: ignore[arg-type]
    except CheckpointError as exc:
        raise PlannerError(f"planner {name!r} cannot be built: {exc}") from exc
    except TypeError as exc:
        raise PlannerError(f"bad arguments for planner {name!r}: {exc}") from exc
