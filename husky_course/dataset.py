"""The random-policy dataset on disk: its layout, safe loading, statistics and training splits.

Layout (the paper's single-indexed pool, Section 3.2, plus what it lacked):

=================  ===============  ====================================================================
file               shape / dtype    meaning
=================  ===============  ====================================================================
``images.npy``     (N, 50, 50) f2   depth image taken *before* the step's primitive, in [0, 1]
``prims.npy``      (N,) int16       primitive applied at that step, or ``-1`` where it collided
``labels.npy``     (N,) uint8       1 where applying that step's primitive collides, else 0
``applied.npy``    (N,) int16       primitive actually applied at every step (also at a collision)
``episode.npy``    (N,) int32       video index of every image
``step.npy``       (N,) int16       step of the image within its video (0, 1, ...)
``poses.npy``      (N, 3) f4        robot pose ``(x, y, yaw)`` where the image was taken
``world_seeds.npy`` (V,) int64      world seed of every video
``lengths.npy``    (V,) int16       primitives applied in every video (the colliding one included)
``collided.npy``   (V,) uint8       whether the video ended in a collision
``meta.json``                       config, seeds, backend, version, counts and a sha256 per array
=================  ===============  ====================================================================

A video that survives all ``max_primitives`` primitives ends after its last *safe* step: it has
``max_primitives`` images, no ``-1`` and no unsafe label; the image after its final primitive is
not stored (no primitive is applied there). ``meta.json`` is written last: a directory without it
is not a finished dataset.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

FORMAT_VERSION = 1
STEP_ARRAYS = ("images", "prims", "labels", "applied", "episode", "step", "poses")
VIDEO_ARRAYS = ("world_seeds", "lengths", "collided")
DTYPES = {
    "images": np.float16,
    "prims": np.int16,
    "labels": np.uint8,
    "applied": np.int16,
    "episode": np.int32,
    "step": np.int16,
    "poses": np.float32,
    "world_seeds": np.int64,
    "lengths": np.int16,
    "collided": np.uint8,
}


class DatasetError(ValueError):
    """A dataset directory or file that cannot be used as it is (the message says why)."""


# --- small safe-IO helpers (also used by the collector) -----------------------------------------
def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` via a temporary file and an atomic rename."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "wb") as fh:
        fh.write(data)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


def atomic_save_npy(path: Path, array: np.ndarray) -> None:
    """``np.save`` to ``path`` atomically (a reader never sees a partial file)."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "wb") as fh:
        np.save(fh, np.ascontiguousarray(array), allow_pickle=False)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


def load_npy(path: Path, mmap: bool = False) -> np.ndarray:
    """Load one ``.npy`` safely; a missing, truncated or corrupted file raises :class:`DatasetError`."""
    path = Path(path)
    if not path.is_file():
        raise DatasetError(f"missing dataset file {path}")
    try:
        return np.load(path, allow_pickle=False, mmap_mode="r" if mmap else None)
    except (ValueError, OSError, EOFError) as exc:
        raise DatasetError(f"{path} is truncated or corrupted ({exc}); delete it and collect again") from exc


def sha256_file(path: Path) -> str:
    """Hex sha256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


# --- the dataset --------------------------------------------------------------------------------
@dataclass
class Dataset:
    """A loaded dataset (arrays as described in the module docstring)."""

    path: Path
    meta: dict
    images: np.ndarray
    prims: np.ndarray
    labels: np.ndarray
    applied: np.ndarray
    episode: np.ndarray
    step: np.ndarray
    poses: np.ndarray
    world_seeds: np.ndarray
    lengths: np.ndarray
    collided: np.ndarray

    def __len__(self) -> int:
        return int(self.labels.shape[0])

    def image(self, i: int) -> np.ndarray:
        """Image ``i`` as float32 in [0, 1]."""
        return np.asarray(self.images[i], np.float32)

    def video(self, v: int) -> np.ndarray:
        """Pool indices of the images of video ``v``, in order."""
        return np.flatnonzero(self.episode == v)


def load_dataset(path: str | Path, verify: bool = True, mmap: bool = False) -> Dataset:
    """Load a finished dataset directory.

    Parameters
    ----------
    verify : bool
        Check every array against the sha256 in ``meta.json`` (detects corrupted files).
    mmap : bool
        Memory-map the arrays instead of reading them.
    """
    path = Path(path)
    meta_path = path / "meta.json"
    if not meta_path.is_file():
        raise DatasetError(
            f"{path} holds no finished dataset (no meta.json): run "
            f"`python -m husky_course collect --out {path}` to build or finish it"
        )
    try:
        meta = json.loads(meta_path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise DatasetError(
            f"{meta_path} is truncated or corrupted ({exc}); collect the dataset again"
        ) from exc
    missing = [k for k in ("format", "images", "videos", "sha256") if k not in meta]
    if missing:
        raise DatasetError(f"{meta_path} lacks {', '.join(missing)}; collect the dataset again")
    if meta.get("format") != FORMAT_VERSION:
        raise DatasetError(f"{path}: dataset format {meta.get('format')} != {FORMAT_VERSION}")
    arrays = {}
    for name in STEP_ARRAYS + VIDEO_ARRAYS:
        file = path / f"{name}.npy"
        if verify and file.is_file() and sha256_file(file) != meta["sha256"][name]:
            raise DatasetError(f"{file} is corrupted (its sha256 does not match meta.json)")
        arr = load_npy(file, mmap=mmap)
        if arr.dtype != DTYPES[name]:
            raise DatasetError(f"{file} has dtype {arr.dtype}, expected {np.dtype(DTYPES[name])}")
        arrays[name] = arr
    n, v = meta["images"], meta["videos"]
    for name in STEP_ARRAYS:
        if arrays[name].shape[0] != n:
            raise DatasetError(f"{path}/{name}.npy has {arrays[name].shape[0]} rows, meta says {n}")
    for name in VIDEO_ARRAYS:
        if arrays[name].shape[0] != v:
            raise DatasetError(f"{path}/{name}.npy has {arrays[name].shape[0]} rows, meta says {v}")
    return Dataset(path=path, meta=meta, **arrays)


def stats(ds: Dataset) -> dict:
    """Counts a reader wants first: videos, images, mean primitives per video, safe/unsafe."""
    unsafe = int(ds.labels.sum())
    return {
        "videos": int(ds.lengths.shape[0]),
        "images": len(ds),
        "mean_primitives_per_video": float(ds.lengths.mean()) if len(ds.lengths) else 0.0,
        "safe": len(ds) - unsafe,
        "unsafe": unsafe,
        "videos_ending_in_collision": int(ds.collided.sum()),
        "videos_surviving": int(len(ds.collided) - ds.collided.sum()),
    }


# --- training splits ----------------------------------------------------------------------------
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


def val_videos(ds: Dataset, seed: int = 0, val_fraction: float = 0.2) -> np.ndarray:
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
    ok = (ds.labels[:-1] == 0) & (ds.episode[1:] == ds.episode[:-1])
    return t[ok]


def encoder_decoder_pairs(ds: Dataset, seed: int = 0, val_fraction: float = 0.2) -> PairSplit:
    """The first pipeline's data: collision-free ``(t, t+1)`` pairs, split 80/20 by video (seeded)."""
    t = pair_indices(ds)
    tr, va = _split(t, ds, seed, val_fraction)
    return PairSplit(tr, tr + 1, va, va + 1)


def reward_set(
    ds: Dataset, seed: int = 0, safe_fraction: float = 0.5, val_fraction: float = 0.2
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
