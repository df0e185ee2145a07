"""The one artifact store: datasets, labels and checkpoints under ``artifacts/<profile>/``.

Every artifact's directory name is a hash of what made it -- the config, the *content* hash of
the dataset it came from (the sha256 sums in the dataset's ``meta.json``), the architecture, the
training settings and the fingerprint of the code that builds it
(:func:`~husky_course.data.code.code_fingerprint`: docstrings and comments left out) -- never a file
path, so a store copied or re-cloned elsewhere is reused as it is, and a changed config or a changed
function builds a new artifact instead of silently reusing a stale one. ``python -m husky_course
clean --dry-run`` lists the artifacts no current code or config would make.

Two kinds of calls, and only two:

* ``get_*`` builds what is missing (with a progress bar) and returns it;
* ``load_*`` / :func:`stored_dataset_id` never build: a missing artifact is an error that names
  the command that builds it.

Nothing is ever downloaded. The root is ``$HUSKY_ARTIFACTS`` if set, else ``artifacts/`` in the
repository (when the package is installed from a checkout), else ``./artifacts``.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from ..config import Profile, check_profile, config_hash, world_flag
from ..progress import announce_build
from .code import code_fingerprint
from .collect import collect, collection_spec
from .dataset import Dataset, load_dataset
from .io import DatasetError

ARTIFACTS_ENV = "HUSKY_ARTIFACTS"


def artifacts_root() -> Path:
    """Where artifacts live (see the module docstring)."""
    env = os.environ.get(ARTIFACTS_ENV)
    if env:
        return Path(env)
    repo = Path(__file__).resolve().parents[2]
    if (repo / "pyproject.toml").is_file():
        return repo / "artifacts"
    return Path.cwd() / "artifacts"


def dataset_dir(profile: Profile) -> Path:
    """Directory of the profile's random-policy dataset (it may not exist yet)."""
    data = check_profile(profile).data
    spec = collection_spec(profile, data.videos, data.seed, data.backend)
    key = {**spec, "code": code_fingerprint("husky_course.data.collect")}
    return artifacts_root() / profile.name / f"dataset-{config_hash(key)}"


def _missing_dataset(profile: Profile, path: Path) -> DatasetError:
    return DatasetError(
        f"no {profile.name} dataset in the artifact store ({path}): build it with "
        f"`python -m husky_course collect --profile {profile.name}{world_flag(profile.sim)}`"
    )


def get_dataset(profile: Profile, workers: int | None = None, progress: bool = True) -> Dataset:
    """The profile's dataset, collected first if it is missing or unfinished."""
    path = dataset_dir(profile)
    if not (path / "meta.json").is_file():
        announce_build("dataset", profile.name, f"collect{world_flag(profile.sim)}")
        collect(path, profile, workers=workers or min(2, os.cpu_count() or 1), progress=progress)
    return load_dataset(path)


def load_profile_dataset(profile: Profile) -> Dataset:
    """The profile's dataset if it has been built; never collects (the error names the command)."""
    path = dataset_dir(profile)
    if not (path / "meta.json").is_file():
        raise _missing_dataset(profile, path)
    return load_dataset(path)


def dataset_id(ds: Dataset) -> str:
    """A short hash of a dataset's *bytes* (from the sha256 sums in its ``meta.json``)."""
    return config_hash(ds.meta["sha256"])


def stored_dataset_id(profile: Profile) -> str:
    """:func:`dataset_id` of the profile's dataset, read from its ``meta.json`` alone (never builds)."""
    path = dataset_dir(profile)
    meta = path / "meta.json"
    if not meta.is_file():
        raise _missing_dataset(profile, path)
    try:
        return config_hash(json.loads(meta.read_text())["sha256"])
    except (json.JSONDecodeError, UnicodeDecodeError, KeyError) as exc:
        raise DatasetError(f"{meta} is damaged ({exc}); delete {path} and collect again") from exc


def model_dir(name: str, fingerprint: dict, profile: Profile) -> Path:
    """Directory of artifact ``name`` made under ``fingerprint`` (it may not exist yet)."""
    return artifacts_root() / check_profile(profile).name / "models" / f"{name}-{config_hash(fingerprint)}"


def runs_dir(name: str, fingerprint: dict, profile: Profile) -> Path:
    """TensorBoard log directory of a training run: ``runs/<profile>/<name>-<hash>`` beside the store."""
    return artifacts_root().parent / "runs" / profile.name / f"{name}-{config_hash(fingerprint)}"
