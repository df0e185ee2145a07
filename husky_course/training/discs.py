"""The disc network as an artifact: its fingerprint, a fresh seeded net, loading.

It is *trained* in :mod:`husky_course.imitation.discs` (on the planner's own perception of
simulated views); what identifies and loads its checkpoint lives here, below the planners, so the
planner registry can load it without importing the trainer.
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import torch

from ..config import Profile, to_dict, with_world, world_flag
from ..data.code import code_fingerprint
from ..data.store import model_dir
from ..models.discs import PIECE_FEATURES, DiscNet
from .trainer import CheckpointError, History, load_model


def new_disc_net(profile: Profile) -> DiscNet:
    """A fresh :class:`DiscNet`, seeded by ``profile.discs.train.seed``."""
    torch.manual_seed(profile.discs.train.seed)
    return DiscNet(profile.sim.world.radius_range)


#: what makes the disc network (its views, the planner's piece reader, the fit), named here and
#: hashed with its imports, never imported (a higher stage)
DISCS_CODE = ("husky_course.imitation.discs",)


def disc_fingerprint(profile: Profile) -> dict:
    """What determines the disc network: its spec, its views and labels, the simulator and the code
    that makes it (:data:`DISCS_CODE`).

    One network serves both courses: it reads the geometry of one image, and the moving course at
    time 0 is the static course of the same seed, so it is always the static course's (a profile of
    either course names the same artifact).
    """
    profile = with_world(profile, "static")
    cfg = profile.discs
    views = {k: v for k, v in to_dict(cfg).items() if k in ("collection_seed", "worlds", "poses_per_world")}
    return {"model": new_disc_net(profile).spec.to_dict(), "views": views, "features": PIECE_FEATURES,
            "sim": to_dict(profile.sim), "code": code_fingerprint(*DISCS_CODE)}


def disc_dir(profile: Profile) -> Path:
    """Where the disc network's views and checkpoint live."""
    return model_dir("discs", disc_fingerprint(profile), profile)


def load_discs(profile: Profile) -> tuple[DiscNet, History, str]:
    """The trained disc network; never trains (the error names the command that does)."""
    path = disc_dir(profile) / "model.pt"
    if not path.is_file():
        raise CheckpointError(
            f"no trained disc network for profile {profile.name!r} (expected {path}); train it with "
            f"`python -m husky_course train discs --profile {profile.name}"
            f"{world_flag(with_world(profile, 'static').sim)}`"
        )
    model = new_disc_net(profile)
    history = load_model(path, model, {**disc_fingerprint(profile), "train": asdict(profile.discs.train)})
    return model, history, str(path)
