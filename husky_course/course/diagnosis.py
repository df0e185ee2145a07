"""Chapter 4's experiments: why did the paper's reward net fail?

Each candidate cause becomes a measurement:

1. *The latent lacks the depth of nearby obstacles* -> :func:`probe_r2` (how well a small MLP
   recovers the nearest obstacle's distance from the frozen latent vs from the raw image);
2. *The label depends on the primitive* -> :func:`image_only_ceiling` (the best AUC any
   image-only predictor can reach, computed exactly with the simulator) and the end-to-end
   :class:`~husky_course.models.safety.SafetyNet` with and without the primitive;
3. *The encoder never saw a colliding frame* -> :func:`unsafe_frame_errors` (the decoder's error
   on the frames the encoder never trained on, against fresh simulator renders);
4. *The pipeline itself* -> :class:`RewardVariant` / :func:`run_reward_variant`, the reward net
   re-trained with one plausible slip at a time (labels off by one, softmax fed to a loss that
   expects logits, a summed loss, depth in metres, an untrained encoder).

The trained experiments (the variants and the probes) are built once by :func:`get_diagnosis`,
which ``python -m husky_course train diagnosis`` (and ``train all``) calls, and cached as JSON in
the artifact store, so chapter 4 reads them instead of training while it runs.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, replace
from math import comb

import numpy as np
import torch
import torch.nn.functional as F
from torch import Tensor

from ..config import CameraConfig, Profile, SimConfig, TrainConfig, config_hash
from ..data.code import code_fingerprint
from ..data.dataset import Dataset
from ..data.io import atomic_write_bytes
from ..data.labels import nearest_obstacle_distance, primitive_outcomes
from ..data.splits import reward_set
from ..data.store import dataset_id, get_dataset, model_dir
from ..engines import map_tasks
from ..evaluation.metrics import Classification, classification, image_errors, roc_auc
from ..models.base import DEFAULT_DIMS
from ..models.paper import Encoder, LatentRewardNet
from ..models.safety import Probe
from ..progress import announce_build
from ..sim.fast import FastSimulator
from ..training.builders import get_encoder_decoder
from ..training.datasets import images_tensor
from ..training.inference import encode, predict_next
from ..training.trainer import History, fit


@dataclass(frozen=True)
class RewardVariant:
    """One way of running the paper's second pipeline (the defaults are the faithful one)."""

    name: str
    label_shift: bool = False  #: each image gets the *next* image's label (the -1 read one step early)
    softmax_into_ce: bool = False  #: the softmax output is fed to CrossEntropyLoss, which expects logits
    summed_loss: bool = False  #: the batch loss is summed instead of averaged
    depth_in_metres: bool = False  #: images enter the frozen encoder in metres (0-5), not [0, 1]
    random_encoder: bool = False  #: the latent comes from an untrained encoder


WORKERS = 2  #: processes :func:`get_diagnosis` trains in (every result is the same for any number)

VARIANTS = (
    RewardVariant("faithful (ours)"),
    RewardVariant("labels off by one", label_shift=True),
    RewardVariant("softmax into CrossEntropyLoss", softmax_into_ce=True),
    RewardVariant("summed loss", summed_loss=True),
    RewardVariant("depth in metres", depth_in_metres=True),
    RewardVariant("untrained encoder", random_encoder=True),
)


class _VariantNet(LatentRewardNet):
    """The paper's reward net with a switchable loss."""

    def __init__(self, variant: RewardVariant) -> None:
        super().__init__()
        self.variant = variant

    def loss(self, batch: dict[str, Tensor]) -> Tensor:
        y = batch["label"].float()
        if self.variant.softmax_into_ce:
            probs = self.reward(batch["z"])  # softmax output [p, 1 - p] ...
            target = (1 - y).long()  # class 0 = collision, as in the label [1, 0]
            return F.cross_entropy(probs, target, reduction="sum" if self.variant.summed_loss else "mean")
        logit = self.collision_logit(batch["z"])
        return F.binary_cross_entropy_with_logits(
            logit, y, reduction="sum" if self.variant.summed_loss else "mean"
        )

    @torch.no_grad()
    def p_collision(self, z: Tensor) -> np.ndarray:
        """Predicted probability of collision."""
        self.eval()
        return self.reward(z)[:, 0].numpy()


