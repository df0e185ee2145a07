"""Models beyond the reward net: the joint model the paper proposed (Fig. 9) and our additions.

* :class:`JointModel` -- encoder, decoder and a safety head trained together; the safety head
  maps the latent to one collision logit per primitive and is trained on the applied one;
* :class:`SafetyNet` -- the encoder trained end to end on safety alone (chapter 4's control);
* :class:`SurvivalNet` -- the oracle distilled: predicted steps survived for every primitive;
* :class:`Probe` -- a small regressor that measures what features hold (chapter 4).
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from ..config import ModelConfig, ModelDims
from .base import DEFAULT_DIMS, ModelSpec, make_spec, mlp
from .paper import Decoder, Encoder


class JointModel(nn.Module):
    """The paper's proposed fix (Fig. 9): encoder, decoder and a safety head trained together.

    The safety head maps the latent to one collision logit per primitive, so a planner gets all
    25 probabilities from one forward pass; training uses the logit of the applied primitive.
    The total loss is reconstruction BCE (on steps that have a next image) plus
    ``safety_weight`` x safety BCE (on every step).
    """

    HIDDEN = (64, 256, 1024, 64, 64)

    def __init__(self, safety_weight: float = 1.0, dims: ModelDims = DEFAULT_DIMS) -> None:
        super().__init__()
        self.spec = make_spec("joint", dims, self.HIDDEN)
        self.safety_weight = float(safety_weight)
        self.encoder = Encoder(dims)
        self.decoder = Decoder(dims, hidden=self.HIDDEN[:3])
        self.safety = mlp([dims.latent, *self.HIDDEN[3:], dims.n_primitives])

    def safety_logits(self, z: Tensor) -> Tensor:
        """Collision logits ``(B, n_primitives)`` for latents ``z``."""
        return self.safety(z)

    def collision_probs(self, image: Tensor) -> Tensor:
        """Probability that each of the 25 primitives collides, ``(B, 25)`` in [0, 1]."""
        return torch.sigmoid(self.safety_logits(self.encoder(image)))

    def forward(self, image: Tensor, prim: Tensor) -> tuple[Tensor, Tensor]:
        z = self.encoder(image)
        return self.decoder(z, prim), torch.sigmoid(self.safety_logits(z))

    def loss(self, batch: dict[str, Tensor]) -> Tensor:
        """Masked reconstruction BCE + weighted safety BCE on the applied primitive."""
        z = self.encoder(batch["image"])
        prim = batch["prim"].long()
        logit = self.safety_logits(z).gather(1, prim.view(-1, 1)).squeeze(1)
        safety = F.binary_cross_entropy_with_logits(logit, batch["label"].float())
        mask = batch["has_next"].bool()
        if bool(mask.any()):
            rec_logits = self.decoder.logits(z[mask], prim[mask])
            recon = F.binary_cross_entropy_with_logits(rec_logits, batch["next"][mask].float())
        else:
            recon = z.sum() * 0.0
        return recon + self.safety_weight * safety


class SafetyNet(nn.Module):
    """A CNN trained end to end on safety alone (no decoder): the paper's encoder + a safety head.

    With ``with_primitive`` it outputs 25 logits and is trained on the applied primitive's (as
    the joint model); without, one logit for "the next primitive, whichever it is, collides".
    Chapter 4 uses the pair to measure how much the label depends on the primitive.
    """

    def __init__(self, with_primitive: bool, dims: ModelDims = DEFAULT_DIMS) -> None:
        super().__init__()
        self.with_primitive = bool(with_primitive)
        out = dims.n_primitives if with_primitive else 1
        kind = "safety_prim" if with_primitive else "safety_image"
        self.spec = make_spec(kind, dims, (64, 64, out))
        self.encoder = Encoder(dims)
        self.head = mlp([dims.latent, 64, 64, out])

    def logit(self, image: Tensor, prim: Tensor | None = None) -> Tensor:
        """Collision logit of each image (for the given primitives when ``with_primitive``)."""
        out = self.head(self.encoder(image))
        if not self.with_primitive:
            return out[:, 0]
        if prim is None:
            raise ValueError("this SafetyNet is conditioned on the primitive: pass prim")
        return out.gather(1, prim.long().view(-1, 1)).squeeze(1)

    def loss(self, batch: dict[str, Tensor]) -> Tensor:
        """BCE on the collision label."""
        return F.binary_cross_entropy_with_logits(
            self.logit(batch["image"], batch["prim"]), batch["label"].float()
        )


class SurvivalNet(nn.Module):
    """The oracle distilled: for each of the 25 primitives, how many of the next ``horizon`` steps
    the best continuation that starts with it stays collision-free (as a fraction, via sigmoid).

    Same encoder as every other model; the labels come from the simulator
    (:func:`husky_course.data.labels.survival_steps_parallel`), not from the random policy's single outcome.
    """

    HIDDEN = (64, 64)

    def __init__(self, horizon: int = ModelConfig().distill_horizon, dims: ModelDims = DEFAULT_DIMS) -> None:
        super().__init__()
        self.spec = make_spec("distilled", dims, self.HIDDEN)
        self.horizon = int(horizon)
        self.encoder = Encoder(dims)
        self.head = mlp([dims.latent, *self.HIDDEN, dims.n_primitives])

    def survival(self, image: Tensor) -> Tensor:
        """Predicted steps survived ``(B, n_primitives)`` in [0, horizon]."""
        return torch.sigmoid(self.head(self.encoder(image))) * self.horizon

    def loss(self, batch: dict[str, Tensor]) -> Tensor:
        """BCE between the predicted and the simulator's survival fraction, over every primitive."""
        target = batch["survival"].float() / self.horizon
        return F.binary_cross_entropy_with_logits(self.head(self.encoder(batch["image"])), target)


class Probe(nn.Module):
    """A small MLP regressor (one hidden layer): how much of a quantity do features hold?"""

    def __init__(self, n_in: int, hidden: int = 64) -> None:
        super().__init__()
        self.spec = ModelSpec("probe", hidden=(n_in, hidden))
        self.net = mlp([n_in, hidden, 1])

    def forward(self, x: Tensor) -> Tensor:
        return self.net(x.float().flatten(1))[:, 0]

    def loss(self, batch: dict[str, Tensor]) -> Tensor:
        """Mean squared error."""
        return F.mse_loss(self(batch["x"]), batch["y"].float())
