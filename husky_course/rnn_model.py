"""The RNN look-ahead the paper proposed (Fig. 10): predict several steps ahead from one image.

Architecture (the paper draws the idea, not the layers; our choices):

* the paper's :class:`~husky_course.models.Encoder` turns the current image into the latent ``z``;
* ``h_0 = tanh(W z)``, a 64-wide hidden state;
* every primitive of a sequence enters as a learned 16-number embedding, and a ``GRUCell``
  updates ``h_{k+1} = GRU(embed(a_k), h_k)``;
* from every ``h_{k+1}`` two heads predict the depth image after step ``k`` (64 -> 256 -> 2500,
  sigmoid) and whether step ``k`` collides (64 -> 64 -> 1, sigmoid).

Training data: every image of a training video starts a sequence of the primitives that followed
it (up to :data:`HORIZON` steps, up to the collision), so every prefix of every video is used. The
colliding step supervises the collision head; images are supervised only where a next image
exists. Unlike iterating decoder -> encoder (Algorithm 1), the RNN never has to re-read its own
blurry predictions.
"""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F
from torch import Tensor, nn

from .dataset import Dataset
from .metrics import roc_auc
from .models import IMAGE_SIZE, LATENT, N_PRIMITIVES, Encoder, JointModel, ModelSpec, _mlp

HORIZON = 5


class RNNLookahead(nn.Module):
    """Encoder + GRU rolled over primitives, with image and collision heads at every step."""

    spec = ModelSpec("rnn", hidden=(64, 16, 256))

    def __init__(self, hidden: int = 64, embed: int = 16) -> None:
        super().__init__()
        self.encoder = Encoder()
        self.init = nn.Linear(LATENT, hidden)
        self.embed = nn.Embedding(N_PRIMITIVES, embed)
        self.cell = nn.GRUCell(embed, hidden)
        self.image_head = _mlp([hidden, 256, IMAGE_SIZE * IMAGE_SIZE])
        self.collide_head = _mlp([hidden, 64, 1])
        self.bank: Tensor | None = None  #: the image pool that batches index into (set by training)

    def start(self, image: Tensor) -> Tensor:
        """Initial hidden state ``(B, hidden)`` from images."""
        return torch.tanh(self.init(self.encoder(image)))

    def rollout(self, h: Tensor, prims: Tensor, images: bool = True) -> tuple[Tensor | None, Tensor]:
        """Roll ``h`` over primitive sequences ``(B, K)``.

        Returns image logits ``(B, K, 50, 50)`` (``None`` if ``images`` is false) and collision
        logits ``(B, K)``; entry ``k`` is about the step that applies ``prims[:, k]``.
        """
        emb = self.embed(prims.long())
        img, col = [], []
        for k in range(prims.shape[1]):
            h = self.cell(emb[:, k], h)
            col.append(self.collide_head(h)[:, 0])
            if images:
                img.append(self.image_head(h).view(-1, IMAGE_SIZE, IMAGE_SIZE))
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


def sequence_data(ds: Dataset, idx: np.ndarray, horizon: int = HORIZON) -> dict[str, Tensor]:
    """Sequences starting at pool indices ``idx``: the next ``horizon`` primitives, labels and images.

    ``label_mask[k]`` says step ``k`` happened (same video); ``next_mask[k]`` says it was safe and
    its resulting image is stored (``next_idx``).
    """
    idx = np.asarray(idx, np.int64)
    n = len(ds)
    steps = idx[:, None] + np.arange(horizon)[None]
    inside = steps < n
    s = np.minimum(steps, n - 1)
    label_mask = inside & (ds.episode[s] == ds.episode[idx][:, None])
    nxt = np.minimum(s + 1, n - 1)
    next_mask = label_mask & (ds.labels[s] == 0) & (s + 1 < n) & (ds.episode[nxt] == ds.episode[idx][:, None])
    return {
        "image_idx": torch.from_numpy(idx),
        "prims": torch.from_numpy(np.where(label_mask, ds.applied[s], 0).astype(np.int64)),
        "labels": torch.from_numpy(np.where(label_mask, ds.labels[s], 0).astype(np.float32)),
        "label_mask": torch.from_numpy(label_mask),
        "next_idx": torch.from_numpy(np.where(next_mask, nxt, 0)),
        "next_mask": torch.from_numpy(next_mask),
    }


@torch.no_grad()
def rnn_predictions(model: RNNLookahead, images: Tensor, prims: Tensor) -> tuple[np.ndarray, np.ndarray]:
    """Predicted images ``(B, K, 50, 50)`` and collision probabilities ``(B, K)`` along sequences."""
    model.eval()
    img, col = model.rollout(model.start(images.float()), prims)
    assert img is not None
    return torch.sigmoid(img).numpy(), torch.sigmoid(col).numpy()


@torch.no_grad()
def loop_predictions(model: JointModel, images: Tensor, prims: Tensor) -> tuple[np.ndarray, np.ndarray]:
    """The same predictions made the way Algorithm 1 does: decode, re-encode, repeat.

    The collision probability of step ``k`` is the joint model's safety head for ``prims[:, k]``
    on the latent reached after ``k`` decode/encode rounds.
    """
    model.eval()
    z = model.encoder(images.float())
    imgs, cols = [], []
    for k in range(prims.shape[1]):
        a = prims[:, k]
        cols.append(torch.sigmoid(model.safety_logits(z)).gather(1, a.view(-1, 1))[:, 0])
        img = model.decoder(z, a)
        imgs.append(img)
        z = model.encoder(img)
    return torch.stack(imgs, 1).numpy(), torch.stack(cols, 1).numpy()


def horizon_errors(
    predict, ds: Dataset, idx: np.ndarray, horizon: int = HORIZON, batch: int = 512
) -> dict[str, np.ndarray]:
    """Image MAE/BCE and collision AUC per horizon ``1..horizon`` for a ``predict(images, prims)``.

    Horizon ``h`` compares the predicted image after ``h`` true primitives with the stored one
    (where the first ``h`` steps were safe) and scores the collision probability of step ``h``
    against its label (where the first ``h - 1`` steps were safe).
    """
    data = sequence_data(ds, idx, horizon)
    bank = torch.from_numpy(np.asarray(ds.images))
    mae = np.zeros(horizon)
    bce = np.zeros(horizon)
    count = np.zeros(horizon)
    probs, labels, masks = [], [], []
    for start in range(0, len(idx), batch):
        sl = slice(start, start + batch)
        img, col = predict(bank[data["image_idx"][sl]], data["prims"][sl])
        nm = data["next_mask"][sl].numpy()
        true = bank[data["next_idx"][sl]].float().numpy()
        err = np.abs(img - true).mean((2, 3))
        pc = np.clip(img, 1e-6, 1 - 1e-6)
        b = -(true * np.log(pc) + (1 - true) * np.log(1 - pc)).mean((2, 3))
        mae += (err * nm).sum(0)
        bce += (b * nm).sum(0)
        count += nm.sum(0)
        probs.append(col)
        labels.append(data["labels"][sl].numpy())
        masks.append(data["label_mask"][sl].numpy())
    p, y, m = np.concatenate(probs), np.concatenate(labels), np.concatenate(masks)
    auc = np.array([roc_auc(y[m[:, k], k], p[m[:, k], k]) for k in range(horizon)])
    return {"mae": mae / np.maximum(count, 1), "bce": bce / np.maximum(count, 1), "auc": auc, "n": count}
