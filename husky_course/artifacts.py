"""The one artifact resolver: datasets and checkpoints under ``artifacts/<profile>/``.

Each artifact's directory name carries a hash of the config that made it, so a changed config
builds a new artifact instead of silently reusing a stale one. Nothing is ever downloaded: a
missing artifact is built on demand, with a progress bar.

The root is ``$HUSKY_ARTIFACTS`` if set, else ``artifacts/`` in the repository (when the package
is installed from a checkout), else ``./artifacts``.
"""

from __future__ import annotations

import os
from pathlib import Path

from .collect import collect, collection_spec
from .config import Profile, config_hash, get_profile
from .dataset import Dataset, load_dataset


def artifacts_root() -> Path:
    """Where artifacts live (see the module docstring)."""
    env = os.environ.get("HUSKY_ARTIFACTS")
    if env:
        return Path(env)
    repo = Path(__file__).resolve().parents[1]
    if (repo / "pyproject.toml").is_file():
        return repo / "artifacts"
    return Path.cwd() / "artifacts"


def dataset_dir(profile: Profile | str | None = None) -> Path:
    """Directory of the profile's random-policy dataset (it may not exist yet)."""
    profile = profile if isinstance(profile, Profile) else get_profile(profile)
    data = profile.data
    spec = collection_spec(profile, data.videos, data.seed, data.backend)
    return artifacts_root() / profile.name / f"dataset-{config_hash(spec)}"


def get_dataset(
    profile: Profile | str | None = None, workers: int | None = None, progress: bool = True
) -> Dataset:
    """The profile's dataset, collected first if it is missing or unfinished."""
    profile = profile if isinstance(profile, Profile) else get_profile(profile)
    path = dataset_dir(profile)
    if not (path / "meta.json").is_file():
        collect(path, profile, workers=workers or min(2, os.cpu_count() or 1), progress=progress)
    return load_dataset(path)


def model_dir(name: str, fingerprint: dict, profile: Profile | str | None = None) -> Path:
    """Checkpoint directory of model ``name`` trained under ``fingerprint`` (may not exist yet)."""
    profile = profile if isinstance(profile, Profile) else get_profile(profile)
    return artifacts_root() / profile.name / "models" / f"{name}-{config_hash(fingerprint)}"


def runs_dir(name: str, fingerprint: dict, profile: Profile | str | None = None) -> Path:
    """TensorBoard log directory of a training run: ``runs/<profile>/<name>-<hash>`` beside ``artifacts/``."""
    profile = profile if isinstance(profile, Profile) else get_profile(profile)
    return artifacts_root().parent / "runs" / profile.name / f"{name}-{config_hash(fingerprint)}"
