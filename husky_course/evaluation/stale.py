"""Stale artifacts: what ``python -m husky_course clean`` lists and removes.

Every artifact's name is the hash of a key that holds the code that made it
(:func:`~husky_course.data.code.code_fingerprint`), so an edit of that code, or of a config, leaves
the old artifact where it was, under a name nothing asks for any more. :func:`sweep` sorts the
entries of ``artifacts/<profile>/`` into

* *current* -- a name today's code and the profile's config give (on either course,
  ``--world static`` or ``moving``): the dataset, the labels and models trained on a dataset
  that is in the store, the memory student, the disc network and its cut network, the certificate
  (at the profile's scale, or at the scale a ``certify`` run recorded in its ``key.json``), a joint
  model of any ``safety_weight`` its checkpoint records; a stored evaluation whose recorded code fingerprint
  is today's (:func:`~husky_course.evaluation.stored.stale_evaluation`);
* *stale* -- every other entry of those kinds (a model of a dataset no longer in the store
  included: build the dataset first to keep it);
* *unchecked* -- kinds this module cannot judge (chapter 4's ``diagnosis``, anything unknown):
  always kept.

The training runs' TensorBoard logs beside the store (``runs/<profile>/<name>-<hash>``, named as
the artifact the run made) are sorted the same way: a log of a judged kind is current when the
store's current artifact of that name is, else stale; the others (the DAgger rounds' logs, whose
names hash each round's own key) are unchecked.

Judging builds nothing: it reads ``meta.json`` files, checkpoint headers and ``key.json`` files.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import dataclass, field, replace
from pathlib import Path

from ..config import SENSING, WORLD_KINDS, Profile, check_profile, with_sensing, with_world
from ..data.io import DatasetError
from ..data.store import artifacts_root, dataset_dir, stored_dataset_id
from ..training.builders import MODELS, checkpoint_dir, labels_dir
from ..training.cuts import cut_dir
from ..training.discs import disc_dir
from ..training.memory import memory_dir
from ..training.trainer import CheckpointError, read_checkpoint
from .certificate import KEY_FILE, certificate_dir
from .stored import stale_evaluation

#: model kinds :func:`sweep` judges (the others under ``models/`` are unchecked)
JUDGED = (*MODELS, "labels", "memory", "discs", "cuts", "certificate")


@dataclass
class Sweep:
    """The entries of one profile's store, sorted (see the module docstring)."""

    stale: list[Path] = field(default_factory=list)
    current: list[Path] = field(default_factory=list)
    unchecked: list[Path] = field(default_factory=list)


def _joint_weights(models: Path) -> set[float]:
    """The ``safety_weight`` of every joint model in the store (from its checkpoint's fingerprint)."""
    found = {1.0}
    for run in models.glob("joint-*"):
        for name in ("model.pt", "last.pt"):
            try:
                found.add(float(read_checkpoint(run / name)["fingerprint"]["w"]))
                break
            except (CheckpointError, KeyError, TypeError, ValueError):
                continue
    return found


def _certificate_scales(models: Path, profile: Profile) -> list[Profile]:
    """``profile`` at its own certificate scale and at each scale a stored ``key.json`` records."""
    scales = [profile]
    for key in models.glob(f"certificate-*/{KEY_FILE}"):
        try:
            guarantee = json.loads(key.read_text())["guarantee"]
            scales.append(replace(profile, guarantee=replace(profile.guarantee, **guarantee)))
        except (OSError, ValueError, KeyError, TypeError):
            continue
    return scales


def current_paths(profile: Profile) -> set[Path]:
    """Every artifact path today's code and ``profile`` give, on either course and with either senses
    (chapter 11's realistic disc network is current too; builds nothing)."""
    profile = check_profile(profile)
    models = artifacts_root() / profile.name / "models"
    weights = _joint_weights(models)
    out: set[Path] = set()
    for senses in SENSING:
        out |= _current_with(with_sensing(profile, senses), models, weights)
    return out


def _current_with(profile: Profile, models: Path, weights: set[float]) -> set[Path]:
    """:func:`current_paths` for ``profile``'s senses."""
    out = {disc_dir(profile), cut_dir(profile)}
    for kind in WORLD_KINDS:
        p = with_world(profile, kind)
        out |= {dataset_dir(p), memory_dir(p)}
        out |= {certificate_dir(scale) for scale in _certificate_scales(models, p)}
        try:
            ds_id = stored_dataset_id(p)
        except DatasetError:
            continue  # no dataset: nothing trained on it is current
        out.add(labels_dir(p, ds_id))
        out |= {checkpoint_dir(name, p, ds_id) for name in MODELS}
        out |= {checkpoint_dir("joint", p, ds_id, w) for w in weights}
    return out


def sweep(profile: Profile) -> Sweep:
    """Sort the entries of ``artifacts/<profile>/``, and the training logs of ``runs/<profile>/``, into
    stale, current and unchecked."""
    profile = check_profile(profile)
    root = artifacts_root() / profile.name
    found = Sweep()
    current = current_paths(profile)
    for entry in sorted(root.iterdir()) if root.is_dir() else []:
        if entry.name.startswith("dataset-"):
            (found.current if entry in current else found.stale).append(entry)
        elif entry.name == "models" and entry.is_dir():
            for run in sorted(entry.iterdir()):
                if run.name.rsplit("-", 1)[0] not in JUDGED:
                    found.unchecked.append(run)
                else:
                    (found.current if run in current else found.stale).append(run)
        elif entry.name == "evaluations" and entry.is_dir():
            for run in sorted(entry.iterdir()):
                stale = run.suffix != ".npz" or stale_evaluation(run)
                (found.stale if stale else found.current).append(run)
        else:
            found.unchecked.append(entry)
    logs = artifacts_root().parent / "runs" / profile.name  # :func:`~husky_course.data.store.runs_dir`
    names = {path.name for path in current}
    for run in sorted(logs.iterdir()) if logs.is_dir() else []:
        if run.name.rsplit("-", 1)[0] not in JUDGED:
            found.unchecked.append(run)
        else:
            (found.current if run.name in names else found.stale).append(run)
    return found


def remove(paths: list[Path]) -> None:
    """Delete ``paths`` (directories with everything in them)."""
    for path in paths:
        if path.is_dir():
            shutil.rmtree(path)
        else:
            path.unlink(missing_ok=True)
