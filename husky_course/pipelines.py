"""The paper's training pipelines as functions that build or load their checkpoints.

* :func:`get_encoder_decoder` -- Fig. 3: image t + primitive -> image t+1, collision-free pairs;
* :func:`get_reward_net` -- Fig. 4: the reward net on the frozen encoder's latents, trained on the
  reward set (all unsafe + 50 % of the safe images) exactly as the paper did;
* :func:`get_safety_net` -- a CNN trained end to end on safety alone (chapter 4's control);
* :func:`get_joint` -- Fig. 9: encoder, decoder and a primitive-conditioned safety head trained
  together on every image;
* :func:`get_rnn` -- Fig. 10: the RNN look-ahead, trained on every prefix of every video.

Each call trains only if the artifact resolver has no finished checkpoint for the same dataset,
architecture and training config (``artifacts/<profile>/models/<name>-<hash>/model.pt``), so later
chapters reuse what earlier ones trained. Training is seeded (``torch.manual_seed``) and logs to
``runs/<profile>/...`` for TensorBoard.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import torch
from torch import Tensor, nn

from .artifacts import get_dataset, model_dir, runs_dir
from .config import Profile, TrainConfig, config_hash, get_profile
from .dataset import Dataset, encoder_decoder_pairs, reward_set, val_videos
from .models import Encoder, EncoderDecoder, JointModel, LatentRewardNet, SafetyNet
from .training import CheckpointError, History, fit


@dataclass
class Trained:
    """A trained model with the history of the run that made it."""

    model: nn.Module
    history: History
    path: str


def _profile(profile: Profile | str | None) -> Profile:
    return profile if isinstance(profile, Profile) else get_profile(profile)


def dataset_id(ds: Dataset) -> str:
    """A short hash of a dataset's bytes (from the sha256 sums in its ``meta.json``)."""
    return config_hash(ds.meta["sha256"])


_IMAGES: dict[tuple[str, str], Tensor] = {}  # (path, dataset id) -> images; the last two datasets


def images_tensor(ds: Dataset) -> Tensor:
    """All images of ``ds`` as one float16 tensor ``(N, 50, 50)`` (shared, not copied per call)."""
    key = (str(ds.path), dataset_id(ds))
    if key not in _IMAGES:
        if len(_IMAGES) >= 2:
            _IMAGES.pop(next(iter(_IMAGES)))
        _IMAGES[key] = torch.from_numpy(np.asarray(ds.images))
    return _IMAGES[key]


def _train(
    name: str,
    model: nn.Module,
    train: dict[str, Tensor],
    val: dict[str, Tensor],
    cfg: TrainConfig,
    ds: Dataset,
    profile: Profile,
    progress: bool,
    extra: dict | None = None,
    parameters: list[nn.Parameter] | None = None,
    load_only: bool = False,
) -> Trained:
    fingerprint = {
        "model": model.spec.to_dict(),
        "dataset": dataset_id(ds),
        "train": asdict(cfg),
        **(extra or {}),
    }  # type: ignore[union-attr]
    run = model_dir(name, fingerprint, profile)
    if load_only and not (run / "model.pt").is_file():
        raise CheckpointError(
            f"no trained {name} model for profile {profile.name!r} (expected {run / 'model.pt'}); "
            f"train it with `python -m husky_course train {name} --profile {profile.name}`"
        )
    hist = fit(
        model,
        train,
        val,
        cfg,
        run_dir=run,
        fingerprint=fingerprint,
        log_dir=runs_dir(name, fingerprint, profile),
        progress=progress,
        desc=name,
        parameters=parameters,
    )
    return Trained(model, hist, str(run / "model.pt"))


# --- pipeline 1: encoder + decoder ----------------------------------------------------------------
def pair_data(ds: Dataset, t: np.ndarray) -> dict[str, Tensor]:
    """Tensors of the pairs ``(image t, applied primitive, image t+1)`` for pool indices ``t``."""
    images = images_tensor(ds)
    ti = torch.from_numpy(np.asarray(t, np.int64))
    return {
        "image": images[ti],
        "prim": torch.from_numpy(ds.applied[t].astype(np.int64)),
        "next": images[ti + 1],
    }


def get_encoder_decoder(profile: Profile | str | None = None, progress: bool = True) -> Trained:
    """The first pipeline, trained (or loaded) for the profile's dataset."""
    profile = _profile(profile)
    ds = get_dataset(profile, progress=progress)
    split = encoder_decoder_pairs(ds, seed=profile.data.seed)
    cfg = profile.train.encoder_decoder
    torch.manual_seed(cfg.seed)
    model = EncoderDecoder()
    return _train(
        "encoder_decoder",
        model,
        pair_data(ds, split.train_t),
        pair_data(ds, split.val_t),
        cfg,
        ds,
        profile,
        progress,
    )


