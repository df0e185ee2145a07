"""Running trained models on many images: batched, in evaluation mode, without gradients.

Chapters and builders call these; nothing here trains. Each function runs the model on the
configured device (:func:`husky_course.device.resolve_device`: a GPU when there is one), a batch
at a time, and leaves the model where it found it; results come back as CPU numpy arrays.
:class:`single_thread` is the one place that decides how many threads a single decision uses.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import torch
from torch import Tensor, nn

from ..device import resolve_device
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


def model_device(model: nn.Module) -> torch.device:
    """Where ``model``'s weights are: its inputs are made there (the CPU unless it was moved)."""
    return next(model.parameters()).device


@contextmanager
def on_device(model: nn.Module) -> Iterator[torch.device]:
    """Run ``model`` (in evaluation mode) on the configured device inside the block, then move it back."""
    home = model_device(model)
    device = resolve_device()
    model.to(device).eval()
    try:
        yield device
    finally:
        model.to(home)


def _numpy(x: Tensor) -> np.ndarray:
    return x.cpu().numpy()


@torch.no_grad()
def encode(encoder: Encoder, images: Tensor | np.ndarray, batch: int = BATCH) -> np.ndarray:
    """Latents ``(N, latent)`` of images (evaluation mode, batched)."""
    images = torch.as_tensor(np.asarray(images)) if not isinstance(images, Tensor) else images
    with on_device(encoder) as dev:
        out = [_numpy(encoder(images[i : i + batch].to(dev).float())) for i in range(0, len(images), batch)]
    return np.concatenate(out) if out else np.zeros((0, encoder.fc.out_features), np.float32)


@torch.no_grad()
def predict_next(
    model: EncoderDecoder | JointModel, images: np.ndarray | Tensor, prims: np.ndarray, batch: int = BATCH
) -> np.ndarray:
    """Predicted next images ``(N, size, size)`` for images and applied primitives."""
    images = torch.as_tensor(np.asarray(images)).float()
    prims_t = torch.as_tensor(np.asarray(prims, np.int64))
    out = []
    with on_device(model) as dev:
        for i in range(0, len(images), batch):
            z = model.encoder(images[i : i + batch].to(dev))
            out.append(_numpy(model.decoder(z, prims_t[i : i + batch].to(dev))))
    return np.concatenate(out)


@torch.no_grad()
def collision_probs(model: JointModel, images: np.ndarray | Tensor, batch: int = BATCH) -> np.ndarray:
    """The joint model's collision probability of every primitive for each image, ``(N, n)``."""
    images = torch.as_tensor(np.asarray(images)).float()
    with on_device(model) as dev:
        out = [
            _numpy(model.collision_probs(images[i : i + batch].to(dev))) for i in range(0, len(images), batch)
        ]
    return np.concatenate(out)


@torch.no_grad()
def survival_predictions(model: nn.Module, images: np.ndarray | Tensor, batch: int = BATCH) -> np.ndarray:
    """Predicted steps survived ``(N, n)`` from a :class:`~husky_course.models.safety.SurvivalNet`."""
    images = torch.as_tensor(np.asarray(images)).float()
    with on_device(model) as dev:
        out = [_numpy(model.survival(images[i : i + batch].to(dev))) for i in range(0, len(images), batch)]  # type: ignore[operator]
    return np.concatenate(out)


@torch.no_grad()
def rnn_predictions(model: RNNLookahead, images: Tensor, prims: Tensor) -> tuple[np.ndarray, np.ndarray]:
    """Predicted images ``(B, K, size, size)`` and collision probabilities ``(B, K)`` along sequences."""
    with on_device(model) as dev:
        img, col = model.rollout(model.start(images.to(dev).float()), prims.to(dev))
        assert img is not None
        return _numpy(torch.sigmoid(img)), _numpy(torch.sigmoid(col))


@torch.no_grad()
def loop_predictions(model: JointModel, images: Tensor, prims: Tensor) -> tuple[np.ndarray, np.ndarray]:
    """The same predictions made the way Algorithm 1 does: decode, re-encode, repeat.

    The collision probability of step ``k`` is the joint model's safety head for ``prims[:, k]``
    on the latent reached after ``k`` decode/encode rounds.
    """
    with on_device(model) as dev:
        z = model.encoder(images.to(dev).float())
        imgs, cols = [], []
        for k in range(prims.shape[1]):
            a = prims[:, k].to(dev)
            cols.append(torch.sigmoid(model.safety_logits(z)).gather(1, a.view(-1, 1))[:, 0])
            img = model.decoder(z, a)
            imgs.append(img)
            z = model.encoder(img)
        return _numpy(torch.stack(imgs, 1)), _numpy(torch.stack(cols, 1))
