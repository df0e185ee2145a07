"""The memory student's network as an artifact: its fingerprint, a fresh seeded net, loading.

The student is *trained* by DAgger in :mod:`husky_course.imitation.dagger` (it needs planners to
roll out); what identifies and loads its checkpoint lives here, below the planners, so the
planner registry can load it without importing the trainer.
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import torch

from ..config import OracleConfig, Profile, to_dict, world_flag
from ..data.store import model_dir
from ..models.memory import MOVING_INPUTS, MemoryNet, map_channels
from .trainer import CheckpointError, History, load_model


def new_memory_net(profile: Profile) -> MemoryNet:
    """A fresh :class:`~husky_course.models.memory.MemoryNet`, seeded by ``profile.memory.train.seed``."""
    mem = profile.memory
    torch.manual_seed(mem.train.seed)
    return MemoryNet(mem.label_horizon, mem.map_cells, profile.dims, map_channels(profile.sim))


def memory_fingerprint(profile: Profile) -> dict:
    """What determines the student: its network, the memory config, the simulator and the teacher."""
    found = {
        "model": new_memory_net(profile).spec.to_dict(),
        "memory": to_dict(profile.memory),
        "sim": to_dict(profile.sim),
        "teacher": {"planner": "oracle", **asdict(OracleConfig())},
    }
    if map_channels(profile.sim) > 1:  # the moving course's inputs (the static student's key predates this)
        found["inputs"] = MOVING_INPUTS
    return found


def memory_dir(profile: Profile) -> Path:
    """Where the student's rounds and final checkpoint live."""
    return model_dir("memory", memory_fingerprint(profile), profile)


def final_fingerprint(profile: Profile) -> dict:
    """The fingerprint stored in the final ``model.pt``."""
    return {**memory_fingerprint(profile), "train": asdict(profile.memory.train)}


def load_memory(profile: Profile) -> tuple[MemoryNet, History, str]:
    """The trained student ``(network, history, path)``; never trains (the error names the command)."""
    final = memory_dir(profile) / "model.pt"
    if not final.is_file():
        raise CheckpointError(
            f"no trained memory model for profile {profile.name!r} (expected {final}); "
            f"train it with `python -m husky_course train memory "
            f"--profile {profile.name}{world_flag(profile.sim)}`"
        )
    model = new_memory_net(profile)
    history = load_model(final, model, final_fingerprint(profile))
    return model, history, str(final)
