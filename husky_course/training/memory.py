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
from ..data.code import code_fingerprint
from ..data.store import model_dir
from ..models.memory import MemoryNet, map_channels
from .trainer import CheckpointError, History, load_model


def new_memory_net(profile: Profile) -> MemoryNet:
    """A fresh :class:`~husky_course.models.memory.MemoryNet`, seeded by ``profile.memory.train.seed``."""
    mem = profile.memory
    torch.manual_seed(mem.train.seed)
    return MemoryNet(mem.label_horizon, mem.map_cells, profile.dims, map_channels(profile.sim))


#: what trains the student (DAgger: the rollouts, the teacher, the labels, the student planner's
#: inputs, the fit), named here and hashed with its imports, never imported (a higher stage)
MEMORY_CODE = ("husky_course.imitation.dagger",)


def memory_fingerprint(profile: Profile) -> dict:
    """What determines the student: its network, the memory config, the simulator, the teacher and
    the code that trains it (:data:`MEMORY_CODE`)."""
    return {
        "model": new_memory_net(profile).spec.to_dict(),
        "memory": to_dict(profile.memory),
        "sim": to_dict(profile.sim),
        "teacher": {"planner": "oracle", **asdict(OracleConfig())},
        "code": code_fingerprint(*MEMORY_CODE),
    }


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
