"""The RNN look-ahead the paper proposed (Fig. 10): predict several steps ahead from one image.

Architecture (the paper draws the idea, not the layers; our choices):

* the paper's :class:`~husky_course.models.Encoder` turns the current image into the latent ``z``;
* ``h_0 = tanh(W z)``, a 64-wide hidden state;
* every primitive of a sequence enters as a learned 16-number embedding, and a ``GRUCell``
  updates ``h_{k+1} = GRU(embed(a_k), h_k)``;
* from every ``h_{k+1}`` two heads predict the depth image after step ``k`` (64 -> 256 -> 2500,
  sigmoid) and whether step ``k`` collides (64 -> 64 -> 1, sigmoid).

Training data (:func:`husky_course.training.datasets.sequence_data`): every image of a training
video starts a sequence of the primitives that followed it (up to ``ModelConfig.rnn_horizon``
steps, up to the collision), so every prefix of every video is used. The colliding step supervises
the collision head; images are supervised only where a next image exists. Unlike iterating
decoder -> encoder (Algorithm 1), the RNN never has to re-read its own blurry predictions.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from ..config import ModelDims
from .base import DEFAULT_DIMS, make_spec, mlp
from .paper import Encoder


class RNNLookahead(nn.Module):
    """Encoder + GRU rolled over primitives, with image and collision heads at every step."""

    HIDDEN = (64, 16, 256)  #: GRU width, primitive embedding, image head width

    def __init__(self, dims: ModelDims = DEFAULT_DIMS) -> None:
        super().__init__()
        hidden, embed, image_hidden = self.HIDDEN
        self.spec = make_spec("rnn", dims, self.HIDDEN)
        self.size = dims.image_size
        self.encoder = Encoder(dims)
        self.init = nn.Linear(dims.latent, hidden)
        self.embed = nn.Embedding(dims.n_primitives, embed)
        self.cell = nn.GRUCell(embed, hidden)
        self.image_head = mlp([hidden, image_hidden, self.size * self.size])
        self.collide_head = mlp([hidden, 64, 1])
        self.bank: Tensor | None = None  #: the image pool that batches index into (set by training)

    def start(self, image: Tensor) -> Tensor:
        """Initial hidden state ``(B, hidden)`` from images."""
        return torch.tanh(self.init(self.encoder(image)))

    def rollout(self, h: Tensor, prims: Tensor, images: bool = True) -> tuple[Tensor | None, Tensor]:
        """Roll ``h`` over primitive sequences ``(B, K)``.

        Returns image logits ``(B, K, size, size)`` (``None`` if ``images`` is false) and collision
        logits ``(B, K)``; entry ``k`` is about the step that applies ``prims[:, k]``.
        """
        emb = self.embed(prims.long())
        img, col = [], []
        for k in range(prims.shape[1]):
            h = self.cell(emb[:, k], h)
            col.append(self.collide_head(h)[:, 0])
            if images:
                img.append(self.image_head(h).view(-1, self.size, self.size))
        return (torch.stack(img, 1) if images else None), torch.stack(col, 1)

    def loss(self, batch: dict[str, Tensor]) -> Tensor:
        """Masked image BCE over predicted steps + masked collision BCE over every step."""
        if self.bank is None:
            raise RuntimeError("set model.bank to the image pool before training")
        image = self.bank[batch["image_idx"]]
        img_logits, col_logits = self.rollout(self.start(image), batch["prims"])
        lm, nm = batch["label_mask"].bool(), batch["next_mask"].bool()
        collide = F.binary_cross_entropy_with_logits(col_logits[lm], batch["labels"][lm].float())
        assert img_logits is not None
        target = self.bank[batch["next_idx"][nm]].float()
        recon = F.binary_cross_entropy_with_logits(img_logits[nm], target) if bool(nm.any()) else collide * 0
        return recon + collide
