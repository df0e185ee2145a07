"""The paper's training pipelines as artifacts: ``get_*`` builds (or loads), ``load_*`` only loads.

* ``encoder_decoder`` -- Fig. 3: image t + primitive -> image t+1, collision-free pairs;
* ``reward_net`` -- Fig. 4: the reward net on the frozen encoder's latents, trained on the
  reward set (all unsafe + half of the safe images) exactly as the paper did;
* ``safety_image`` / ``safety_prim`` -- a CNN trained end to end on safety alone (chapter 4's
  control), without and with the primitive;
* ``joint`` -- Fig. 9: encoder, decoder and a primitive-conditioned safety head trained together;
* ``rnn`` -- Fig. 10: the RNN look-ahead, trained on every prefix of every video;
* ``distilled`` -- the oracle distilled into a network, from the simulator's survival labels.

A checkpoint lives at ``artifacts/<profile>/models/<name>-<hash>/model.pt``, the hash taken over
its *fingerprint*: the model's spec, the dataset's content hash, the training config, the code that
trains it (:func:`code_fingerprint` of the model's module, the trainer, the data preparation and
this module's own statements: :func:`model_code`) and, where one model builds on another (or on
the survival labels), the other's fingerprint (never a path). A changed label function is a new
labels key, hence a new ``distilled`` key; a docstring changes none. ``get_<name>`` trains only
when no finished checkpoint has the same fingerprint; :func:`load` never trains and never
collects, and a missing checkpoint is a :class:`~husky_course.training.trainer.CheckpointError`
naming the command that builds it. Training is seeded and logs to ``runs/<profile>/...`` for
TensorBoard.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch
from torch import Tensor, nn

from ..config import Profile, TrainConfig, check_profile, config_hash, to_dict, world_flag
from ..data.code import code_fingerprint, module_fingerprint
from ..data.dataset import Dataset
from ..data.io import DatasetError, atomic_save_npy, load_npy
from ..data.labels import survival_steps_parallel
from ..data.splits import encoder_decoder_pairs, reward_set, split_all
from ..data.store import dataset_dir, dataset_id, get_dataset, model_dir, runs_dir, stored_dataset_id
from ..models.paper import EncoderDecoder, LatentRewardNet
from ..models.rnn import RNNLookahead
from ..models.safety import JointModel, SafetyNet, SurvivalNet
from ..progress import announce_build
from .datasets import (
    images_tensor,
    joint_data,
    pair_data,
    reward_data,
    safety_data,
    sequence_data,
    survival_data,
)
from .inference import encode
from .trainer import CheckpointError, History, fit, load_model

#: every model ``get``/``load`` know, in the order the chapters need them
MODELS = ("encoder_decoder", "reward_net", "safety_image", "safety_prim", "joint", "rnn", "distilled")

Data = tuple[dict[str, Tensor], dict[str, Tensor]]

#: what trains every model here: the loop, the tensors, the splits (with their imports)
TRAINING_CODE = (
    "husky_course.training.trainer", "husky_course.training.datasets", "husky_course.data.splits"
)
#: what computes the survival labels (the ``labels`` artifact)
LABELS_CODE = ("husky_course.data.labels",)


def model_code(model: nn.Module, *more: str) -> dict:
    """The code part of a model's fingerprint: the model's module, :data:`TRAINING_CODE` and ``more``
    (with their imports), and this module's own statements (its imports not followed: they are the
    other models')."""
    return {"code": code_fingerprint(type(model).__module__, *TRAINING_CODE, *more),
            "pipeline": module_fingerprint(__name__)}


@dataclass
class Trained:
    """A trained model, the history of the run that made it, its checkpoint and its fingerprint."""

    model: nn.Module
    history: History
    path: str
    fingerprint: dict