def shifted_labels(ds: Dataset) -> np.ndarray:
    """The off-by-one slip: every image labelled with its successor's label (0 at a video's end)."""
    nxt = np.append(ds.labels[1:], 0)
    same = np.append(ds.episode[1:] == ds.episode[:-1], False)
    return np.where(same, nxt, 0).astype(np.uint8)


@dataclass
class VariantResult:
    """What one variant's run gave on the validation images (true labels)."""

    variant: RewardVariant
    history: History
    quality: Classification

    def row(self) -> dict:
        """A table row."""
        h = self.history
        return {
            "variant": self.variant.name,
            **self.quality.row(),
            "first train loss": h.train_loss[0],
            "last train loss": h.train_loss[-1],
            "val loss change": h.val_loss[-1] - h.val_loss[0],
            "epochs": len(h.train_loss),
        }


def variant_latents(
    variant: RewardVariant,
    encoder: Encoder,
    images: Tensor,
    camera: CameraConfig | None = None,
    seed: int = 0,
) -> np.ndarray:
    """The latents ``(N, latent)`` the reward net of ``variant`` (trained with ``seed``) is trained on."""
    if variant.random_encoder:
        torch.manual_seed(seed + 1)
        encoder = Encoder(replace(DEFAULT_DIMS, image_size=encoder.size, latent=encoder.fc.out_features))
        encoder.eval()
    if variant.depth_in_metres:  # bypasses the [0, 1] input check on purpose: that is the slip
        far = (camera or CameraConfig()).far  # normalised depth x far: metres, give or take `near`
        encoder.eval()
        with torch.no_grad():
            return torch.cat(
                [
                    encoder.unchecked(images[i : i + 2048].float().unsqueeze(1) * far)
                    for i in range(0, len(images), 2048)
                ]
            ).numpy()
    return encode(encoder, images)


def _fit_variant(task: tuple) -> tuple[History, np.ndarray]:
    """One variant's reward net trained on ``(z, label)`` rows: its history and validation p(collision)."""
    variant, z_train, y_train, z_val, y_val, cfg = task
    torch.manual_seed(cfg.seed)
    net = _VariantNet(variant)

    def data(z: np.ndarray, y: np.ndarray) -> dict[str, Tensor]:
        return {"z": torch.from_numpy(z), "label": torch.from_numpy(y.astype(np.float32))}

    hist = fit(net, data(z_train, y_train), data(z_val, y_val), cfg, progress=False, desc=variant.name)
    return hist, net.p_collision(torch.from_numpy(z_val))


def _variant_task(
    variant: RewardVariant, ds: Dataset, train_idx: np.ndarray, val_idx: np.ndarray, z: np.ndarray,
    cfg: TrainConfig,
) -> tuple:
    labels = shifted_labels(ds) if variant.label_shift else ds.labels
    return variant, z[train_idx], labels[train_idx], z[val_idx], labels[val_idx], cfg


def run_reward_variant(
    variant: RewardVariant,
    ds: Dataset,
    train_idx: np.ndarray,
    val_idx: np.ndarray,
    encoder: Encoder,
    cfg: TrainConfig,
    images: Tensor,
    camera: CameraConfig | None = None,
) -> VariantResult:
    """Train the paper's reward net under ``variant``; score it against the *true* labels."""
    z = variant_latents(variant, encoder, images, camera, cfg.seed)
    hist, p = _fit_variant(_variant_task(variant, ds, train_idx, val_idx, z, cfg))
    return VariantResult(variant, hist, classification(ds.labels[val_idx], p))


def probe_r2(
    x_train: np.ndarray, y_train: np.ndarray, x_val: np.ndarray, y_val: np.ndarray, cfg: TrainConfig
) -> float:
    """R^2 on validation of a one-hidden-layer MLP regressing ``y`` on features ``x`` (standardised)."""
    x_train = np.asarray(x_train, np.float32).reshape(len(x_train), -1)
    x_val = np.asarray(x_val, np.float32).reshape(len(x_val), -1)
    mu, sd = x_train.mean(0), x_train.std(0) + 1e-6
    ym, ys = float(y_train.mean()), float(y_train.std() + 1e-9)
    torch.manual_seed(cfg.seed)
    probe = Probe(x_train.shape[1])

    def data(x: np.ndarray, y: np.ndarray) -> dict[str, Tensor]:
        return {
            "x": torch.from_numpy((x - mu) / sd),
            "y": torch.from_numpy(((y - ym) / ys).astype(np.float32)),
        }

    fit(probe, data(x_train, y_train), data(x_val, y_val), cfg, progress=False, desc="probe")
    probe.eval()
    with torch.no_grad():
        pred = probe(torch.from_numpy((x_val - mu) / sd)).numpy() * ys + ym
    return float(1.0 - ((pred - y_val) ** 2).mean() / y_val.var())