@torch.no_grad()
def encode(encoder: Encoder, images: Tensor | np.ndarray, batch: int = 2048) -> np.ndarray:
    """Latents ``(N, 15)`` of images (evaluation mode, batched)."""
    encoder.eval()
    images = torch.as_tensor(np.asarray(images)) if not isinstance(images, Tensor) else images
    out = [encoder(images[i : i + batch].float()) for i in range(0, len(images), batch)]
    return torch.cat(out).numpy() if out else np.zeros((0, 15), np.float32)


@torch.no_grad()
def predict_next(
    model: EncoderDecoder | JointModel, images: np.ndarray | Tensor, prims: np.ndarray
) -> np.ndarray:
    """Predicted next images ``(N, 50, 50)`` for images and applied primitives."""
    model.eval()
    images = torch.as_tensor(np.asarray(images)).float()
    prims_t = torch.as_tensor(np.asarray(prims, np.int64))
    out = [
        model.decoder(model.encoder(images[i : i + 2048]), prims_t[i : i + 2048])
        for i in range(0, len(images), 2048)
    ]
    return torch.cat(out).numpy()


# --- pipeline 2: the paper's reward net -----------------------------------------------------------
def reward_data(ds: Dataset, idx: np.ndarray, latents: np.ndarray) -> dict[str, Tensor]:
    """Latents and safety labels of pool indices ``idx`` (``latents`` covers the whole pool)."""
    return {"z": torch.from_numpy(latents[idx]), "label": torch.from_numpy(ds.labels[idx].astype(np.float32))}


def get_reward_net(profile: Profile | str | None = None, progress: bool = True) -> tuple[Trained, Trained]:
    """The second pipeline: ``(encoder_decoder, reward_net)``, the reward net on frozen latents.

    The paper's settings: batch 16, lr 1e-3, BCE on the softmax pair (Section 4.2).
    """
    profile = _profile(profile)
    ed = get_encoder_decoder(profile, progress)
    ds = get_dataset(profile, progress=False)
    latents = encode(ed.model.encoder, images_tensor(ds))  # type: ignore[union-attr]
    split = reward_set(ds, seed=profile.data.seed)
    cfg = profile.train.reward_net
    torch.manual_seed(cfg.seed)
    net = LatentRewardNet()
    trained = _train(
        "reward_net",
        net,
        reward_data(ds, split.train, latents),
        reward_data(ds, split.val, latents),
        cfg,
        ds,
        profile,
        progress,
        extra={"encoder": config_hash({"path": ed.path, "val": ed.history.best_val})},
    )
    return ed, trained


# --- end-to-end safety and the joint model --------------------------------------------------------
def safety_data(ds: Dataset, idx: np.ndarray) -> dict[str, Tensor]:
    """Images, applied primitives and safety labels of pool indices ``idx``."""
    images = images_tensor(ds)
    return {
        "image": images[torch.from_numpy(np.asarray(idx, np.int64))],
        "prim": torch.from_numpy(ds.applied[idx].astype(np.int64)),
        "label": torch.from_numpy(ds.labels[idx].astype(np.float32)),
    }


def get_safety_net(
    with_primitive: bool, profile: Profile | str | None = None, progress: bool = True
) -> Trained:
    """A :class:`~husky_course.models.SafetyNet` trained end to end on the reward set."""
    profile = _profile(profile)
    ds = get_dataset(profile, progress=progress)
    split = reward_set(ds, seed=profile.data.seed)
    cfg = profile.train.joint
    torch.manual_seed(cfg.seed)
    model = SafetyNet(with_primitive)
    name = model.spec.kind
    return _train(
        name, model, safety_data(ds, split.train), safety_data(ds, split.val), cfg, ds, profile, progress
    )


def joint_data(ds: Dataset, idx: np.ndarray) -> dict[str, Tensor]:
    """Every image with its primitive, label and (where one exists) next image."""
    idx = np.asarray(idx, np.int64)
    data = safety_data(ds, idx)
    nxt = np.minimum(idx + 1, len(ds) - 1)
    has_next = (ds.labels[idx] == 0) & (ds.episode[nxt] == ds.episode[idx]) & (idx + 1 < len(ds))
    images = images_tensor(ds)
    data["next"] = images[torch.from_numpy(np.where(has_next, nxt, idx))]
    data["has_next"] = torch.from_numpy(has_next)
    return data


