"""The paper's networks (Section 3.4): encoder, decoder, reward net, and its two pipelines.

The paper fixes the encoder's convolutions, the latent size, the decoder's input (latent + 1)
and output (one value per pixel through a sigmoid) and the reward net's input (the latent) and
output (2 through a softmax). It is silent on the rest; our choices, each written down where it
is made:

* **The primitive is one number.** The decoder's input is the latent plus one value, so the
  primitive enters as a single scalar: its lateral offset scaled to [-1, 1]
  (:func:`~husky_course.models.base.encode_primitive`). Neighbouring primitives get neighbouring
  inputs, which is the geometry the decoder has to learn anyway.
* **One fully connected layer after the convolutions**: Fig. 5 shows the flattened volume
  followed directly by the latent.
* **Hidden widths.** Decoder 64 -> 256 -> 1024 ("growing width"); reward net 32 -> 64 -> 32
  ("widen, then narrow").
* **Logits inside, probabilities outside.** ``forward`` returns what the paper's networks
  output (sigmoid images, softmax pairs); the losses use the pre-activation logits, which is the
  same loss computed without overflow.

Sizes (image side, primitives, latent) come from the config as a
:class:`~husky_course.config.ModelDims`.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from ..config import ModelDims
from .base import DEFAULT_DIMS, check_images, encode_primitive, make_spec, mlp


def _conv_out(size: int, kernel: int, stride: int) -> int:
    return (size - kernel) // stride + 1


class Encoder(nn.Module):
    """Depth image -> BatchNorm -> Conv(1,32,10,s2) -> ELU -> Conv(32,16,8,s2) -> ELU -> FC -> latent."""

    def __init__(self, dims: ModelDims = DEFAULT_DIMS) -> None:
        super().__init__()
        self.size = dims.image_size
        self.features = nn.Sequential(
            nn.BatchNorm2d(1),
            nn.Conv2d(1, 32, kernel_size=10, stride=2),
            nn.ELU(),
            nn.Conv2d(32, 16, kernel_size=8, stride=2),
            nn.ELU(),
            nn.Flatten(),
        )
        side = _conv_out(_conv_out(self.size, 10, 2), 8, 2)  # 50 -> 21 -> 7 at the paper's size
        self.fc = nn.Linear(16 * side * side, dims.latent)

    def forward(self, x: Tensor) -> Tensor:
        return self.unchecked(check_images(x, self.size))

    def unchecked(self, x: Tensor) -> Tensor:
        """The encoder without input checks, for ``(B, 1, size, size)`` float input (experiments only)."""
        if torch.is_grad_enabled() and self.training:  # training: the fused first layers are faster
            return self.fc(self.features[2:](self._norm_conv(x)))
        return self.fc(self.features(x.contiguous(memory_format=torch.channels_last)))  # oneDNN's is faster

    def _norm_conv(self, x: Tensor) -> Tensor:
        """``features[1](features[0](x))``, the BatchNorm and the first convolution, as one product.

        The same function and the same gradients as the two layers; training epochs are about 1.5x
        faster on 2 CPU cores (oneDNN's backward of a 10x10 convolution with one input channel is
        slow; its forward alone is faster than this, so inference runs the layers). The image is
        data, so its normalised version ``xhat`` needs no gradient, and, with ``g, b`` the
        BatchNorm's scale and shift and ``W, c`` the convolution's weights and bias,
        ``conv(g xhat + b) = g conv_W(xhat) + (b sum(W) + c)``: the first term is one matrix product
        of ``xhat``'s 10x10 patches (strided views of it) with ``W``. ``F.batch_norm`` computes
        ``xhat`` and updates the running statistics exactly as the BatchNorm layer does. Checked
        against the layers in ``tests/test_models.py``.
        """
        bn, conv = self.features[0], self.features[1]
        with torch.no_grad():
            xhat = F.batch_norm(
                x, bn.running_mean, bn.running_var, None, None, bn.training, float(bn.momentum), bn.eps
            ).contiguous()
        if bn.training and bn.num_batches_tracked is not None:
            bn.num_batches_tracked.add_(1)
        n, _, h, w = xhat.shape
        k, s = conv.kernel_size[0], conv.stride[0]
        ho, wo, out = _conv_out(h, k, s), _conv_out(w, k, s), conv.out_channels
        patches = xhat.as_strided((n, ho, wo, k, k), (h * w, s * w, s, w, 1)).reshape(n * ho * wo, k * k)
        weight = conv.weight.reshape(out, k * k)
        y = (patches @ weight.t()) * bn.weight + (bn.bias * weight.sum(1) + conv.bias)
        return y.view(n, ho, wo, out).permute(0, 3, 1, 2)  # channels-last memory, as oneDNN likes it


class Decoder(nn.Module):
    """concat(latent, primitive) -> 64 -> 256 -> 1024 -> one value per pixel -> Sigmoid -> image."""

    def __init__(self, dims: ModelDims = DEFAULT_DIMS, hidden: tuple[int, ...] = (64, 256, 1024)) -> None:
        super().__init__()
        self.size, self.n_primitives = dims.image_size, dims.n_primitives
        self.net = mlp([dims.latent + 1, *hidden, self.size * self.size])

    def logits(self, z: Tensor, prim: Tensor) -> Tensor:
        """Pre-sigmoid image ``(B, size, size)`` for latents ``z`` and primitive indices ``prim``."""
        out = self.net(torch.cat([z, encode_primitive(prim, self.n_primitives).to(z)], dim=1))
        return out.view(-1, self.size, self.size)

    def forward(self, z: Tensor, prim: Tensor) -> Tensor:
        return torch.sigmoid(self.logits(z, prim))


class RewardNet(nn.Module):
    """latent -> 32 -> 64 -> 32 -> 2 -> Softmax = [p, 1 - p], p the probability of collision."""

    def __init__(self, dims: ModelDims = DEFAULT_DIMS, hidden: tuple[int, ...] = (32, 64, 32)) -> None:
        super().__init__()
        self.net = mlp([dims.latent, *hidden, 2])

    def logits(self, z: Tensor) -> Tensor:
        """The two pre-softmax scores."""
        return self.net(z)

    def forward(self, z: Tensor) -> Tensor:
        return torch.softmax(self.logits(z), dim=1)


class EncoderDecoder(nn.Module):
    """The first pipeline (Fig. 3): image t and primitive -> image t+1."""

    HIDDEN = (64, 256, 1024)

    def __init__(self, dims: ModelDims = DEFAULT_DIMS) -> None:
        super().__init__()
        self.spec = make_spec("encoder_decoder", dims, self.HIDDEN)
        self.encoder = Encoder(dims)
        self.decoder = Decoder(dims, hidden=self.HIDDEN)

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

    HIDDEN = (32, 64, 32)

    def __init__(self, dims: ModelDims = DEFAULT_DIMS) -> None:
        super().__init__()
        self.spec = make_spec("reward_net", dims, self.HIDDEN)
        self.reward = RewardNet(dims, hidden=self.HIDDEN)

    def forward(self, z: Tensor) -> Tensor:
        return self.reward(z)

    def collision_logit(self, z: Tensor) -> Tensor:
        """``log p - log(1 - p)``: a single score, higher = more likely to collide."""
        s = self.reward.logits(z)
        return s[:, 0] - s[:, 1]

    def loss(self, batch: dict[str, Tensor]) -> Tensor:
        """BCE of ``[p, 1 - p]`` against ``[label, 1 - label]`` (equal to BCE on ``p``)."""
        return F.binary_cross_entropy_with_logits(self.collision_logit(batch["z"]), batch["label"].float())
