"""Tensors the trainer consumes, built from the dataset for each pipeline.

Every builder takes pool indices (from :mod:`husky_course.data.splits`) and returns a dict of
equal-length tensors, the input :func:`husky_course.training.trainer.fit` expects. Images are
shared with the dataset's array, never copied (:func:`images_tensor`).
"""

from __future__ import annotations

import numpy as np
import torch
from torch import Tensor

from ..data.dataset import Dataset


def images_tensor(ds: Dataset) -> Tensor:
    """All images of ``ds`` as one float16 tensor ``(N, size, size)`` sharing the dataset's memory."""
    return torch.from_numpy(np.asarray(ds.images))


def pair_data(ds: Dataset, t: np.ndarray) -> dict[str, Tensor]:
    """Tensors of the pairs ``(image t, applied primitive, image t+1)`` for pool indices ``t``."""
    images = images_tensor(ds)
    ti = torch.from_numpy(np.asarray(t, np.int64))
    return {
        "image": images[ti],
        "prim": torch.from_numpy(ds.applied[t].astype(np.int64)),
        "next": images[ti + 1],
    }


def reward_data(ds: Dataset, idx: np.ndarray, latents: np.ndarray) -> dict[str, Tensor]:
    """Latents and safety labels of pool indices ``idx`` (``latents`` covers the whole pool)."""
    return {"z": torch.from_numpy(latents[idx]), "label": torch.from_numpy(ds.labels[idx].astype(np.float32))}


def safety_data(ds: Dataset, idx: np.ndarray) -> dict[str, Tensor]:
    """Images, applied primitives and safety labels of pool indices ``idx``."""
    images = images_tensor(ds)
    return {
        "image": images[torch.from_numpy(np.asarray(idx, np.int64))],
        "prim": torch.from_numpy(ds.applied[idx].astype(np.int64)),
        "label": torch.from_numpy(ds.labels[idx].astype(np.float32)),
    }


def joint_data(ds: Dataset, idx: np.ndarray) -> dict[str, Tensor]:
    """Every image with its primitive, label and (where one exists) next image."""
    idx = np.asarray(idx, np.int64)
    data = safety_data(ds, idx)
    has_next = ds.has_next(idx)
    nxt = np.minimum(idx + 1, len(ds) - 1)
    data["next"] = images_tensor(ds)[torch.from_numpy(np.where(has_next, nxt, idx))]
    data["has_next"] = torch.from_numpy(has_next)
    return data


def survival_data(ds: Dataset, idx: np.ndarray, survival: np.ndarray) -> dict[str, Tensor]:
    """Images and the simulator's survival labels ``(N, n_primitives)`` of pool indices ``idx``."""
    t = torch.from_numpy(np.asarray(idx, np.int64))
    return {"image": images_tensor(ds)[t], "survival": torch.from_numpy(survival)[t]}


def sequence_data(ds: Dataset, idx: np.ndarray, horizon: int) -> dict[str, Tensor]:
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
    next_mask = label_mask & ds.has_next(s)
    return {
        "image_idx": torch.from_numpy(idx),
        "prims": torch.from_numpy(np.where(label_mask, ds.applied[s], 0).astype(np.int64)),
        "labels": torch.from_numpy(np.where(label_mask, ds.labels[s], 0).astype(np.float32)),
        "label_mask": torch.from_numpy(label_mask),
        "next_idx": torch.from_numpy(np.where(next_mask, nxt, 0)),
        "next_mask": torch.from_numpy(next_mask),
    }