def split_all(ds: Dataset, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Every pool index, split by the shared video split: ``(train, val)``."""
    in_val = val_videos(ds, seed)[ds.episode]
    return np.flatnonzero(~in_val), np.flatnonzero(in_val)


def get_joint(
    profile: Profile | str | None = None,
    progress: bool = True,
    safety_weight: float = 1.0,
    load_only: bool = False,
) -> Trained:
    """The joint model (Fig. 9) trained on every image of the training videos.

    With ``load_only`` a missing checkpoint raises :class:`CheckpointError` instead of training.
    """
    profile = _profile(profile)
    ds = get_dataset(profile, progress=progress)
    cfg = profile.train.joint
    torch.manual_seed(cfg.seed)
    model = JointModel(safety_weight)
    extra = {"w": safety_weight}
    if load_only:
        return _train("joint", model, {}, {}, cfg, ds, profile, False, extra=extra, load_only=True)
    tr, va = split_all(ds, profile.data.seed)
    return _train(
        "joint", model, joint_data(ds, tr), joint_data(ds, va), cfg, ds, profile, progress, extra=extra
    )


@torch.no_grad()
def collision_probs(model: JointModel, images: np.ndarray | Tensor, batch: int = 2048) -> np.ndarray:
    """The joint model's 25 collision probabilities for each image, ``(N, 25)``."""
    model.eval()
    images = torch.as_tensor(np.asarray(images)).float()
    return torch.cat(
        [model.collision_probs(images[i : i + batch]) for i in range(0, len(images), batch)]
    ).numpy()


def get_rnn(profile: Profile | str | None = None, progress: bool = True, load_only: bool = False) -> Trained:
    """The RNN look-ahead (Fig. 10), trained on sequences starting at every training image."""
    from .rnn_model import HORIZON, RNNLookahead, sequence_data

    profile = _profile(profile)
    ds = get_dataset(profile, progress=progress)
    cfg = profile.train.rnn
    torch.manual_seed(cfg.seed)
    model = RNNLookahead()
    extra = {"h": HORIZON}
    if load_only:
        return _train("rnn", model, {}, {}, cfg, ds, profile, False, extra=extra, load_only=True)
    tr, va = split_all(ds, profile.data.seed)
    model.bank = images_tensor(ds)
    try:
        return _train(
            "rnn",
            model,
            sequence_data(ds, tr),
            sequence_data(ds, va),
            cfg,
            ds,
            profile,
            progress,
            extra=extra,
        )
    finally:
        model.bank = None


# --- the oracle distilled ---------------------------------------------------------------------------
DISTILL_HORIZON = 3


def get_survival_labels(profile: Profile | str | None = None, progress: bool = True) -> np.ndarray:
    """Simulator survival labels ``(N, 25)`` (horizon :data:`DISTILL_HORIZON`) for every pool image.

    Cached as an artifact keyed by the dataset and horizon; built with 2 worker processes.
    """
    from .dataset import atomic_save_npy, load_npy
    from .labels import survival_steps_parallel

    profile = _profile(profile)
    ds = get_dataset(profile, progress=progress)
    path = (
        model_dir("labels", {"dataset": dataset_id(ds), "survival_h": DISTILL_HORIZON}, profile)
        / "survival.npy"
    )
    if path.is_file():
        return load_npy(path)
    labels = survival_steps_parallel(ds, DISTILL_HORIZON, config=profile.sim, progress=progress)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_save_npy(path, labels)
    return labels


def get_distilled(
    profile: Profile | str | None = None, progress: bool = True, load_only: bool = False
) -> Trained:
    """:class:`~husky_course.models.SurvivalNet` trained on every training image's survival labels."""
    from .models import SurvivalNet

    profile = _profile(profile)
    ds = get_dataset(profile, progress=progress)
    tr, va = split_all(ds, profile.data.seed)
    cfg = profile.train.distilled
    torch.manual_seed(cfg.seed)
    model = SurvivalNet(DISTILL_HORIZON)
    extra = {"h": DISTILL_HORIZON}
    if load_only:  # no data needed: the checkpoint is loaded (or a clear error raised)
        return _train("distilled", model, {}, {}, cfg, ds, profile, False, extra=extra, load_only=True)
    survival = torch.from_numpy(get_survival_labels(profile, progress))
    images = images_tensor(ds)

    def data(idx: np.ndarray) -> dict[str, Tensor]:
        t = torch.from_numpy(idx)
        return {"image": images[t], "survival": survival[t]}

    return _train("distilled", model, data(tr), data(va), cfg, ds, profile, progress, extra=extra)


@torch.no_grad()
def survival_predictions(model: nn.Module, images: np.ndarray | Tensor, batch: int = 2048) -> np.ndarray:
    """Predicted steps survived ``(N, 25)`` from a :class:`~husky_course.models.SurvivalNet`."""
    model.eval()
    images = torch.as_tensor(np.asarray(images)).float()
    return torch.cat([model.survival(images[i : i + batch]) for i in range(0, len(images), batch)]).numpy()  # type: ignore[operator]