def _parts(
    name: str, profile: Profile, ds_id: str, safety_weight: float = 1.0
) -> tuple[nn.Module, TrainConfig, dict]:
    """A fresh, seeded model of ``name``, its training config and its fingerprint."""
    plan, dims, sizes = profile.train, profile.dims, profile.model
    extra: dict = {}
    more: tuple[str, ...] = ()
    make: Callable[[], nn.Module]
    if name == "encoder_decoder":
        cfg, make = plan.encoder_decoder, lambda: EncoderDecoder(dims)
    elif name == "reward_net":
        cfg, make = plan.reward_net, lambda: LatentRewardNet(dims)
        extra = {"encoder": config_hash(_parts("encoder_decoder", profile, ds_id)[2])}
        more = ("husky_course.training.inference",)  # it trains on the encoder's latents
    elif name in ("safety_image", "safety_prim"):
        cfg, make = plan.joint, lambda: SafetyNet(name == "safety_prim", dims)
    elif name == "joint":
        cfg, make, extra = plan.joint, lambda: JointModel(safety_weight, dims), {"w": safety_weight}
    elif name == "rnn":
        cfg, make, extra = plan.rnn, lambda: RNNLookahead(dims), {"h": sizes.rnn_horizon}
    elif name == "distilled":
        labels = config_hash(labels_key(profile, ds_id))  # new labels, a new model
        cfg, extra = plan.distilled, {"h": sizes.distill_horizon, "labels": labels}
        make = lambda: SurvivalNet(sizes.distill_horizon, dims)  # noqa: E731
    else:
        raise ValueError(f"unknown model {name!r}: choose one of {', '.join(MODELS)}")
    torch.manual_seed(cfg.seed)  # the initial weights depend on the seed alone
    model = make()
    fingerprint = {"model": model.spec.to_dict(), "dataset": ds_id, "train": asdict(cfg),  # type: ignore[union-attr]
                   **model_code(model, *more), **extra}
    return model, cfg, fingerprint


def _checkpoint(name: str, fingerprint: dict, profile: Profile):
    return model_dir(name, fingerprint, profile) / "model.pt"


def checkpoint_dir(name: str, profile: Profile, ds_id: str, safety_weight: float = 1.0) -> Path:
    """The directory today's code and ``profile`` give model ``name`` trained on dataset ``ds_id``."""
    return model_dir(name, _parts(name, profile, ds_id, safety_weight)[2], profile)


def load(name: str, profile: Profile, safety_weight: float = 1.0) -> Trained:
    """The trained model ``name`` of ``profile``; never collects or trains.

    Raises
    ------
    CheckpointError
        When the checkpoint (or the dataset it was trained on) is missing; the message names the
        command that builds it.
    """
    profile = check_profile(profile)  # a name or anything else: the clear ConfigError, not an AttributeError
    try:
        ds_id = stored_dataset_id(profile)
    except DatasetError as exc:
        if (dataset_dir(profile) / "meta.json").is_file():
            raise  # damaged: its own message says what to do
        raise CheckpointError(
            f"no trained {name} model for profile {profile.name!r}: its dataset is missing; train it with "
            f"`python -m husky_course train {name} "
            f"--profile {profile.name}{world_flag(profile.sim)}`"
        ) from exc
    model, _, fingerprint = _parts(name, profile, ds_id, safety_weight)
    path = _checkpoint(name, fingerprint, profile)
    if not path.is_file():
        raise CheckpointError(
            f"no trained {name} model for profile {profile.name!r} (expected {path}); "
            f"train it with `python -m husky_course train {name} "
            f"--profile {profile.name}{world_flag(profile.sim)}`"
        )
    return Trained(model, load_model(path, model, fingerprint), str(path), fingerprint)


def _build(
    name: str,
    profile: Profile,
    ds: Dataset,
    data: Callable[[], Data],
    progress: bool,
    safety_weight: float = 1.0,
    prepare: Callable[[nn.Module], None] | None = None,
) -> Trained:
    """Load ``name`` if its checkpoint exists, else build its data and train it."""
    model, cfg, fingerprint = _parts(name, profile, dataset_id(ds), safety_weight)
    run = model_dir(name, fingerprint, profile)
    path = run / "model.pt"
    if path.is_file():
        return Trained(model, load_model(path, model, fingerprint), str(path), fingerprint)
    announce_build(name, profile.name, f"train {name}{world_flag(profile.sim)}")
    train, val = data()
    if prepare is not None:
        prepare(model)
    history = fit(
        model,
        train,
        val,
        cfg,
        run_dir=run,
        fingerprint=fingerprint,
        log_dir=runs_dir(name, fingerprint, profile),
        progress=progress,
        desc=name,
    )
    return Trained(model, history, str(run / "model.pt"), fingerprint)


def get_encoder_decoder(profile: Profile, progress: bool = True) -> Trained:
    """The first pipeline, trained (or loaded) for the profile's dataset."""
    ds = get_dataset(profile, progress=progress)

    def data() -> Data:
        split = encoder_decoder_pairs(ds, profile.data.seed, profile.data.val_fraction)
        return pair_data(ds, split.train_t), pair_data(ds, split.val_t)

    return _build("encoder_decoder", profile, ds, data, progress)


