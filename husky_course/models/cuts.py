"""The cut network: where one piece of surface joins two cylinders.

The planner's scan is cut into pieces of surface where the columns' points jump by more than 0.3 m
or two arcs meet at a peak (:func:`~husky_course.planners.pieces.segments`). A cylinder standing
beside another, or partly behind it, often stays joined to it in one piece: the depth step where
their surfaces meet is no larger than the steps within one cylinder's arc at the same range. The
disc network (:mod:`.discs`) then reads one disc for the two, and the map loses the other one.

This network looks at every boundary between two consecutive points of a piece
(:func:`~husky_course.planners.cuts.boundary_features`: the points on either side in the boundary's
own frame, how far the piece's disc leaves each of them, where the boundary lies in the piece) and
gives a logit: the two points lie on different cylinders. It is trained on the same simulated views
as the disc network, labelled by the cylinder each column's ray hits first
(:mod:`husky_course.imitation.cuts`).
"""

from __future__ import annotations

import torch.nn.functional as F
from torch import Tensor, nn

from .base import DEFAULT_DIMS, make_spec, mlp

#: points taken on each side of a boundary
CUT_WINDOW = 6
#: features per boundary: the window's points (2 each) and their offsets from the piece's disc, 6 about
#: the boundary and its piece, 10 about the two parts either side
CUT_FEATURES = 4 * CUT_WINDOW + 2 * CUT_WINDOW + 6 + 10
#: what the features of a boundary are (part of the cut network's artifact key: a change retrains it)
CUT_FEATURE_TEXT = (
    f"{CUT_WINDOW} points each side of the boundary, relative to its midpoint, along and across the ray "
    "through it (x5 per m, 0 past the piece's ends); their offsets from the piece's disc circle (clipped "
    "to 0.5 m, x4); range / far, points left and right of it / window (capped at 1), points / 50, "
    "the disc network reads a cylinder, the piece's largest offset; the two parts either side, each read "
    "by the disc network as a piece: logits (clipped to 10, /5), RMS offsets of each part's points from "
    "its own disc and from the other's (clipped to 0.5 m, x4), the discs' centres apart (capped at 2 m), "
    "radii apart (x4), points per part / 12 (capped at 1)"
)


class CutNet(nn.Module):
    """Boundary features ``(B, CUT_FEATURES)`` -> logit that the boundary separates two cylinders."""

    HIDDEN = (128, 64)

    def __init__(self) -> None:
        super().__init__()
        self.spec = make_spec("cuts", DEFAULT_DIMS, (*self.HIDDEN, CUT_WINDOW))
        self.net = mlp([CUT_FEATURES, *self.HIDDEN, 1])

    def forward(self, features: Tensor) -> Tensor:
        """``(B,)`` logits."""
        return self.net(features.float())[:, 0]

    def loss(self, batch: dict[str, Tensor]) -> Tensor:
        """Binary cross-entropy against ``batch["cut"]`` (the two points hit different cylinders)."""
        return F.binary_cross_entropy_with_logits(self(batch["features"]), batch["cut"].float())
