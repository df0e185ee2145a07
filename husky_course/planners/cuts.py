"""Pieces cut again where the cut network says two cylinders meet (chapters 8 and 10).

The tracker's cut (:func:`~husky_course.planners.pieces.segments`: gaps of 0.3 m, two arcs' peak)
leaves a cylinder standing beside another, or partly behind it, joined to it in one piece; the disc
network then reads one disc for the two, and the map loses the other. In random views of training
worlds, 7% of the pieces that hit a cylinder join two, and the depth step where they meet is no
larger than the steps within one cylinder's arc at the same range. Priced with a privileged shadow
(``benchmarks/exp_moving_memory.py``'s rule ``j``: every piece cut where two cylinders' columns meet,
each part read by the disc network as it is), such joins cost the moving disc planner 25 of its 151
fatal choices on tuning worlds 0-999 (126, p = 0.002): as much as every cylinder its memory loses.

:class:`~husky_course.models.cuts.CutNet` reads every boundary between two consecutive points of a
piece (:func:`cut_features`: the points on either side in the boundary's frame and how far the
piece's disc leaves each; the disc network's read of the two parts either side, each as a piece of
its own); :class:`PieceCutter` cuts the pieces where its probability passes ``DiscConfig.cut``, and
the disc network reads each part (:meth:`~husky_course.planners.discs.DiscMap.pieces`). Nothing
privileged: the image's points and the disc network's own reads. Throwaway prototypes, judged from
the same states (``benchmarks/exp_moving_paired.py``, full profile, moving tuning worlds 0-999, 151
fatal choices of the planner without a cut; a prototype's fatal choices, only its own / only the
planner's): the window of points alone (trained on 1,500 worlds; at the boundary level, 0.72
precision and 0.54 recall at 0.5) at 0.3 / 0.5 / 0.7, 144 (30 / 37) / 146 (29 / 34) / 145 (21 / 27);
with the two parts' reads (0.77 / 0.60) at 0.3 / 0.5, 141 (24 / 34) / 144 (24 / 31). Privileged
hybrids of the first at 0.5 split the gap: its cuts kept only where two cylinders do meet, 140; every
place they meet cut, and its wrong cuts too, 131. Most of what the learned cut leaves is missed
joins, most of them one column of a cylinder beside another's piece.

The network this module runs is trained on the disc network's own views (3,000 training worlds in the
full profile). At the boundary level, on views of 200 worlds no training uses, it cuts with precision
0.74 / 0.85 / 0.94 and recall 0.73 / 0.61 / 0.48 at 0.3 / 0.5 / 0.7. At 0.3 (``DiscConfig.cut``, the
prototypes' best), from the same states on moving tuning worlds 0-1,999 (17,853 winnable decisions),
the planner with it made 290 fatal choices and the planner without it 335 (43 only with it, 88 only
without; p < 0.001); as a planner it crossed 0.833 of those worlds (without it: 0.828 and 0.826 of
their two halves). On the static course, as episodes on 2,000 tuning worlds (evaluation set 1), it
crossed 0.949 against 0.951 without (3 worlds won only with it, 7 only without) at twice the time
per decision: the static disc planner does without it.

Neither more cuts nor more data helped it further (the same states, worlds 0-999, where it made 148
fatal choices): at threshold 0.1 / 0.2 it made 160 (25 only it / 13 only at 0.3) / 152 (10 / 6). A
throwaway net trained on three times the worlds (the 3,000 views and 6,000 more of the same seed; on
the 200 held-out worlds its average precision rose from 0.807 to 0.847, recall at 0.3 from 0.73 to
0.79 at 0.75 precision) made 152 (13 / 9) at 0.3 and 154 (19 / 13) at 0.5: a better cut at the
boundary level no longer changes the planner's fatal choices that can be shown.
"""

from __future__ import annotations

import numpy as np

from ..models.base import NumpyMLP
from ..models.cuts import CUT_FEATURES, CUT_WINDOW, CutNet


