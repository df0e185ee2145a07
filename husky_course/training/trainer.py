"""One small trainer for every model in the course, with safe, resumable checkpoints.

:func:`fit` trains any module that has a ``loss(batch) -> Tensor`` method on in-memory tensors:
Adam (fused on CPU), seeded shuffling, a validation pass per epoch, early stopping on the
validation loss (the best weights are kept), a TensorBoard event log (as the paper monitored its
runs), a tqdm bar, and a checkpoint after every epoch.

Checkpoints are plain dicts of tensors and JSON-able values, written atomically and read with
``torch.load(..., weights_only=True)``. Each records the model's :class:`~husky_course.models.base.ModelSpec`
and a *fingerprint* (the model spec, training config, dataset hash and code that produced it); loading
one into a different architecture, or resuming a run whose fingerprint differs, raises
:class:`CheckpointError` instead of silently mixing results. A run killed mid-epoch restarts from
its last finished epoch and ends with the same weights as an uninterrupted run, because the
shuffling of epoch ``e`` depends only on ``(seed, e)``.
"""

from __future__ import annotations

import io
import json
import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import torch
from torch import Tensor, nn

from ..config import TrainConfig
from ..data.io import atomic_write_bytes
from ..device import resolve_device
from ..progress import tqdm

CHECKPOINT_FORMAT = 1


class CheckpointError(ValueError):
    """A checkpoint that is missing, corrupted, or made for another architecture or config."""


@dataclass
class History:
    """Per-epoch losses of a run and how it ended."""

    train_loss: list[float] = field(default_factory=list)
    val_loss: list[float] = field(default_factory=list)
    best_epoch: int = -1
    best_val: float = math.inf
    seconds: float = 0.0
    stopped_early: bool = False

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> History:
        """Inverse of :meth:`to_dict`."""
        return cls(**data)


def _n_rows(data: dict[str, Tensor]) -> int:
    sizes = {k: int(v.shape[0]) for k, v in data.items()}
    if not sizes or len(set(sizes.values())) != 1:
        raise ValueError(f"every tensor in a dataset must have the same number of rows, got {sizes}")
    return next(iter(sizes.values()))


def _batches(data: dict[str, Tensor], order: np.ndarray, batch_size: int, device: torch.device):
    for start in range(0, len(order), batch_size):
        idx = torch.from_numpy(order[start : start + batch_size])
        yield {k: v[idx].to(device) for k, v in data.items()}, len(idx)  # a no-op on the CPU


def _cpu_state(model: nn.Module) -> dict[str, Tensor]:
    """The weights as CPU tensors (checkpoints load on any device)."""
    return {k: v.detach().to("cpu", copy=True) for k, v in model.state_dict().items()}


def _save(path: Path, payload: dict) -> None:
    buffer = io.BytesIO()
    torch.save(payload, buffer)
    atomic_write_bytes(path, buffer.getvalue())


def _payload(model: nn.Module, fingerprint: dict, history: History, **extra: object) -> dict:
    """The checkpoint dict: format, spec, fingerprint, history, weights, and ``extra`` entries."""
    return {
        "format": CHECKPOINT_FORMAT,
        "spec": model.spec.to_dict(),  # type: ignore[union-attr]
        "fingerprint": json.loads(json.dumps(fingerprint)),
        "history": history.to_dict(),
        "state_dict": _cpu_state(model),
        **extra,
    }


def read_checkpoint(path: str | Path) -> dict:
    """Read a checkpoint dict safely (``weights_only=True``); problems raise :class:`CheckpointError`."""
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"missing checkpoint {path}")
    try:
        payload = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # torch raises several types for truncated or foreign files
        raise CheckpointError(f"{path} is not a readable checkpoint ({exc}); delete it and retrain") from exc
    if not isinstance(payload, dict) or payload.get("format") != CHECKPOINT_FORMAT:
        raise CheckpointError(f"{path} is not a husky_course checkpoint (format {CHECKPOINT_FORMAT})")
    return payload


def load_into(
    model: nn.Module, payload: dict, source: str = "checkpoint", fingerprint: dict | None = None
) -> None:
    """Load ``payload['state_dict']`` into ``model`` after checking architecture and fingerprint."""
    want = model.spec.to_dict()  # type: ignore[union-attr]
    got = payload.get("spec")
    if got != want:
        raise CheckpointError(
            f"{source} was saved from architecture {got}, which does not match {type(model).__name__} "
            f"{want}; retrain it or load it into the right model"
        )
    if fingerprint is not None and payload.get("fingerprint") != json.loads(json.dumps(fingerprint)):
        raise CheckpointError(f"{source} was trained with another config or dataset; retrain it")
    try:
        model.load_state_dict(payload["state_dict"])
    except (RuntimeError, KeyError) as exc:
        raise CheckpointError(f"{source} does not fit {type(model).__name__}: {exc}") from exc


def save_model(path: str | Path, model: nn.Module, fingerprint: dict, history: History) -> None:
    """Write a finished model checkpoint atomically."""
    _save(Path(path), _payload(model, fingerprint, history))


def load_model(path: str | Path, model: nn.Module, fingerprint: dict | None = None) -> History:
    """Load a finished checkpoint into ``model`` (checked) and return its training history."""
    payload = read_checkpoint(path)
    load_into(model, payload, str(path), fingerprint)
    return History.from_dict(payload["history"])


def _evaluate(model: nn.Module, data: dict[str, Tensor], batch_size: int, device: torch.device) -> float:
    model.eval()
    total, count = 0.0, 0
    with torch.no_grad():
        for batch, n in _batches(data, np.arange(_n_rows(data)), max(batch_size, 512), device):
            total += float(model.loss(batch)) * n  # type: ignore[operator]
            count += n
    return total / max(count, 1)


