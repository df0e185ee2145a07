"""The paper's networks (Section 3.4) and the joint model it proposed (Fig. 9).

The paper fixes the encoder's convolutions, the latent size (15), the decoder's input size (16)
and output (2,500 through a sigmoid) and the reward net's input (15) and output (2 through a
softmax). It is silent on the rest; our choices, each written down where it is made:

* **The primitive is one number.** The decoder's input of 16 = 15 latent values + 1, so the
  primitive enters as a single scalar: its lateral offset scaled to [-1, 1]
  (:func:`encode_primitive`). Neighbouring primitives get neighbouring inputs, which is the
  geometry the decoder has to learn anyway.
* **One fully connected layer after the convolutions** (784 -> 15): Fig. 5 shows the flattened
  volume followed directly by the latent.
* **Hidden widths.** Decoder 16 -> 64 -> 256 -> 1024 -> 2500 ("growing width"); reward net
  15 -> 32 -> 64 -> 32 -> 2 ("widen, then narrow").
* **Logits inside, probabilities outside.** ``forward`` returns what the paper's networks
  output (sigmoid images, softmax pairs); the losses use the pre-activation logits, which is the
  same loss computed without overflow.

The joint model adds a *safety head* conditioned on the primitive: it maps the latent to 25
collision logits, one per primitive, and is trained on the one that was applied.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import torch
import torch.nn.functional as F
from torch import Tensor, nn

IMAGE_SIZE = 50
N_PRIMITIVES = 25
LATENT = 15


def encode_primitive(index: Tensor, n_primitives: int = N_PRIMITIVES) -> Tensor:
    """The decoder's one-number primitive input: index scaled to [-1, 1], shape ``(B, 1)``.

    Primitive ``k`` has lateral offset proportional to ``k - (n - 1) / 2``, so this is the offset
    divided by the library's spread.
    """
    index = torch.as_tensor(index)
    if index.dtype.is_floating_point:
        raise TypeError(f"primitive indices must be integers, got dtype {index.dtype}")
    if index.numel() and (int(index.min()) < 0 or int(index.max()) >= n_primitives):
        raise ValueError(f"primitive indices must be in 0..{n_primitives - 1}")
    return (2.0 * index.float() / (n_primitives - 1) - 1.0).reshape(-1, 1)


def check_images(x: Tensor) -> Tensor:
    """Return ``x`` as ``(B, 1, 50, 50)`` float32, or raise ``ValueError`` naming the problem."""
    if not isinstance(x, Tensor):
        raise TypeError(f"expected a torch.Tensor of depth images, got {type(x).__name__}")
    if x.dim() == 3:
        x = x.unsqueeze(1)
    if x.dim() != 4 or tuple(x.shape[1:]) != (1, IMAGE_SIZE, IMAGE_SIZE):
        raise ValueError(f"depth images must have shape (B, 50, 50) or (B, 1, 50, 50), got {tuple(x.shape)}")
    if not x.dtype.is_floating_point:
        raise ValueError(f"depth images must be floating point in [0, 1], got dtype {x.dtype}")
    if x.numel():
        lo_t, hi_t = torch.aminmax(x)  # one pass; NaN propagates into both
        lo, hi = float(lo_t), float(hi_t)
        if not (lo >= 0.0 and hi <= 1.0):
            if not bool(torch.isfinite(x).all()):
                raise ValueError("depth images contain NaN or inf values")
            raise ValueError(f"depth images must be normalised to [0, 1], got values in [{lo:.3g}, {hi:.3g}]")
    return x.float()


@dataclass(frozen=True)
class ModelSpec:
    """What identifies an architecture: checkpoints record it and refuse a mismatch."""

    kind: str
    latent: int = LATENT
    n_primitives: int = N_PRIMITIVES
    hidden: tuple[int, ...] = ()

    def to_dict(self) -> dict:
        """JSON-ready form (stored inside checkpoints)."""
        data = asdict(self)
        data["hidden"] = list(self.hidden)
        return data


def _mlp(widths: list[int]) -> nn.Sequential:
    """Linear layers with ELU between them (none after the last)."""
    layers: list[nn.Module] = []
    for i, (a, b) in enumerate(zip(widths[:-1], widths[1:], strict=True)):
        layers.append(nn.Linear(a, b))
        if i < len(widths) - 2:
            layers.append(nn.ELU())
    return nn.Sequential(*layers)


class Encoder(nn.Module):
    """1x50x50 depth -> BatchNorm -> Conv(1,32,10,s2) -> ELU -> Conv(32,16,8,s2) -> ELU -> FC -> 15."""

    def __init__(self, latent: int = LATENT) -> None:
        super().__init__()
        self.features = nn.Sequential(
            nn.BatchNorm2d(1),
            nn.Conv2d(1, 32, kernel_size=10, stride=2),  # 50 -> 21
            nn.ELU(),
            nn.Conv2d(32, 16, kernel_size=8, stride=2),  # 21 -> 7
            nn.ELU(),
            nn.Flatten(),
        )
        self.fc = nn.Linear(16 * 7 * 7, latent)

    def forward(self, x: Tensor) -> Tensor:
        return self.unchecked(check_images(x))

    def unchecked(self, x: Tensor) -> Tensor:
        """The encoder without input checks, for ``(B, 1, 50, 50)`` float input (experiments only)."""
        return self.fc(self.features(x.contiguous(memory_format=torch.channels_last)))


class Decoder(nn.Module):
    """concat(latent, primitive) (16) -> 64 -> 256 -> 1024 -> 2500 -> Sigmoid -> 50x50."""

    def __init__(self, latent: int = LATENT, hidden: tuple[int, ...] = (64, 256, 1024)) -> None:
        super().__init__()
        self.net = _mlp([latent + 1, *hidden, IMAGE_SIZE * IMAGE_SIZE])

    def logits(self, z: Tensor, prim: Tensor) -> Tensor:
        """Pre-sigmoid image ``(B, 50, 50)`` for latents ``z`` and primitive indices ``prim``."""
        out = self.net(torch.cat([z, encode_primitive(prim).to(z)], dim=1))
        return out.view(-1, IMAGE_SIZE, IMAGE_SIZE)

    def forward(self, z: Tensor, prim: Tensor) -> Tensor:
        return torch.sigmoid(self.logits(z, prim))


class RewardNet(nn.Module):
    """latent (15) -> 32 -> 64 -> 32 -> 2 -> Softmax = [p, 1 - p], p the probability of collision."""

    def __init__(self, latent: int = LATENT, hidden: tuple[int, ...] = (32, 64, 32)) -> None:
        super().__init__()
        self.net = _mlp([latent, *hidden, 2])

    def logits(self, z: Tensor) -> Tensor:
        """The two pre-softmax scores."""
        return self.net(z)

    def forward(self, z: Tensor) -> Tensor:
        return torch.softmax(self.logits(z), dim=1)


class EncoderDecoder(nn.Module):
    """The first pipeline (Fig. 3): image t and primitive -> image t+1."""

    spec = ModelSpec("encoder_decoder", hidden=(64, 256, 1024))

    def __init__(self) -> None:
        super().__init__()
        self.encoder = Encoder()
        self.decoder = Decoder(hidden=self.spec.hidden)

    def forward(self, image: Tensor, prim: Tensor) -> Tensor:
        return self.decoder(self.encoder(image), prim)

    def loss(self, batch: dict[str, Tensor]) -> Tensor:
        """Mean per-pixel BCE between the predicted and the true next image."""
        logits = self.decoder.logits(self.encoder(batch["image"]), batch["prim"])
        return F.binary_cross_entropy_with_logits(logits, batch["next"].float())


class LatentRewardNet(nn.Module):
    """The second pipeline (Fig. 4): a reward net on latents of a frozen encoder.

    Its ``loss`` reproduces the paper's target convention: the label ``[1, 0]`` for a collision
    and ``[0, 1]`` otherwise, compared with the softmax output by BCE.
    """

    spec = ModelSpec("reward_net", hidden=(32, 64, 32))

    def __init__(self) -> None:
        super().__init__()
        self.reward = RewardNet(hidden=self.spec.hidden)

    def forward(self, z: Tensor) -> Tensor:
        return self.reward(z)

    def collision_logit(self, z: Tensor) -> Tensor:
        """``log p - log(1 - p)``: a single score, higher = more likely to collide."""
        s = self.reward.logits(z)
        return s[:, 0] - s[:, 1]

    def loss(self, batch: dict[str, Tensor]) -> Tensor:
        """BCE of ``[p, 1 - p]`` against ``[label, 1 - label]`` (equal to BCE on ``p``)."""
        return F.binary_cross_entropy_with_logits(self.collision_logit(batch["z"]), batch["label"].float())


class JointModel(nn.Module):
    """The paper's proposed fix (Fig. 9): encoder, decoder and a safety head trained together.

    The safety head maps the latent to one collision logit per primitive, so a planner gets all
    25 probabilities from one forward pass; training uses the logit of the applied primitive.
    The total loss is reconstruction BCE (on steps that have a next image) plus
    ``safety_weight`` x safety BCE (on every step).
    """

    spec = ModelSpec("joint", hidden=(64, 256, 1024, 64, 64))

    def __init__(self, safety_weight: float = 1.0) -> None:
        super().__init__()
        self.safety_weight = float(safety_weight)
        self.encoder = Encoder()
        self.decoder = Decoder(hidden=self.spec.hidden[:3])
        self.safety = _mlp([LATENT, *self.spec.hidden[3:], N_PRIMITIVES])

    def safety_logits(self, z: Tensor) -> Tensor:
        """Collision logits ``(B, 25)`` for latents ``z``."""
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

    def __init__(self, with_primitive: bool) -> None:
        super().__init__()
        self.with_primitive = bool(with_primitive)
        out = N_PRIMITIVES if with_primitive else 1
        self.spec = ModelSpec("safety_prim" if with_primitive else "safety_image", hidden=(64, 64, out))
        self.encoder = Encoder()
        self.head = _mlp([LATENT, 64, 64, out])

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
    (:func:`husky_course.labels.survival_steps`), not from the random policy's single outcome.
    """

    spec = ModelSpec("distilled", hidden=(64, 64))

    def __init__(self, horizon: int = 3) -> None:
        super().__init__()
        self.horizon = int(horizon)
        self.encoder = Encoder()
        self.head = _mlp([LATENT, *self.spec.hidden, N_PRIMITIVES])

    def survival(self, image: Tensor) -> Tensor:
        """Predicted steps survived ``(B, 25)`` in [0, horizon]."""
        return torch.sigmoid(self.head(self.encoder(image))) * self.horizon

    def loss(self, batch: dict[str, Tensor]) -> Tensor:
        """BCE between the predicted and the simulator's survival fraction, over all 25 primitives."""
        target = batch["survival"].float() / self.horizon
        return F.binary_cross_entropy_with_logits(self.head(self.encoder(batch["image"])), target)


class Probe(nn.Module):
    """A small MLP regressor (one hidden layer): how much of a quantity do features hold?"""

    def __init__(self, n_in: int, hidden: int = 64) -> None:
        super().__init__()
        self.spec = ModelSpec("probe", hidden=(n_in, hidden))
        self.net = _mlp([n_in, hidden, 1])

    def forward(self, x: Tensor) -> Tensor:
        return self.net(x.float().flatten(1))[:, 0]

    def loss(self, batch: dict[str, Tensor]) -> Tensor:
        """Mean squared error."""
        return F.mse_loss(self(batch["x"]), batch["y"].float())


def count_parameters(module: nn.Module) -> int:
    """Number of trainable parameters."""
    return sum(p.numel() for p in module.parameters() if p.requires_grad)
