"""Running trained models on many images: batched, in evaluation mode, without gradients.

Planners and chapters call these; nothing here trains. :class:`single_thread` is the one place
that decides how many threads a single decision uses.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import Tensor, nn

from ..models.paper import Encoder, EncoderDecoder
from ..models.rnn import RNNLookahead
from ..models.safety import JointModel

BATCH = 2048  #: images per forward pass (bounds memory, not results)


class single_thread:  # noqa: N801 (used like a function: ``with single_thread():``)
    """Run torch on one thread inside the block.

    One decision is a handful of tiny matrix products; splitting them across threads costs more in
    synchronisation than it saves, and on a busy 2-core machine it made decisions 100x slower.
    """

    def __enter__(self) -> None:
        self.saved = torch.get_num_threads()
        torch.set_num_threads(1)

    def __exit__(self, *exc: object) -> None:
        torch.set_num_threads(self.saved)


@torch.no_grad()
def encode(encoder: Encoder, images: Tensor | np.ndarray, batch: int = BATCH) -> np.ndarray:
    """Latents ``(N, latent)`` of images (evaluation mode, batched)."""
    encoder.eval()
    images = torch.as_tensor(np.asarray(images)) if not isinstance(images, Tensor) else images
    out = [encoder(images[i : i + batch].float()) for i in range(0, len(images), batch)]
    return torch.cat(out).numpy() if out else np.zeros((0, encoder.fc.out_features), np.float32)


@torch.no_grad()
def predict_next(
    model: EncoderDecoder | JointModel, images: np.ndarray | Tensor, prims: np.ndarray, batch: int = BATCH
) -> np.ndarray:
    """Predicted next images ``(N, size, size)`` for images and applied primitives."""
    model.eval()
    images = torch.as_tensor(np.asarray(images)).float()
    prims_t = torch.as_tensor(np.asarray(prims, np.int64))
    out = [
        model.decoder(model.encoder(images[i : i + batch]), prims_t[i : i + batch])
        for i in range(0, len(images), batch)
    ]
    return torch.cat(out).numpy()


@torch.no_grad()
def collision_probs(model: JointModel, images: np.ndarray | Tensor, batch: int = BATCH) -> np.ndarray:
    """The joint model's collision probability of every primitive for each image, ``(N, n)``."""
    model.eval()
    images = torch.as_tensor(np.asarray(images)).float()
    return torch.cat(
        [model.collision_probs(images[i : i + batch]) for i in range(0, len(images), batch)]
    ).numpy()


@torch.no_grad()
def survival_predictions(model: nn.Module, images: np.ndarray | Tensor, batch: int = BATCH) -> np.ndarray:
    """Predicted steps survived ``(N, n)`` from a :class:`~husky_course.models.safety.SurvivalNet`."""
    model.eval()
    images = torch.as_tensor(np.asarray(images)).float()
    return torch.cat([model.survival(images[i : i + batch]) for i in range(0, len(images), batch)]).numpy()  # type: ignore[operator]


@torch.no_grad()
def rnn_predictions(model: RNNLookahead, images: Tensor, prims: Tensor) -> tuple[np.ndarray, np.ndarray]:
    """Predicted images ``(B, K, size, size)`` and collision probabilities ``(B, K)`` along sequences."""
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
