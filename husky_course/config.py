"""Every number the course depends on, in one place.

The configuration is a tree of frozen dataclasses. ``HUSKY_PROFILE`` (``quick`` or ``full``) is read
here and nowhere else; every size a notebook uses comes from :func:`get_profile`. Geometry conventions:

* world frame: ``x`` forward along the course (the robot starts at ``x = 0`` and has crossed the
  course at ``x = 10``), ``y`` to the robot's left, ``z`` up; units are metres and radians;
* a robot pose is ``(x, y, yaw)``; ``yaw = 0`` faces along ``+x``.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import asdict, dataclass, field, replace

PROFILES = ("quick", "full")
PROFILE_ENV = "HUSKY_PROFILE"

#: World seeds >= this are evaluation worlds: collection refuses them, so no training world is one.
EVAL_SEED_BASE = 2**31


class ConfigError(ValueError):
    """A configuration value, profile or world name that the course cannot use."""


@dataclass(frozen=True)
class WorldConfig:
    """The obstacle course (paper, Section 3.1.1), with the calibrated values we chose.

    The paper fixes the area (10 x 10 m), the number of cylinders (20) and their height
    (100 x robot_height); it samples positions and radii uniformly but does not print the ranges.
    The radius range below was calibrated so that the random policy survives 4.4 primitives per
    video on average, as the paper reports: :func:`husky_course.data.calibration.calibrate`
    reruns the sweep (:class:`CalibrationConfig`), chapter 2 shows it.
    """

    length: float = 10.0  #: forward extent of the course, obstacles have x in [obstacle_x_min, length]
    width: float = 10.0  #: lateral extent; side walls stand at y = +-width/2
    n_obstacles: int = 20
    robot_height: float = 0.075  #: the paper's scale constant
    obstacle_height_factor: float = 100.0  #: obstacle height = factor x robot_height = 7.5 m
    radius_range: tuple[float, float] = (0.15, 0.35)  #: uniform obstacle radius range (m)
    obstacle_x_min: float = 2.0  #: obstacles stand in x in [2, 10]: the first 2 m are a start zone
    start_half_width: float = 2.0  #: the start y is uniform in [-start_half_width, start_half_width]
    robot_radius: float = 0.45  #: the robot's collision shape: a vertical cylinder of this radius
    start_clearance: float = 0.25  #: free margin around the start disc (obstacles are redrawn)
    wall_thickness: float = 0.2
    wall_x_range: tuple[float, float] = (-10.0, 25.0)  #: walls extend beyond the course (for views)

    @property
    def obstacle_height(self) -> float:
        """Height of every cylinder and wall (m)."""
        return self.obstacle_height_factor * self.robot_height


WORLD_KINDS = ("static", "moving")


@dataclass(frozen=True)
class MovingWorldConfig(WorldConfig):
    """The moving course (chapter 10): the static course of the same seed, some cylinders walking
    across it (along ``y``), bouncing off the walls; time counts steps (:func:`.sim.world.make_world`)."""

    moving_fraction: float = 0.4
    speed_range: tuple[float, float] = (0.2, 0.6)  #: m per step; the robot advances 1 m per step


@dataclass(frozen=True)
class CameraConfig:
    """The onboard depth camera, mounted rigidly on the chassis (not on a joint).

    The camera looks straight ahead (no pitch); ``fov_deg`` is both the vertical and horizontal
    field of view (square image). Depth is the distance along the view axis (metres), clipped to
    ``[near, far]`` and normalised to ``(z - near) / (far - near)`` in [0, 1].
    """

    size: int = 50
    fov_deg: float = 130.0  #: our choice (the paper gives none); chapter 1 shows why 90 is too narrow
    near: float = 0.02
    far: float = 5.0
    mount_forward: float = 0.45  #: m ahead of the base centre, on the collision cylinder, behind the bumper
    mount_height: float = 0.40  #: m above the ground


@dataclass(frozen=True)
class PrimitiveConfig:
    """The 25-primitive library (paper, Section 2.1): smooth forward S-curves.

    Every primitive advances ``advance`` metres along the course and shifts the robot sideways by
    one of ``n`` evenly spaced offsets in ``[-lateral_spread, lateral_spread]``; it starts and ends
    at the same heading. Ten primitives cross the 10 m course.
    """

    n: int = 25
    advance: float = 1.0
    lateral_spread: float = 0.8
    samples: int = 101  #: recorded poses per primitive (chapter 1 measures their spacing)


@dataclass(frozen=True)
class SimConfig:
    """World, camera and primitive library together: everything that defines the simulator."""

    world: WorldConfig = field(default_factory=WorldConfig)
    camera: CameraConfig = field(default_factory=CameraConfig)
    primitives: PrimitiveConfig = field(default_factory=PrimitiveConfig)
    max_primitives: int = 10  #: a video (episode) ends after this many primitives


@dataclass(frozen=True)
class DataConfig:
    """Random-policy data collection (paper, Section 3.2)."""

    videos: int = 10_000
    seed: int = 0
    shard_videos: int = 250  #: videos per shard file (the unit of resumable work)
    backend: str = "fast"
    val_fraction: float = 0.2  #: share of videos held out for validation (the paper's 80/20)
    reward_safe_fraction: float = 0.5  #: share of safe images in the reward set (paper, Section 4.2)


@dataclass(frozen=True)
class CalibrationConfig:
    """The sweep that chose ``WorldConfig.radius_range`` (see :mod:`husky_course.data.calibration`).

    Each candidate range is tried on ``videos`` random-policy videos of collection ``seed``, a
    seed other than the dataset's, so the worlds the calibration tuned on are not the worlds the
    book reports. The target is the paper's mean of 4.4 primitives per video.
    """

    target: float = 4.4  #: the paper's mean primitives per random-policy video (Section 3.2)
    radius_ranges: tuple[tuple[float, float], ...] = (
        (0.05, 0.25),
        (0.10, 0.30),
        (0.15, 0.35),
        (0.20, 0.40),
        (0.25, 0.45),
    )
    videos: int = 2_000
    seed: int = 1


@dataclass(frozen=True)
class TrainConfig:
    """One training run's optimiser settings (see :func:`husky_course.training.trainer.fit`).

    The paper: Adam, lr 1e-5, batch 32, 3,200 epochs (12 h) for the encoder/decoder; lr 1e-3, batch
    16, 2,000 epochs (6 h) for the reward net. On 2 CPU cores: larger lr and batch, early stopping.
    """

    lr: float = 1e-3
    batch_size: int = 128
    epochs: int = 40  #: a cap; early stopping usually ends the run before it
    patience: int = 4  #: epochs without a validation improvement before stopping
    min_delta: float = 1e-4  #: an improvement smaller than this does not count
    seed: int = 0
    weight_decay: float = 0.0


@dataclass(frozen=True)
class ModelConfig:
    """Sizes of the learned models that the paper fixes or that we chose once for every model (image
    size and primitives come from :class:`SimConfig` through :func:`model_dims`, never repeated)."""

    latent: int = 15  #: the encoder's latent size (paper, Section 3.4)
    rnn_horizon: int = 5  #: steps the RNN look-ahead is trained to predict (chapter 6)
    distill_horizon: int = 3  #: look-ahead of the simulator's survival labels (chapter 7)


@dataclass(frozen=True)
class ModelDims:
    """The three sizes every network is built from: image side, primitives, latent."""

    image_size: int
    n_primitives: int
    latent: int


def model_dims(sim: SimConfig | None = None, model: ModelConfig | None = None) -> ModelDims:
    """The network sizes implied by a simulator config and a model config (defaults: the course's)."""
    sim, model = sim or SimConfig(), model or ModelConfig()
    return ModelDims(sim.camera.size, sim.primitives.n, model.latent)


@dataclass(frozen=True)
class TrainingPlan:
    """The training runs of the learning chapters, sized per profile (defaults: the full profile's; its
    epoch caps are `make book`'s budget on 2 cores, not convergence: chapter 3 prints how a run ended)."""

    encoder_decoder: TrainConfig = field(default_factory=lambda: TrainConfig(epochs=7, patience=3))
    reward_net: TrainConfig = field(  # the paper's lr and batch size (Section 4.2)
        default_factory=lambda: TrainConfig(lr=1e-3, batch_size=16, epochs=30, patience=5)
    )
    joint: TrainConfig = field(default_factory=lambda: TrainConfig(epochs=5, patience=3))  # safety nets too
    probe: TrainConfig = field(default_factory=lambda: TrainConfig(epochs=30, patience=4))
    rnn: TrainConfig = field(default_factory=lambda: TrainConfig(epochs=5, patience=3))
    distilled: TrainConfig = field(default_factory=lambda: TrainConfig(epochs=6, patience=3))


@dataclass(frozen=True)
class OracleConfig:
    """How the oracle ranks plans of equal length (see :func:`husky_course.sim.lattice.rank_plans`)."""

    cap: float = 0.3  #: clearance (m) above which plans are not told apart
    quantum: float = 0.02  #: clearance is compared in bins of this size (m)


@dataclass(frozen=True)
class MemoryConfig:
    """The memory student (chapter 8): its map input and its DAgger training.

    The student sees the current depth image and an egocentric occupancy map rasterised from every
    scan so far (moved by dead reckoning); the teacher is the oracle's lattice search on the true
    world. Training worlds come from collection seed ``collection_seed`` (a seed no dataset or
    calibration uses), so none is an evaluation world.
    """

    map_cells: int = 32  #: the map raster is map_cells x map_cells
    map_ahead: float = 5.4  #: the raster covers x in [-map_behind, map_ahead] (m, robot frame) ...
    map_behind: float = 1.0
    map_half_width: float = 3.2  #: ... and y in [-map_half_width, map_half_width]
    label_horizon: int = 5  #: survival labels over this many steps (the simulator's lattice search)
    rounds: int = 3  #: round 0 follows the teacher, later rounds the student (DAgger)
    worlds_per_round: int = 450  #: sized so that `make book`'s budget holds (see the closing notes)
    collection_seed: int = 2
    train: TrainConfig = field(default_factory=lambda: TrainConfig(epochs=10, patience=3))


@dataclass(frozen=True)
class DiscConfig:
    """Chapter 8's disc planner: its net's views (:mod:`husky_course.imitation.discs`: random poses in
    training worlds of a seed nothing else uses) and its settings (chosen on the tuning set)."""

    collection_seed: int = 4
    worlds: int = 3_000
    poses_per_world: int = 8
    grow: float = 0.0  #: m added to every predicted radius
    margin: float = 0.0  #: the search's margin (m; the mapping planner's is 0.02)
    unexplained: float = 0.05  #: a cylinder piece's points further than this (m) from its disc stay points
    train: TrainConfig = field(default_factory=lambda: TrainConfig(batch_size=256, epochs=40, patience=4))


@dataclass(frozen=True)
class GuaranteeConfig:
    """Chapter 9's PAC-Bayes certificate (:mod:`husky_course.evaluation.certificate`): a Gaussian over
    the memory student's last layer. Prior: centred on the DAgger weights, deviation
    ``prior_scale`` times their RMS, fixed before any certificate world is seen. Posterior: fitted on
    ``finetune_worlds`` of the ``worlds`` training worlds (collection ``collection_seed``, used by
    nothing else), certified on all of them, then measured on ``heldout_worlds`` of evaluation set
    ``heldout_set`` (0 reports the planners, 1 tunes)."""

    collection_seed: int = 3
    worlds: int = 5_000  #: N, the certificate's training worlds
    finetune_worlds: int = 500  #: the first of them, whose states the posterior is fitted on
    draws_per_world: int = 1
    heldout_worlds: int = 10_000
    heldout_set: int = 2
    prior_scale: float = 0.5
    delta: float = 0.009  #: the PAC-Bayes bound's confidence parameter
    delta_prime: float = 0.001  #: the sample-convergence bound's (together: 99% confidence)
    seed: int = 0  #: weight draws and the posterior's training
    train: TrainConfig = field(default_factory=lambda: TrainConfig(lr=3e-3, batch_size=256, epochs=30))


@dataclass(frozen=True)
class EvalPlan:
    """How many held-out worlds the planning chapters evaluate on (tables), and tune on (sweeps)."""

    worlds: int = 500
    seed: int = 0  #: which held-out set (see :func:`husky_course.evaluation.episodes.eval_world_seeds`)
    tuning_worlds: int = 200  #: a sweep's worlds, of evaluation set ``tuning_seed``
    tuning_seed: int = 1  #: the held-out set every sweep and choice is made on (never ``seed``)
    workers: int = 2  #: local processes the chapters evaluate with (every result but timing is the same)


@dataclass(frozen=True)
class Profile:
    """A named set of sizes: ``quick`` for tests and class demos, ``full`` for the paper's scale."""

    name: str
    sim: SimConfig
    data: DataConfig
    train: TrainingPlan = field(default_factory=TrainingPlan)
    eval: EvalPlan = field(default_factory=EvalPlan)
    model: ModelConfig = field(default_factory=ModelConfig)
    calibration: CalibrationConfig = field(default_factory=CalibrationConfig)
    memory: MemoryConfig = field(default_factory=MemoryConfig)
    guarantee: GuaranteeConfig = field(default_factory=GuaranteeConfig)
    discs: DiscConfig = field(default_factory=DiscConfig)

    @property
    def dims(self) -> ModelDims:
        """Network sizes for this profile (see :func:`model_dims`)."""
        return model_dims(self.sim, self.model)


def _profiles() -> dict[str, Profile]:
    sim = SimConfig()
    return {
        "quick": Profile(
            "quick", sim, DataConfig(videos=1_000),
            TrainingPlan(
                encoder_decoder=TrainConfig(epochs=20, patience=3), joint=TrainConfig(epochs=10, patience=3),
                reward_net=TrainConfig(batch_size=16, epochs=30, patience=5),
                probe=TrainConfig(epochs=15, patience=3), rnn=TrainConfig(epochs=10, patience=3),
                distilled=TrainConfig(epochs=10, patience=3),
            ),
            EvalPlan(worlds=60, tuning_worlds=30), calibration=CalibrationConfig(videos=500),
            memory=MemoryConfig(worlds_per_round=300, train=TrainConfig(epochs=10, patience=3)),
            guarantee=GuaranteeConfig(worlds=400, finetune_worlds=150, heldout_worlds=1_000),
            discs=DiscConfig(worlds=600),
        ),
        "full": Profile("full", sim, DataConfig(videos=10_000)),
    }


#: Minutes to build each artifact on 2 CPU cores, rounded: the estimate progress.announce_build prints
BUILD_MINUTES: dict[str, dict[str, float]] = {
    "quick": {
        "dataset": 0.1, "encoder_decoder": 0.7, "reward_net": 0.1, "safety_image": 0.2, "safety_prim": 0.2,
        "joint": 0.4, "diagnosis": 0.3, "rnn": 0.5, "survival labels": 0.2, "distilled": 0.3, "memory": 2,
        "discs": 0.3, "certificate": 0.4,
    },
    "full": {
        "dataset": 0.2, "encoder_decoder": 1.5, "reward_net": 0.4, "safety_image": 0.5, "safety_prim": 0.5,
        "joint": 1.3, "diagnosis": 2, "rnn": 1.6, "survival labels": 0.9, "distilled": 1.1, "memory": 4,
        "discs": 1.6, "certificate": 2.7,
    },
}


def check_world_kind(kind: str) -> str:
    """Return ``kind`` if it is one of :data:`WORLD_KINDS`, else raise :class:`ConfigError`."""
    if kind not in WORLD_KINDS:
        raise ConfigError(f"unknown world {kind!r}: choose one of {', '.join(WORLD_KINDS)}")
    return kind


def world_kind(sim: SimConfig) -> str:
    """``"moving"`` if ``sim``'s world has moving obstacles, else ``"static"``."""
    return "moving" if isinstance(sim.world, MovingWorldConfig) else "static"


def world_flag(sim: SimConfig) -> str:
    """The command-line flag that selects ``sim``'s course (empty for the default, static)."""
    return " --world moving" if world_kind(sim) == "moving" else ""


def sim_for_world(sim: SimConfig, kind: str) -> SimConfig:
    """``sim`` on the static or the moving course (everything else the same)."""
    if world_kind(sim) == check_world_kind(kind):
        return sim
    base = {f: getattr(sim.world, f) for f in WorldConfig.__dataclass_fields__}
    return replace(sim, world=MovingWorldConfig(**base) if kind == "moving" else WorldConfig(**base))


def with_world(profile: Profile, kind: str) -> Profile:
    """``profile`` on the static or the moving course (same everything else; artifacts keyed by it)."""
    return replace(profile, sim=sim_for_world(profile.sim, kind))


def check_profile_name(name: str) -> str:
    """Return ``name`` if it is a known profile, else raise :class:`ConfigError`."""
    if name not in PROFILES:
        raise ConfigError(f"unknown profile {name!r}: choose one of {', '.join(PROFILES)}")
    return name


def get_profile(name: str | None = None) -> Profile:
    """The profile ``name`` (``"quick"`` or ``"full"``), or the one ``HUSKY_PROFILE`` names (default
    ``quick``). Call it once, where the user chooses (the CLI, the top of a notebook), and pass the
    returned :class:`Profile` down: no function below takes a profile name."""
    if name is None:
        name = os.environ.get(PROFILE_ENV, "quick").strip() or "quick"
    return _profiles()[check_profile_name(name)]


def check_profile(profile: object) -> Profile:
    """Return ``profile`` if it is a :class:`Profile`, else raise :class:`ConfigError` (library
    functions take the :class:`Profile` itself, resolved once by :func:`get_profile`)."""
    if not isinstance(profile, Profile):
        raise ConfigError(f"expected a Profile, got {profile!r}: resolve the name once with "
                          "husky_course.config.get_profile(name) and pass the result")
    return profile


def to_dict(cfg: object) -> dict:
    """A JSON-ready dict of a config dataclass (tuples become lists); dicts pass through."""
    data = cfg if isinstance(cfg, dict) else asdict(cfg)  # type: ignore[call-overload]
    return json.loads(json.dumps(data))


def config_hash(cfg: object) -> str:
    """A short stable hash of a config dataclass (or a plain dict), used to key artifacts."""
    text = json.dumps(to_dict(cfg), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:12]