def _diagnosis_task(task: tuple) -> object:
    """A probe (``("probe", args)``: its R^2) or a variant (``("variant", args)``: history, p)."""
    kind, args = task
    return probe_r2(*args) if kind == "probe" else _fit_variant(args)


def image_only_ceiling(ds: Dataset, idx: np.ndarray, config: SimConfig | None = None) -> dict[str, float]:
    """The best any image-only safety predictor can do, computed exactly with the simulator.

    An image fixes the robot's situation but not the primitive that will be drawn next. The best
    image-only score is therefore the fraction ``q`` of the 25 primitives that collide from there
    (the exact probability of collision under the random policy). Its AUC against the recorded
    labels is the ceiling; a predictor that also sees the primitive can reach 1.0.
    """
    outcomes = primitive_outcomes(ds, idx, config)
    q = outcomes.mean(1)
    y = ds.labels[idx].astype(bool)
    return {
        "image_only_auc": roc_auc(y, q),
        "image_only_accuracy": float(((q >= 0.5) == y).mean()),
        "with_primitive_auc": roc_auc(y, outcomes[np.arange(len(idx)), ds.applied[idx]]),
    }


def unsafe_frame_errors(
    model: torch.nn.Module, ds: Dataset, n: int = 400, seed: int = 0, config: SimConfig | None = None
) -> dict[str, dict]:
    """Decoder error on frames the encoder trained on (safe) vs never saw (the colliding ones).

    From each sampled frame we apply a primitive that is *safe* from there (the simulator tells us
    which) and render the true next image, so both groups get a fair target.
    """
    rng = np.random.default_rng(seed)
    sim = FastSimulator(config)
    size = sim.config.camera.size
    out = {}
    for name, label in (("safe frames (trained on)", 0), ("colliding frames (never seen)", 1)):
        pool = np.flatnonzero(ds.labels == label)
        idx = np.sort(rng.choice(pool, size=min(n, len(pool)), replace=False))
        ok = ~primitive_outcomes(ds, idx, config)
        keep = ok.any(1)
        idx, ok = idx[keep], ok[keep]
        prims = np.array([rng.choice(np.flatnonzero(row)) for row in ok])
        true = np.empty((len(idx), size, size), np.float32)
        for j, (i, k) in enumerate(zip(idx, prims, strict=True)):
            sim.load(int(ds.world_seeds[ds.episode[i]]))
            end = sim.apply(np.asarray(ds.poses[i], float), int(k)).pose
            true[j] = sim.depth(end[None])[0]
        pred = predict_next(model, ds.images[idx], prims)  # type: ignore[arg-type]
        out[name] = {**image_errors(pred, true, sim.config.camera).row(), "n": len(idx)}
    return out


MIN_AUC = 0.6  #: a classifier with a smaller ROC AUC has not learned (see :func:`failed`)
MIN_MARGIN = 0.02  #: nor one whose accuracy beats the majority-class rate by no more than this


def failed(q: Classification) -> bool:
    """Chapter 4's criterion for a classifier that did not learn: AUC below :data:`MIN_AUC`, or an
    accuracy at most :data:`MIN_MARGIN` above the majority-class rate."""
    return q.auc < MIN_AUC or q.accuracy <= q.majority + MIN_MARGIN


def sign_test(a: np.ndarray, b: np.ndarray) -> tuple[int, int, float]:
    """Exact two-sided sign test of paired outcomes: did ``a`` succeed where ``b`` failed more often
    than the reverse? Returns ``(only_a, only_b, p)``; ``p`` is 1 when no pair differs."""
    a, b = np.asarray(a, bool), np.asarray(b, bool)
    if a.shape != b.shape:
        raise ValueError(f"paired outcomes need equal shapes, got {a.shape} and {b.shape}")
    only_a, only_b = int((a & ~b).sum()), int((b & ~a).sum())
    m, k = only_a + only_b, min(only_a, only_b)
    p = min(1.0, 2 * sum(comb(m, i) for i in range(k + 1)) / 2**m) if m else 1.0
    return only_a, only_b, p