def fit(
    model: nn.Module,
    train: dict[str, Tensor],
    val: dict[str, Tensor],
    cfg: TrainConfig,
    run_dir: str | Path | None = None,
    fingerprint: dict | None = None,
    log_dir: str | Path | None = None,
    progress: bool = True,
    desc: str = "train",
    parameters: list[nn.Parameter] | None = None,
    device: str | None = None,
) -> History:
    """Train ``model`` with Adam and early stopping; return the :class:`History`.

    Parameters
    ----------
    model : nn.Module
        Must define ``loss(batch: dict[str, Tensor]) -> Tensor`` (a mean over the batch).
    train, val : dict of str to Tensor
        Equal-length tensors; a batch is the same rows of each.
    cfg : TrainConfig
        Learning rate, batch size, epoch cap, patience and seed.
    run_dir : path, optional
        Where ``last.pt`` (resumable state, after every epoch) and ``model.pt`` (the finished
        best model) go. A finished ``model.pt`` is loaded instead of training again.
    fingerprint : dict, optional
        What produced the run (stored; a resume or reload with another fingerprint is refused).
    log_dir : path, optional
        TensorBoard event directory.
    parameters : list, optional
        Only these are optimised (e.g. a reward net on a frozen encoder); default: all.
    device : str, optional
        Where to train (:func:`husky_course.device.resolve_device`; default ``$HUSKY_DEVICE`` or
        ``auto``). The data stay on the CPU and travel a batch at a time; the model ends on the
        CPU, and checkpoints hold CPU tensors.
    """
    if cfg.epochs < 1 or cfg.batch_size < 1 or cfg.lr <= 0 or cfg.patience < 1:
        raise ValueError(f"invalid training config {cfg}")
    if not hasattr(model, "loss"):
        raise TypeError(f"{type(model).__name__} has no loss(batch) method")
    fingerprint = {**(fingerprint or {}), "train": asdict(cfg)}
    run = Path(run_dir) if run_dir is not None else None
    if run is not None and (run / "model.pt").is_file():
        return load_model(run / "model.pt", model, fingerprint)
    dev = resolve_device(device)
    n_train = _n_rows(train)
    _n_rows(val)
    if run is not None:
        run.mkdir(parents=True, exist_ok=True)

    model.to(dev)  # parameters move in place: ``parameters`` (if given) still names them
    params = parameters if parameters is not None else [p for p in model.parameters() if p.requires_grad]
    optim = torch.optim.Adam(params, lr=cfg.lr, weight_decay=cfg.weight_decay, fused=True)
    hist, start, best_state, bad_epochs = History(), 0, None, 0
    if run is not None and (run / "last.pt").is_file():
        state = read_checkpoint(run / "last.pt")
        load_into(model, state, str(run / "last.pt"), fingerprint)
        optim.load_state_dict(state["optimizer"])  # its tensors follow the parameters' device
        hist = History.from_dict(state["history"])
        start, bad_epochs, best_state = state["epoch"] + 1, state["bad_epochs"], state["best_state"]

    writer = None
    if log_dir is not None:
        from torch.utils.tensorboard import SummaryWriter  # imported lazily: slow and optional

        writer = SummaryWriter(str(log_dir), purge_step=start)
    t0 = time.perf_counter() - hist.seconds
    bar = tqdm(range(start, cfg.epochs), desc=desc, disable=not progress, leave=False)
    for epoch in bar:
        model.train()
        order = np.random.default_rng([cfg.seed, epoch]).permutation(n_train)
        total = 0.0
        for batch, n in _batches(train, order, cfg.batch_size, dev):
            optim.zero_grad(set_to_none=True)
            loss = model.loss(batch)  # type: ignore[operator]
            if not torch.isfinite(loss):
                raise FloatingPointError(f"{desc}: loss became {float(loss)} at epoch {epoch}")
            loss.backward()
            optim.step()
            total += float(loss.detach()) * n
        hist.train_loss.append(total / n_train)
        hist.val_loss.append(_evaluate(model, val, cfg.batch_size, dev))
        if hist.val_loss[-1] < hist.best_val - cfg.min_delta:
            hist.best_val, hist.best_epoch, bad_epochs = hist.val_loss[-1], epoch, 0
            best_state = _cpu_state(model)
        else:
            bad_epochs += 1
        hist.seconds = time.perf_counter() - t0
        if writer is not None:
            writer.add_scalar("loss/train", hist.train_loss[-1], epoch)
            writer.add_scalar("loss/validation", hist.val_loss[-1], epoch)
        bar.set_postfix(train=f"{hist.train_loss[-1]:.4f}", val=f"{hist.val_loss[-1]:.4f}")
        stop = bad_epochs >= cfg.patience
        hist.stopped_early = stop
        if run is not None:
            _save(
                run / "last.pt",
                _payload(
                    model,
                    fingerprint,
                    hist,
                    optimizer=optim.state_dict(),
                    epoch=epoch,
                    bad_epochs=bad_epochs,
                    best_state=best_state,
                ),
            )
        if stop:
            break
    bar.close()
    if writer is not None:
        writer.close()
    model.to("cpu")  # planners decide on the CPU; batched inference moves it where it runs
    if best_state is not None:
        model.load_state_dict(best_state)
    model.eval()
    if run is not None:
        save_model(run / "model.pt", model, fingerprint, hist)
        (run / "last.pt").unlink(missing_ok=True)
    return hist
