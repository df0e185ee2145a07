"""How prediction quality decays with the horizon (chapter 6): RNN look-ahead vs Algorithm 1's loop."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch
from torch import Tensor

from ..data.dataset import Dataset
from ..training.datasets import sequence_data
from .metrics import roc_auc


def horizon_errors(
    predict: Callable[[Tensor, Tensor], tuple[np.ndarray, np.ndarray]],
    ds: Dataset,
    idx: np.ndarray,
    horizon: int,
    batch: int = 512,
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