def variant_table(results: list[VariantResult]) -> list[dict]:
    """Rows for a results table, faithful first."""
    return [r.row() for r in results]


@dataclass
class Diagnosis:
    """Chapter 4's trained experiments: the reward-net variants and the probes' R^2."""

    variants: list[VariantResult]
    probes: dict[str, float]  #: feature set -> R^2 for the nearest obstacle's distance

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return {
            "variants": [
                {"variant": asdict(r.variant), "history": r.history.to_dict(), "quality": asdict(r.quality)}
                for r in self.variants
            ],
            "probes": self.probes,
        }

    @classmethod
    def from_dict(cls, data: dict) -> Diagnosis:
        """Inverse of :meth:`to_dict`."""
        variants = [
            VariantResult(
                RewardVariant(**v["variant"]), History.from_dict(v["history"]), Classification(**v["quality"])
            )
            for v in data["variants"]
        ]
        return cls(variants, {k: float(v) for k, v in data["probes"].items()})


def diagnosis_fingerprint(profile: Profile, encoder: str, dataset: str) -> dict:
    """The key of chapter 4's results: the dataset's and the frozen encoder's content keys (never
    paths), both training configs, the variants, and the code that trains and scores them."""
    return {
        "dataset": dataset,
        "encoder": encoder,
        "reward_net": asdict(profile.train.reward_net),
        "probe": asdict(profile.train.probe),
        "variants": [asdict(v) for v in VARIANTS],
        "code": code_fingerprint(__name__),
    }


def get_diagnosis(profile: Profile, progress: bool = True) -> Diagnosis:
    """Chapter 4's variants and probes, trained once and cached as ``results.json``.

    The cache is keyed by :func:`diagnosis_fingerprint`; anything in it changing builds a new entry
    instead of reusing a stale one.
    """
    ed = get_encoder_decoder(profile, progress)
    ds = get_dataset(profile, progress=False)
    fingerprint = diagnosis_fingerprint(profile, config_hash(ed.fingerprint), dataset_id(ds))
    path = model_dir("diagnosis", fingerprint, profile) / "results.json"
    if path.is_file():
        return Diagnosis.from_dict(json.loads(path.read_text()))
    announce_build("diagnosis", profile.name, "train diagnosis")
    rs = reward_set(ds, profile.data.seed, profile.data.reward_safe_fraction, profile.data.val_fraction)
    tr, va = rs.train, rs.val
    images = images_tensor(ds)
    encoder = ed.model.encoder  # type: ignore[union-attr]
    latents = encode(encoder, images)
    dist = nearest_obstacle_distance(ds, config=profile.sim)
    torch.manual_seed(profile.course.random_encoder_seed)
    random_latents = encode(Encoder(profile.dims).eval(), images)
    pixels, latent = profile.dims.image_size**2, profile.dims.latent
    probe_inputs = {
        f"raw image ({pixels:,} pixels)": ds.images,
        f"frozen latent ({latent})": latents,
        f"untrained encoder's latent ({latent})": random_latents,
    }
    cfg = profile.train
    tasks = [("probe", (x[tr], dist[tr], x[va], dist[va], cfg.probe)) for x in probe_inputs.values()]
    for v in VARIANTS:  # the latents here (two threads), the small trainings in the workers
        z = variant_latents(v, encoder, images, profile.sim.camera, cfg.reward_net.seed)
        tasks.append(("variant", _variant_task(v, ds, tr, va, z, cfg.reward_net)))
    # many small runs, each on one torch thread whatever the number of workers: the same numbers
    done = map_tasks(_diagnosis_task, tasks, engine="local", workers=WORKERS, desc="diagnosis",
                     progress=progress)
    probes = dict(zip(probe_inputs, done[: len(probe_inputs)], strict=True))
    variants = [
        VariantResult(v, hist, classification(ds.labels[va], p))
        for v, (hist, p) in zip(VARIANTS, done[len(probe_inputs) :], strict=True)
    ]
    result = Diagnosis(variants, probes)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_bytes(path, json.dumps(result.to_dict(), indent=1).encode())
    return result
