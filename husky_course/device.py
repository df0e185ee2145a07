"""Where torch runs: ``HUSKY_DEVICE`` (or the CLI's ``--device``) is read here and nowhere else.

``auto`` (the default) is CUDA when torch sees a GPU, else the CPU; ``cpu`` and ``cuda`` (or
``cuda:N``) force one. Training (:func:`husky_course.training.trainer.fit`) and batched inference
(:mod:`husky_course.training.inference`) run there. Checkpoints are always written with CPU
tensors and read with ``map_location="cpu"``, so a model trained on one device loads on the other.
A single planning decision stays on the CPU unless ``evaluate --device`` asks otherwise: one image
through these small networks takes about a millisecond on one CPU thread, less than a GPU round trip.

On a CPU-only machine ``auto`` is the CPU and every result is the same as before devices existed.
"""

from __future__ import annotations

import os

import torch

ENV = "HUSKY_DEVICE"
CHOICES = ("auto", "cpu", "cuda")
_chosen: str | None = None  # set by the CLI's --device; wins over the environment


def resolve_device(name: str | None = None) -> torch.device:
    """The ``torch.device`` for ``name`` (``auto``, ``cpu``, ``cuda``, ``cuda:N``).

    ``None`` means the CLI's choice (:func:`set_device`), else ``$HUSKY_DEVICE``, else ``auto``.
    Raises ``ValueError`` for an unknown name or for CUDA on a machine without it.
    """
    name = (name or _chosen or os.environ.get(ENV) or "auto").strip().lower()
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if name == "cpu":
        return torch.device("cpu")
    if name == "cuda" or (name.startswith("cuda:") and name[5:].isdigit()):
        if not torch.cuda.is_available():
            raise ValueError(
                f"device {name!r} asked for (--device or ${ENV}), but torch sees no CUDA GPU here; "
                "use --device cpu (or auto)"
            )
        return torch.device(name)
    raise ValueError(f"unknown device {name!r} (--device or ${ENV}): choose one of {', '.join(CHOICES)}")


def set_device(name: str | None) -> torch.device:
    """Choose the device for this process (the CLI's ``--device``); checked now, not at first use."""
    global _chosen
    device = resolve_device(name)
    _chosen = name
    return device
