"""The disc network: which cylinder stands behind a piece of surface the depth camera glimpsed.

A depth scan shows a cylinder as an arc of points: its front, often cut by the edge of the view
or by a nearer cylinder, sampled by a handful of columns. The classical mapping planner keeps those
points as they are; chapter 8 measures that a planner which knows the whole cylinder behind every
arc it has seen does better. This network reads one piece of surface
(:meth:`husky_course.planners.discs.PieceReader.features`: its points resampled to a fixed number, in a
frame that looks from the camera at the piece, and how the piece lies in the image) and predicts

* whether it is part of a cylinder (a logit; otherwise a stretch of wall), and
* the cylinder's centre (offsets along and across the camera's ray through the piece) and radius,

trained on pieces of simulated scans labelled with the cylinder each column hit
(:mod:`husky_course.imitation.discs`). A planner then searches over the predicted discs exactly as
the mapping planner searches over its points: a learned model plus a search, the paper's own
structure.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from .base import DEFAULT_DIMS, make_spec, mlp

#: points a piece is resampled to; global features per piece (range, columns, edges, bearing, beside it)
PIECE_POINTS, PIECE_GLOBALS = 16, 9
#: what the features of a piece are (part of the disc network's artifact key: a change retrains it)
PIECE_FEATURES = (
    "pieces: segments(gap 0.3 m, 1.5 columns' spacing) of the seen columns; features: 16 points "
    "resampled along the columns, relative to the mean, in the (ray, across) frame from the camera; "
    "range / far, columns / size, touches the left edge, touches the right edge, bearing / half fov; "
    "per end: the column beside it sees nothing, its depth minus the end's / far (an occluder: < 0)"
)


class DiscNet(nn.Module):
    """Piece features ``(B, 2 * PIECE_POINTS + PIECE_GLOBALS)`` -> cylinder logit, centre offsets, radius."""

    HIDDEN = (128, 128, 64)

    def __init__(self, radius_range: tuple[float, float]) -> None:
        super().__init__()
        self.spec = make_spec("discs", DEFAULT_DIMS, (*self.HIDDEN, PIECE_POINTS, PIECE_GLOBALS))
        self.net = mlp([2 * PIECE_POINTS + PIECE_GLOBALS, *self.HIDDEN, 4])
        lo, hi = (float(r) for r in radius_range)
        self.register_buffer("radius_lo", torch.tensor(lo), persistent=False)
        self.register_buffer("radius_span", torch.tensor(hi - lo), persistent=False)

    def forward(self, features: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        """``(logit (B,), centre offsets (B, 2) along and across the ray, radius (B,))``.

        The radius is squashed into the course's radius range (a cylinder is never outside it).
        """
        out = self.net(features.float())
        radius = self.radius_lo + self.radius_span * torch.sigmoid(out[:, 3])
        return out[:, 0], out[:, 1:3], radius

    def loss(self, batch: dict[str, Tensor]) -> Tensor:
        """BCE on "is a cylinder", plus, on cylinders only, Huber losses on the centre and the radius (m)."""
        logit, centre, radius = self(batch["features"])
        is_cyl = batch["cylinder"].float()
        loss = F.binary_cross_entropy_with_logits(logit, is_cyl)
        err = F.smooth_l1_loss(centre, batch["centre"].float(), reduction="none", beta=0.05).sum(1)
        err = err + F.smooth_l1_loss(radius, batch["radius"].float(), reduction="none", beta=0.05)
        return loss + 10.0 * (err * is_cyl).sum() / is_cyl.sum().clamp(min=1.0)
