"""The random-policy dataset on disk: its layout, safe loading and statistics.

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

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .io import DatasetError, load_npy, sha256_file

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

    def has_next(self, idx: np.ndarray) -> np.ndarray:
        """Whether each pool index's step was safe and its next image (same video) is stored.

        The one definition of "has a next image": the colliding step has none, and neither does
        the last image of a video that survived every primitive (the next pool entry starts
        another video).
        """
        idx = np.asarray(idx, np.int64)
        n = len(self)
        nxt = np.minimum(idx + 1, n - 1)
        return (self.labels[idx] == 0) & (idx + 1 < n) & (self.episode[nxt] == self.episode[idx])


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
