"""The cut network as an artifact: its fingerprint, a fresh seeded net, loading.

It is *trained* in :mod:`husky_course.imitation.cuts` on the disc network's views, read by the
trained disc network; its key holds the disc network's
(:func:`~husky_course.training.discs.disc_fingerprint`),
so a retrained disc network retrains it too.
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import torch

from ..config import Profile, with_world, world_flag
from ..data.code import code_fingerprint
from ..data.store import model_dir
from ..models.cuts import CUT_FEATURE_TEXT, CutNet
from .discs import disc_fingerprint
from .trainer import CheckpointError, History, load_model

#: what makes the cut network, named here and hashed with its imports, never imported (a higher stage)
CUTS_CODE = ("husky_course.imitation.cuts",)


def new_cut_net(profile: Profile) -> CutNet:
    """A fresh :class:`CutNet`, seeded by ``profile.discs.cut_train.seed``."""
    torch.manual_seed(profile.discs.cut_train.seed)
    return CutNet()


def cut_fingerprint(profile: Profile) -> dict:
    """What determines the cut network: its spec and features, the disc network it reads with (its
    views included) and the code that makes it (:data:`CUTS_CODE`); always the static course's."""
    profile = with_world(profile, "static")
    return {"model": new_cut_net(profile).spec.to_dict(), "features": CUT_FEATURE_TEXT,
            "discs": disc_fingerprint(profile), "code": code_fingerprint(*CUTS_CODE)}


def cut_dir(profile: Profile) -> Path:
    """Where the cut network's views and checkpoint live."""
    return model_dir("cuts", cut_fingerprint(profile), profile)


def load_cuts(profile: Profile) -> tuple[CutNet, History, str]:
    """The trained cut network; never trains (the error names the command that does)."""
    path = cut_dir(profile) / "model.pt"
    if not path.is_file():
        raise CheckpointError(
            f"no trained cut network for profile {profile.name!r} (expected {path}); train it with "
            f"`python -m husky_course train cuts --profile {profile.name}"
            f"{world_flag(with_world(profile, 'static').sim)}` (after the disc network, which it reads with)"
        )
    model = new_cut_net(profile)
    history = load_model(path, model, {**cut_fingerprint(profile), "train": asdict(profile.discs.cut_train)})
    return model, history, str(path)
