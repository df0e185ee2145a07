"""Training splits: which images each pipeline trains and validates on.

Every split is by whole video (:func:`val_videos`), seeded, and shared by all pipelines, so all
models are compared on the same validation worlds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config import DataConfig
from .dataset import Dataset

_DEFAULT = DataConfig()


@dataclass(frozen=True)
class PairSplit:
    """Encoder/decoder pairs: image ``t`` (pool index), its primitive, image ``t + 1``."""

    train_t: np.ndarray
    train_next: np.ndarray
    val_t: np.ndarray
    val_next: np.ndarray


@dataclass(frozen=True)
class LabelSplit:
    """Reward-net examples: pool indices whose safety label is the target."""

    train: np.ndarray
    val: np.ndarray


def val_videos(ds: Dataset, seed: int = 0, val_fraction: float = _DEFAULT.val_fraction) -> np.ndarray:
    """Boolean mask over videos: which ones form the validation set (seeded, by whole video).

    The paper samples 80 % of the *data* for training. We sample 80 % of the *videos*: two
    consecutive frames of one video are nearly the same picture, and a validation image whose
    neighbour was trained on would measure memory, not generalisation. Every pipeline uses this
    one split, so all models are compared on the same validation worlds.
    """
    if not 0.0 < val_fraction < 1.0:
        raise ValueError(f"val_fraction must be in (0, 1), got {val_fraction}")
    n = int(ds.lengths.shape[0])
    perm = np.random.default_rng([seed, 7]).permutation(n)
    mask = np.zeros(n, bool)
    mask[perm[: int(round(val_fraction * n))]] = True
    return mask


def _split(idx: np.ndarray, ds: Dataset, seed: int, val_fraction: float) -> tuple[np.ndarray, np.ndarray]:
    in_val = val_videos(ds, seed, val_fraction)[ds.episode[idx]]
    return np.sort(idx[~in_val]), np.sort(idx[in_val])


def pair_indices(ds: Dataset) -> np.ndarray:
    """Pool indices ``t`` whose step was safe and whose next image belongs to the same video.

    This is the paper's filter (drop images with safety label 1) made exact: the last image of a
    video that survived all primitives has no successor either, and the next pool entry would be
    the first image of another video, so it is dropped too.
    """
    t = np.arange(len(ds) - 1)
    return t[ds.has_next(t)]


def encoder_decoder_pairs(
    ds: Dataset, seed: int = 0, val_fraction: float = _DEFAULT.val_fraction
) -> PairSplit:
    """The first pipeline's data: collision-free ``(t, t+1)`` pairs, split 80/20 by video (seeded)."""
    t = pair_indices(ds)
    tr, va = _split(t, ds, seed, val_fraction)
    return PairSplit(tr, tr + 1, va, va + 1)


def reward_set(
    ds: Dataset,
    seed: int = 0,
    safe_fraction: float = _DEFAULT.reward_safe_fraction,
    val_fraction: float = _DEFAULT.val_fraction,
) -> LabelSplit:
    """The second pipeline's data: every unsafe image plus ``safe_fraction`` of the safe ones.

    Split 80/20 by video with :func:`val_videos`, like every other pipeline.
    """
    rng = np.random.default_rng(seed)
    unsafe = np.flatnonzero(ds.labels == 1)
    safe = np.flatnonzero(ds.labels == 0)
    keep = rng.choice(safe, size=int(round(safe_fraction * len(safe))), replace=False)
    tr, va = _split(np.concatenate([unsafe, keep]), ds, seed, val_fraction)
    return LabelSplit(tr, va)


def split_all(
    ds: Dataset, seed: int = 0, val_fraction: float = _DEFAULT.val_fraction
) -> tuple[np.ndarray, np.ndarray]:
    """Every pool index, split by the shared video split: ``(train, val)``."""
    in_val = val_videos(ds, seed, val_fraction)[ds.episode]
    return np.flatnonzero(~in_val), np.flatnonzero(in_val)
