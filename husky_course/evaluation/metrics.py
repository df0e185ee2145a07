"""Numbers the learning chapters report: classification quality and image-prediction errors.

Everything here is plain numpy (no scikit-learn needed): ROC AUC by ranks, accuracy against the
majority-class rate, reliability (calibration) bins, and the image errors that separate *where*
an obstacle is (which columns it covers) from *how far* it is (its depth in those columns).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config import CameraConfig
from ..sim.camera import horizon_rows

#: a column is "occupied" when its horizon depth is below this (normalised; 0.5 is about 2.5 m,
#: the reach of the next two primitives)
OCCUPIED_BELOW = 0.5


def _check_binary(y: np.ndarray, score: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    y = np.asarray(y)
    if y.dtype.kind == "f" and not np.all(np.isfinite(y)):
        raise ValueError("labels contain NaN or inf")
    y = y.astype(bool).ravel()
    score = np.asarray(score, float).ravel()
    if y.shape != score.shape:
        raise ValueError(f"labels {y.shape} and scores {score.shape} differ in length")
    if not np.all(np.isfinite(score)):
        raise ValueError("scores contain NaN or inf")
    return y, score


def roc_auc(y: np.ndarray, score: np.ndarray) -> float:
    """Area under the ROC curve (probability a random positive outranks a random negative)."""
    y, score = _check_binary(y, score)
    n_pos, n_neg = int(y.sum()), int((~y).sum())
    if n_pos == 0 or n_neg == 0:
        return float("nan")
    order = np.argsort(score, kind="mergesort")
    ranks = np.empty(len(score))
    sorted_scores = score[order]
    # average ranks for ties
    _, first, counts = np.unique(sorted_scores, return_index=True, return_counts=True)
    avg = first + (counts - 1) / 2.0 + 1.0
    ranks[order] = np.repeat(avg, counts)
    return float((ranks[y].sum() - n_pos * (n_pos + 1) / 2.0) / (n_pos * n_neg))


@dataclass(frozen=True)
class Classification:
    """Quality of collision probabilities ``p`` against labels ``y`` (1 = collision)."""

    auc: float
    accuracy: float
    majority: float  #: accuracy of always predicting the more common class
    n: int

    def row(self) -> dict:
        """A table row."""
        return {"ROC AUC": self.auc, "accuracy": self.accuracy, "majority": self.majority, "n": self.n}


def classification(y: np.ndarray, p: np.ndarray, threshold: float = 0.5) -> Classification:
    """AUC, accuracy at ``threshold`` and the majority-class rate."""
    y, p = _check_binary(y, p)
    rate = float(y.mean()) if len(y) else float("nan")
    return Classification(
        auc=roc_auc(y, p),
        accuracy=float(((p >= threshold) == y).mean()),
        majority=max(rate, 1.0 - rate),
        n=len(y),
    )


def reliability(y: np.ndarray, p: np.ndarray, bins: int = 10) -> dict[str, np.ndarray]:
    """Calibration bins: mean predicted probability, observed frequency and count per bin."""
    y, p = _check_binary(y, p)
    edges = np.linspace(0.0, 1.0, bins + 1)
    which = np.clip(np.digitize(p, edges[1:-1]), 0, bins - 1)
    count = np.bincount(which, minlength=bins)
    with np.errstate(invalid="ignore"):
        mean_p = np.bincount(which, p, bins) / count
        freq = np.bincount(which, y.astype(float), bins) / count
    ece = float(np.nansum(count / max(len(p), 1) * np.abs(mean_p - freq)))
    return {"edges": edges, "mean_p": mean_p, "freq": freq, "count": count, "ece": np.array(ece)}


@dataclass(frozen=True)
class ImageErrors:
    """How a predicted depth image differs from the true one."""

    bce: float  #: mean per-pixel binary cross entropy (the training loss)
    mae: float  #: mean absolute error over all pixels (normalised depth)
    column_iou: float  #: overlap of occupied columns: is the obstacle in the right *place*?
    depth_error_m: (
        float  #: mean |depth error| (m) in columns occupied in both: is it at the right *distance*?
    )
    nearest_error_m: float  #: mean |error| (m) of the nearest surface's distance

    def row(self) -> dict:
        """A table row."""
        return {
            "BCE": self.bce,
            "MAE": self.mae,
            "column IoU": self.column_iou,
            "depth error (m)": self.depth_error_m,
            "nearest error (m)": self.nearest_error_m,
        }


def image_errors(pred: np.ndarray, true: np.ndarray, camera: CameraConfig | None = None) -> ImageErrors:
    """Compare predicted and true normalised depth images ``(B, size, size)``.

    The position/depth split uses the camera's horizon rows
    (:func:`husky_course.sim.camera.horizon_rows`): a column is occupied when its horizon depth is
    below :data:`OCCUPIED_BELOW`. ``column_iou`` compares the occupied columns; ``depth_error_m``
    compares the depths of columns occupied in both images (metres via the camera's near/far).
    """
    camera = camera or CameraConfig()
    pred = np.asarray(pred, np.float64)
    true = np.asarray(true, np.float64)
    if pred.shape != true.shape or pred.ndim != 3:
        raise ValueError(f"expected two (B, H, W) stacks of the same shape, got {pred.shape}, {true.shape}")
    eps = 1e-6
    pc = np.clip(pred, eps, 1 - eps)
    bce = float(-(true * np.log(pc) + (1 - true) * np.log(1 - pc)).mean())
    scale = camera.far - camera.near
    rows = horizon_rows(camera)
    hp, ht = pred[:, rows].mean(1), true[:, rows].mean(1)
    op, ot = hp < OCCUPIED_BELOW, ht < OCCUPIED_BELOW
    union = (op | ot).sum()
    both = op & ot
    return ImageErrors(
        bce=bce,
        mae=float(np.abs(pred - true).mean()),
        column_iou=float((op & ot).sum() / union) if union else float("nan"),
        depth_error_m=float(np.abs(hp - ht)[both].mean() * scale) if both.any() else float("nan"),
        nearest_error_m=float(np.abs(hp.min(1) - ht.min(1)).mean() * scale),
    )
