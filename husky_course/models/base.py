"""What every network shares: sizes from the config, input checks, the spec checkpoints record.

No size is typed here: the image side, the number of primitives and the latent come from the
config (:func:`husky_course.config.model_dims`), and every model takes them as a
:class:`~husky_course.config.ModelDims` (default: the course's).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import torch
from torch import Tensor, nn

from ..config import ModelDims, model_dims

#: the course's sizes (image side, primitives, latent), read from the default config
DEFAULT_DIMS = model_dims()


def encode_primitive(index: Tensor, n_primitives: int) -> Tensor:
    """The decoder's one-number primitive input: index scaled to [-1, 1], shape ``(B, 1)``.

    Primitive ``k`` has lateral offset proportional to ``k - (n - 1) / 2``, so this is the offset
    divided by the library's spread.
    """
    index = torch.as_tensor(index)
    if index.dtype.is_floating_point:
        raise TypeError(f"primitive indices must be integers, got dtype {index.dtype}")
    if index.numel() and (int(index.min()) < 0 or int(index.max()) >= n_primitives):
        raise ValueError(f"primitive indices must be in 0..{n_primitives - 1}")
    return (2.0 * index.float() / (n_primitives - 1) - 1.0).reshape(-1, 1)


def check_images(x: Tensor, size: int) -> Tensor:
    """Return ``x`` as ``(B, 1, size, size)`` float32, or raise ``ValueError`` naming the problem."""
    if not isinstance(x, Tensor):
        raise TypeError(f"expected a torch.Tensor of depth images, got {type(x).__name__}")
    if x.dim() == 3:
        x = x.unsqueeze(1)
    if x.dim() != 4 or tuple(x.shape[1:]) != (1, size, size):
        want = f"(B, {size}, {size}) or (B, 1, {size}, {size})"
        raise ValueError(f"depth images must have shape {want}, got {tuple(x.shape)}")
    if not x.dtype.is_floating_point:
        raise ValueError(f"depth images must be floating point in [0, 1], got dtype {x.dtype}")
    if x.numel():
        lo_t, hi_t = torch.aminmax(x)  # one pass; NaN propagates into both
        lo, hi = float(lo_t), float(hi_t)
        if not (lo >= 0.0 and hi <= 1.0):
            if not bool(torch.isfinite(x).all()):
                raise ValueError("depth images contain NaN or inf values")
            raise ValueError(f"depth images must be normalised to [0, 1], got values in [{lo:.3g}, {hi:.3g}]")
    return x.float()


@dataclass(frozen=True)
class ModelSpec:
    """What identifies an architecture: checkpoints record it and refuse a mismatch."""

    kind: str
    latent: int = DEFAULT_DIMS.latent
    n_primitives: int = DEFAULT_DIMS.n_primitives
    hidden: tuple[int, ...] = ()

    def to_dict(self) -> dict:
        """JSON-ready form (stored inside checkpoints)."""
        data = asdict(self)
        data["hidden"] = list(self.hidden)
        return data


def make_spec(kind: str, dims: ModelDims, hidden: tuple[int, ...]) -> ModelSpec:
    """The spec of a model of ``kind`` built with ``dims`` and hidden widths ``hidden``."""
    return ModelSpec(kind, dims.latent, dims.n_primitives, hidden)


def mlp(widths: list[int]) -> nn.Sequential:
    """Linear layers with ELU between them (none after the last)."""
    layers: list[nn.Module] = []
    for i, (a, b) in enumerate(zip(widths[:-1], widths[1:], strict=True)):
        layers.append(nn.Linear(a, b))
        if i < len(widths) - 2:
            layers.append(nn.ELU())
    return nn.Sequential(*layers)


class NumpyMLP:
    """An :func:`mlp`'s forward pass in numpy, for planners that decide without a torch call.

    It holds copies of the weights, never views: a process pool moves a pickled module's storage to
    shared memory, which would leave a view of the old storage pointing at freed memory.
    """

    def __init__(self, net: nn.Sequential) -> None:
        linears = [m for m in net if isinstance(m, nn.Linear)]
        self.layers = [(m.weight.detach().cpu().numpy().T.astype(np.float64),
                        m.bias.detach().cpu().numpy().astype(np.float64)) for m in linears]

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """The last layer's outputs ``(B, out)`` for inputs ``x (B, in)`` (float64)."""
        for i, (w, b) in enumerate(self.layers):
            x = x @ w + b
            if i < len(self.layers) - 1:
                x = np.where(x > 0, x, np.expm1(np.minimum(x, 0)))
        return x


def count_parameters(module: nn.Module) -> int:
    """Number of trainable parameters."""
    return sum(p.numel() for p in module.parameters() if p.requires_grad)