def boundary_features(
    pts: np.ndarray, pieces: list[np.ndarray], discs: np.ndarray, cylinder: np.ndarray, far: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(features (b, CUT_FEATURES), piece (b,), position (b,))`` of every boundary of an image's
    pieces: boundary ``k`` of a piece lies between its points ``k`` and ``k + 1``.

    ``pts (m, 2)`` are the image's robot-frame points, ``pieces`` index arrays into them (as
    :meth:`~husky_course.planners.discs.PieceReader.pieces` gives them), ``discs (n, 3)`` and
    ``cylinder (n,)`` the disc network's read of each piece, ``far`` the camera's far plane. The
    features: :data:`~husky_course.models.cuts.CUT_FEATURE_TEXT`.
    """
    w = CUT_WINDOW
    count = np.array([len(i) for i in pieces], int)
    if not len(pieces) or count.max() < 2:
        return np.empty((0, CUT_FEATURES), np.float32), np.empty(0, int), np.empty(0, int)
    sel = np.concatenate(pieces)
    p = pts[sel]
    owner = np.repeat(np.arange(len(pieces)), count)
    pos = np.arange(len(sel)) - np.r_[0, np.cumsum(count)[:-1]][owner]
    off = np.clip(np.hypot(*(p - discs[owner, :2]).T) - discs[owner, 2], -0.5, 0.5) * 4
    worst = np.zeros(len(pieces))
    np.maximum.at(worst, owner, np.abs(off))
    b = np.flatnonzero(pos[:-1] + 1 < count[owner[:-1]])  # each boundary's left point (global index)
    piece, at = owner[b], pos[b]
    n = count[piece]
    mid = (p[b] + p[b + 1]) / 2
    ray = mid / np.maximum(np.hypot(mid[:, 0], mid[:, 1]), 1e-9)[:, None]
    across = np.stack([-ray[:, 1], ray[:, 0]], 1)
    steps = np.arange(-w + 1, w + 1)
    inside = (at[:, None] + steps >= 0) & (at[:, None] + steps < n[:, None])
    g = np.where(inside, b[:, None] + steps, 0)
    q = (p[g] - mid[:, None]) * 5
    along = np.where(inside, (q * ray[:, None]).sum(-1), 0.0)
    side = np.where(inside, (q * across[:, None]).sum(-1), 0.0)
    glob = np.stack([np.hypot(mid[:, 0], mid[:, 1]) / far, np.minimum(at + 1, w) / w,
                     np.minimum(n - at - 1, w) / w, n / 50, cylinder[piece].astype(float), worst[piece]], 1)
    feats = np.concatenate([np.stack([along, side], -1).reshape(len(b), -1),
                            np.where(inside, off[g], 0.0), glob], 1)
    return feats.astype(np.float32), piece, at


def part_features(reader, pts: np.ndarray, cols: np.ndarray, d: np.ndarray, pieces: list[np.ndarray],
                  piece: np.ndarray, at: np.ndarray) -> np.ndarray:
    """``(b, 10)``: per boundary (``piece``, ``at`` from :func:`boundary_features`), the disc network's
    read of the two parts of its piece either side of it, each read as a piece of its own: their cylinder
    logits, how far each part's points lie from its own disc and from the other part's (RMS), how far
    apart the two discs' centres are, their radii's difference, the parts' sizes; ``reader`` is a
    :class:`~husky_course.planners.discs.DiscMap` (its piece reader and network)."""
    parts = [part for k, i in zip(piece, at, strict=True) for part in (pieces[k][: i + 1], pieces[k][i + 1:])]
    feats, frames = reader.reader.features_all(pts, cols, d, parts)
    logit, offset, radius = reader.forward(feats)
    centre = frames[:, 0] + offset[:, :1] * frames[:, 1] + offset[:, 1:] * frames[:, 2]
    count = np.array([len(i) for i in parts])
    starts = np.r_[0, np.cumsum(count)[:-1]]
    p = pts[np.concatenate(parts)]
    owner = np.repeat(np.arange(len(parts)), count)
    other = owner ^ 1  # the part on the boundary's other side

    def rms(of: np.ndarray) -> np.ndarray:
        gap = np.hypot(*(p - centre[of]).T) - radius[of]
        return np.minimum(np.sqrt(np.add.reduceat(gap**2, starts) / count), 0.5) * 4

    own, cross = rms(owner), rms(other)
    a, b = slice(0, None, 2), slice(1, None, 2)
    logit = np.clip(logit, -10, 10) / 5
    return np.stack([logit[a], logit[b], own[a], own[b], cross[a], cross[b],
                     np.minimum(np.hypot(*(centre[a] - centre[b]).T), 2.0), np.abs(radius[a] - radius[b]) * 4,
                     np.minimum(count[a], 12) / 12, np.minimum(count[b], 12) / 12], 1)


def cut_features(reader, d: np.ndarray, cols: np.ndarray, pts: np.ndarray,
                 pieces: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(features (b, CUT_FEATURES), piece (b,), position (b,))`` of every boundary of an image's
    pieces: :func:`boundary_features` then :func:`part_features`, read by ``reader`` (a
    :class:`~husky_course.planners.discs.DiscMap`) from the image's per-column depth ``d``, its seen
    columns ``cols``, their points ``pts`` and its ``pieces``."""
    discs, cylinder, _ = reader.decode(d, cols, pts, pieces)
    feats, piece, at = boundary_features(pts, pieces, discs, cylinder, reader.reader.camera.far)
    if not len(feats):
        return np.empty((0, CUT_FEATURES), np.float32), piece, at
    parts = part_features(reader, pts, cols, d, pieces, piece, at)
    return np.concatenate([feats, parts.astype(np.float32)], 1), piece, at


class PieceCutter:
    """The cut network's forward pass in numpy, and the cut it makes (module docstring).

    ``threshold``: the probability above which a boundary is cut.
    """

    def __init__(self, model: CutNet, threshold: float) -> None:
        if not 0.0 < threshold < 1.0:
            raise ValueError(f"the cut threshold is a probability in (0, 1); got {threshold}")
        self.forward = NumpyMLP(model.net)
        self.logit = float(np.log(threshold / (1 - threshold)))

    def __call__(self, reader, d: np.ndarray, cols: np.ndarray, pts: np.ndarray,
                 pieces: list[np.ndarray]) -> list[np.ndarray]:
        """``pieces`` with each cut after every boundary the network cuts (:func:`cut_features`)."""
        feats, piece, at = cut_features(reader, d, cols, pts, pieces)
        if not len(feats):
            return pieces
        cut = self.forward(feats.astype(np.float64))[:, 0] > self.logit
        if not cut.any():
            return pieces
        out: list[np.ndarray] = []
        for k, idx in enumerate(pieces):
            where = at[(piece == k) & cut] + 1
            out += np.split(idx, where) if len(where) else [idx]
        return out