def get_reward_net(profile: Profile, progress: bool = True) -> tuple[Trained, Trained]:
    """The second pipeline: ``(encoder_decoder, reward_net)``, the reward net on frozen latents.

    The paper's settings: batch 16, lr 1e-3, BCE on the softmax pair (Section 4.2).
    """
    ed = get_encoder_decoder(profile, progress)
    ds = get_dataset(profile, progress=False)

    def data() -> Data:
        latents = encode(ed.model.encoder, images_tensor(ds))  # type: ignore[union-attr]
        d = profile.data
        split = reward_set(ds, d.seed, d.reward_safe_fraction, d.val_fraction)
        return reward_data(ds, split.train, latents), reward_data(ds, split.val, latents)

    return ed, _build("reward_net", profile, ds, data, progress)


def get_safety_net(with_primitive: bool, profile: Profile, progress: bool = True) -> Trained:
    """A :class:`~husky_course.models.safety.SafetyNet` trained end to end on the reward set."""
    ds = get_dataset(profile, progress=progress)

    def data() -> Data:
        d = profile.data
        split = reward_set(ds, d.seed, d.reward_safe_fraction, d.val_fraction)
        return safety_data(ds, split.train), safety_data(ds, split.val)

    return _build("safety_prim" if with_primitive else "safety_image", profile, ds, data, progress)


def get_joint(profile: Profile, progress: bool = True, safety_weight: float = 1.0) -> Trained:
    """The joint model (Fig. 9) trained on every image of the training videos."""
    ds = get_dataset(profile, progress=progress)

    def data() -> Data:
        tr, va = split_all(ds, profile.data.seed, profile.data.val_fraction)
        return joint_data(ds, tr), joint_data(ds, va)

    return _build("joint", profile, ds, data, progress, safety_weight=safety_weight)


def get_rnn(profile: Profile, progress: bool = True) -> Trained:
    """The RNN look-ahead (Fig. 10), trained on sequences starting at every training image."""
    ds = get_dataset(profile, progress=progress)
    horizon = profile.model.rnn_horizon

    def data() -> Data:
        tr, va = split_all(ds, profile.data.seed, profile.data.val_fraction)
        return sequence_data(ds, tr, horizon), sequence_data(ds, va, horizon)

    def bank(model: nn.Module) -> None:
        model.bank = images_tensor(ds)  # type: ignore[assignment]

    trained = _build("rnn", profile, ds, data, progress, prepare=bank)
    trained.model.bank = None  # type: ignore[assignment]
    return trained


def labels_key(profile: Profile, ds_id: str) -> dict:
    """What determines the survival labels: the dataset's content, the horizon, the simulator and the
    code that computes them (:data:`LABELS_CODE` and its imports)."""
    return {"dataset": ds_id, "survival_h": profile.model.distill_horizon, "sim": to_dict(profile.sim),
            "code": code_fingerprint(*LABELS_CODE)}


def labels_dir(profile: Profile, ds_id: str) -> Path:
    """Directory of the survival labels of the dataset ``ds_id`` (it may not exist yet)."""
    return model_dir("labels", labels_key(profile, ds_id), profile)


def _labels_path(profile: Profile, ds_id: str) -> Path:
    return labels_dir(profile, ds_id) / "survival.npy"


def get_survival_labels(profile: Profile, progress: bool = True) -> np.ndarray:
    """Simulator survival labels ``(N, n_primitives)`` for every pool image (built if missing).

    Horizon ``profile.model.distill_horizon``; cached as an artifact keyed by :func:`labels_key`;
    computed by 2 worker processes.
    """
    ds = get_dataset(profile, progress=progress)
    path = _labels_path(profile, dataset_id(ds))
    if path.is_file():
        return load_npy(path)
    announce_build("survival labels", profile.name, "train distilled")
    labels = survival_steps_parallel(
        ds, profile.model.distill_horizon, config=profile.sim, progress=progress
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_save_npy(path, labels)
    return labels


def get_distilled(profile: Profile, progress: bool = True) -> Trained:
    """:class:`~husky_course.models.safety.SurvivalNet` trained on every training image's survival labels."""
    ds = get_dataset(profile, progress=progress)

    def data() -> Data:
        survival = get_survival_labels(profile, progress)
        tr, va = split_all(ds, profile.data.seed, profile.data.val_fraction)
        return survival_data(ds, tr, survival), survival_data(ds, va, survival)

    return _build("distilled", profile, ds, data, progress)


#: ``name -> get_<name>(profile, progress)``, for the CLI's ``train`` command
BUILDERS: dict[str, Callable[[Profile, bool], Trained]] = {
    "encoder_decoder": get_encoder_decoder,
    "reward_net": lambda profile, progress: get_reward_net(profile, progress)[1],
    "safety_image": lambda profile, progress: get_safety_net(False, profile, progress),
    "safety_prim": lambda profile, progress: get_safety_net(True, profile, progress),
    "joint": get_joint,
    "rnn": get_rnn,
    "distilled": get_distilled,
}
