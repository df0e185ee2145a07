"""Bad inputs across the library: each one must raise the right exception with a message that names
the problem, and must leave no half-written file behind where a file would have been written.

Cases where the library's error is not clear yet are marked ``xfail(strict=True)`` with the reason:
they state the behaviour we want, and turn into failures (to remove the mark) once it is fixed.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import gymnasium
import numpy as np
import pytest
import torch

from husky_course.cli import main
from husky_course.config import ConfigError, get_profile
from husky_course.data import collect as collect_module
from husky_course.data.collect import collect, fresh_pairs
from husky_course.data.dataset import load_dataset
from husky_course.data.io import DatasetError, load_npy
from husky_course.data.splits import val_videos
from husky_course.data.store import dataset_dir, model_dir
from husky_course.evaluation.episodes import eval_world_seeds
from husky_course.evaluation.metrics import image_errors, roc_auc
from husky_course.evaluation.statistics import clopper_pearson
from husky_course.models.base import check_images, encode_primitive
from husky_course.models.paper import EncoderDecoder, LatentRewardNet
from husky_course.models.safety import JointModel
from husky_course.planners.base import PlannerError, check_look_ahead, check_observation
from husky_course.planners.classic import HeuristicPlanner
from husky_course.planners.registry import make_planner
from husky_course.sim.backends import make_simulator
from husky_course.sim.env import HuskyNavEnv
from husky_course.sim.fast import FastSimulator
from husky_course.sim.primitives import PrimitiveError, make_library
from husky_course.sim.world import make_world
from husky_course.training.trainer import CheckpointError, History, fit, load_model, save_model

QUICK = get_profile("quick")  # resolved once, passed down

VIDEOS, SEED = 6, 5  # a dataset of 6 videos takes a few hundredths of a second


def listing(path: Path) -> dict[str, bytes]:
    """Every file under ``path`` with its bytes (to prove an error changed nothing)."""
    return {str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()}


@pytest.fixture(autouse=True)
def no_temporary_files_left(tmp_path):
    """Whatever a test does, no atomic-write temporary (``.*.tmp``) may be left in its directory."""
    yield
    leftovers = [str(p) for p in tmp_path.rglob("*.tmp")]
    assert not leftovers, f"half-written files left behind: {leftovers}"


@pytest.fixture(scope="module")
def tiny_dataset(tmp_path_factory) -> Path:
    return collect(tmp_path_factory.mktemp("tiny") / "ds", QUICK, videos=VIDEOS, seed=SEED, progress=False)


@pytest.fixture
def dataset_copy(tiny_dataset, tmp_path) -> Path:
    return Path(shutil.copytree(tiny_dataset, tmp_path / "ds"))


# --- primitives --------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "index, message",
    [
        (25, r"primitive index 25 out of range 0\.\.24"),
        (-1, r"primitive index -1 out of range 0\.\.24"),
        (2.0, "primitive index must be an integer, got 2.0"),
        (True, "primitive index must be an integer, got True"),
        ("3", "primitive index must be an integer, got '3'"),
    ],
)
def test_bad_primitive_index(index, message):
    lib = make_library()
    with pytest.raises(PrimitiveError, match=message):
        lib.path_from(np.zeros(3), index)
    sim = FastSimulator()
    sim.load(0)
    with pytest.raises(PrimitiveError, match=message):
        sim.apply(np.zeros(3), index)


@pytest.mark.parametrize("bad", [25, -1])
def test_bad_primitive_index_vectorised(bad):
    lib = make_library()
    with pytest.raises(PrimitiveError, match="out of range"):
        lib.paths_from(np.zeros((2, 3)), np.array([0, bad]))


def test_pose_of_wrong_length():
    with pytest.raises(ValueError, match="pose"):
        make_library().path_from(np.zeros(2), 0)


def test_bad_primitive_for_the_decoder():
    with pytest.raises(ValueError, match=r"primitive indices must be in 0\.\.24"):
        encode_primitive(torch.tensor([3, 25]), 25)
    with pytest.raises(TypeError, match="primitive indices must be integers"):
        encode_primitive(torch.tensor([1.5]), 25)


# --- images for the models, observations for the planners ------------------------------------
@pytest.mark.parametrize(
    "images, error, message",
    [
        (torch.zeros(2, 64, 64), ValueError, r"shape \(B, 50, 50\).*got \(2, 1, 64, 64\)"),
        (torch.zeros(2, 3, 50, 50), ValueError, r"got \(2, 3, 50, 50\)"),
        (torch.zeros(50, 50), ValueError, "shape"),
        (torch.zeros(2, 50, 50, dtype=torch.uint8), ValueError, "floating point.*torch.uint8"),
        (
            np.zeros((2, 50, 50), np.float32),
            TypeError,
            "expected a torch.Tensor of depth images, got ndarray",
        ),
    ],
)
def test_bad_images_for_the_models(images, error, message):
    with pytest.raises(error, match=message):
        check_images(images, 50)
    with pytest.raises(error, match=message):
        EncoderDecoder()(images, torch.zeros(2, dtype=torch.long))


def test_nan_depth_for_the_models():
    images = torch.zeros(2, 50, 50)
    images[1, 10, 10] = float("nan")
    with pytest.raises(ValueError, match="NaN"):
        check_images(images, 50)


def test_depth_outside_0_1_for_the_models():
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        check_images(torch.full((2, 50, 50), 3.0), 50)


@pytest.mark.parametrize(
    "obs, message",
    [
        (np.zeros((64, 64), np.float32), r"shape \(50, 50\), got \(64, 64\)"),
        (np.zeros((1, 50, 50), np.float32), r"shape \(50, 50\)"),
        (np.zeros((50, 50), np.uint8), "float depth image.*uint8"),
        (np.full((50, 50), np.nan, np.float32), "NaN or inf"),
        (np.full((50, 50), 2.5, np.float32), r"normalised depth in \[0, 1\]"),
        ([[0.5] * 50] * 50, "numpy array, got list"),
    ],
)
@pytest.mark.parametrize("planner", ["random", "heuristic"])
def test_bad_observation_for_the_planners(obs, message, planner):
    with pytest.raises(ValueError, match=message):
        check_observation(obs)
    p = make_planner(planner)
    with pytest.raises(ValueError, match=message):
        p.act(obs)


# --- datasets ----------------------------------------------------------------------------------
def test_truncated_npy(dataset_copy):
    path = dataset_copy / "images.npy"
    path.write_bytes(path.read_bytes()[:-1000])
    with pytest.raises(DatasetError, match=r"images\.npy is truncated or corrupted.*collect again"):
        load_npy(path)
    with pytest.raises(DatasetError, match=r"images\.npy is corrupted \(its sha256 does not match"):
        load_dataset(dataset_copy)
    with pytest.raises(DatasetError, match=r"images\.npy is truncated or corrupted"):
        load_dataset(dataset_copy, verify=False)


@pytest.mark.parametrize(
    "damage, message",
    [
        ("flip_byte", r"poses\.npy is corrupted \(its sha256"),
        ("garbage_header", r"labels\.npy is truncated or corrupted"),
        ("pickled_objects", r"labels\.npy is truncated or corrupted"),
        ("missing_file", r"missing dataset file .*step\.npy"),
        ("wrong_dtype", r"labels\.npy has dtype int64, expected uint8"),
        ("wrong_rows", r"labels\.npy has \d+ rows, meta says \d+"),
        ("no_meta", r"no finished dataset \(no meta\.json\).*collect --out"),
        ("other_format", r"dataset format 99 != 1"),
    ],
)
def test_corrupted_dataset(dataset_copy, damage, message):
    d = dataset_copy
    verify = True
    if damage == "flip_byte":
        data = bytearray((d / "poses.npy").read_bytes())
        data[-1] ^= 0xFF
        (d / "poses.npy").write_bytes(bytes(data))
    elif damage == "garbage_header":
        (d / "labels.npy").write_bytes(b"\x93NUMPY garbage")
        verify = False  # (with verify, the sha256 check catches it first)
    elif damage == "pickled_objects":
        np.save(d / "labels.npy", np.array([{}], dtype=object), allow_pickle=True)
        verify = False
    elif damage == "missing_file":
        (d / "step.npy").unlink()
    elif damage == "wrong_dtype":
        np.save(d / "labels.npy", np.load(d / "labels.npy").astype(np.int64))
        verify = False
    elif damage == "wrong_rows":
        np.save(d / "labels.npy", np.load(d / "labels.npy")[:-1])
        verify = False
    elif damage == "no_meta":
        (d / "meta.json").unlink()
    elif damage == "other_format":
        meta = json.loads((d / "meta.json").read_text())
        (d / "meta.json").write_text(json.dumps({**meta, "format": 99}))
    with pytest.raises(DatasetError, match=message):
        load_dataset(d, verify=verify)


@pytest.mark.parametrize("damage", ["truncated", "no_sha256"])
def test_damaged_meta_json(dataset_copy, damage):
    meta_path = dataset_copy / "meta.json"
    if damage == "truncated":
        meta_path.write_text(meta_path.read_text()[:50])
    else:
        meta = json.loads(meta_path.read_text())
        del meta["sha256"]
        meta_path.write_text(json.dumps(meta))
    with pytest.raises(DatasetError, match=r"meta\.json"):
        load_dataset(dataset_copy)


def test_dataset_from_another_config(dataset_copy):
    before = listing(dataset_copy)
    quick = get_profile("quick")
    other_sim = collect_module.replace(quick, sim=collect_module.replace(quick.sim, max_primitives=5))
    for kwargs in (
        {"profile": QUICK, "videos": VIDEOS + 1, "seed": SEED},
        {"profile": QUICK, "videos": VIDEOS, "seed": SEED + 1},
        {"profile": other_sim, "videos": VIDEOS, "seed": SEED},
        {"profile": QUICK, "videos": VIDEOS, "seed": SEED, "backend": "pybullet"},
    ):
        with pytest.raises(DatasetError, match=r"made with a different config \(see .*spec\.json\)"):
            collect(dataset_copy, progress=False, **kwargs)
    assert listing(dataset_copy) == before, "a refused collection changed the directory"


def test_collect_into_a_foreign_directory(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("not a dataset")
    with pytest.raises(DatasetError, match="is not empty and holds no dataset spec"):
        collect(out, QUICK, videos=VIDEOS, seed=SEED, progress=False)
    assert listing(out) == {"notes.txt": b"not a dataset"}


def test_resume_with_a_corrupted_shard(tmp_path, monkeypatch):
    out = tmp_path / "ds"

    def killed(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(collect_module, "_merge", killed)
    with pytest.raises(KeyboardInterrupt):
        collect(out, QUICK, videos=VIDEOS, seed=SEED, progress=False)
    monkeypatch.undo()
    shard = out / "shards" / "shard_00000.npz"
    shard.write_bytes(shard.read_bytes()[:100])
    with pytest.raises(DatasetError, match=r"shard .*shard_00000\.npz is truncated or corrupted.*delete it"):
        collect(out, QUICK, videos=VIDEOS, seed=SEED, progress=False)
    assert not (out / "meta.json").exists() and not list(out.glob("*.npy")), "a half-made dataset"


@pytest.mark.parametrize(
    "kwargs, error, message",
    [
        ({"videos": -1}, ValueError, "number of videos must be a positive integer, got -1"),
        ({"videos": 0}, ValueError, "number of videos must be a positive integer, got 0"),
        ({"videos": 2.5}, ValueError, "number of videos must be a positive integer, got 2.5"),
        ({"videos": True}, ValueError, "number of videos must be a positive integer, got True"),
        ({"videos": 3, "workers": 0}, ValueError, "workers must be a positive integer, got 0"),
        ({"videos": 3, "seed": -1}, ValueError, r"collection seed -1 is out of range 0\.\.2146"),
        ({"videos": 3, "seed": 2148}, ValueError, r"collection seed 2148 is out of range"),
        ({"videos": 3, "backend": "gpu"}, ConfigError, "unknown backend 'gpu': choose one of fast, pybullet"),
        ({"videos": 3, "profile": "huge"}, ConfigError, "expected a Profile, got 'huge': resolve the name"),
    ],
)
def test_bad_collection_sizes_write_nothing(tmp_path, kwargs, error, message):
    out = tmp_path / "ds"
    with pytest.raises(error, match=message):
        collect(out, progress=False, **{"profile": QUICK, **kwargs})
    assert not out.exists(), f"a refused collection created {out}"


def test_fractional_collection_seed_writes_nothing(tmp_path):
    out = tmp_path / "ds"
    with pytest.raises(ValueError, match="collection seed"):
        collect(out, QUICK, videos=3, seed=1.5, progress=False)
    assert not out.exists()


@pytest.mark.parametrize("n", [0, -3])
def test_fresh_pairs_needs_at_least_one(n):
    with pytest.raises(ValueError, match=f"n must be >= 1, got {n}"):
        fresh_pairs(n, seed=7)


def test_fresh_pairs_needs_an_integer():
    with pytest.raises(ValueError, match="n must be"):
        fresh_pairs(1.5, seed=7)


def test_bad_validation_fraction(tiny_dataset):
    ds = load_dataset(tiny_dataset)
    for fraction in (0.0, 1.0, 1.5, -0.2):
        with pytest.raises(ValueError, match=r"val_fraction must be in \(0, 1\)"):
            val_videos(ds, 0, fraction)


# --- artifacts and checkpoints ------------------------------------------------------------------
def test_missing_artifacts(tmp_path, monkeypatch):
    monkeypatch.setenv("HUSKY_ARTIFACTS", str(tmp_path / "artifacts"))
    with pytest.raises(
        DatasetError, match=r"no finished dataset \(no meta\.json\): run `python -m husky_course"
    ):
        load_dataset(dataset_dir(QUICK))
    ckpt = model_dir("encoder_decoder", {"any": 1}, QUICK) / "model.pt"
    with pytest.raises(CheckpointError, match=r"missing checkpoint .*encoder_decoder-\w+/model\.pt"):
        load_model(ckpt, EncoderDecoder())
    assert not (tmp_path / "artifacts").exists(), "looking for an artifact created directories"


@pytest.fixture
def checkpoint(tmp_path) -> Path:
    path = tmp_path / "model.pt"
    save_model(path, EncoderDecoder(), {"dataset": "abc"}, History())
    return path


@pytest.mark.parametrize("model_class", [LatentRewardNet, JointModel])
def test_wrong_architecture_checkpoint(checkpoint, model_class):
    before = checkpoint.read_bytes()
    with pytest.raises(
        CheckpointError, match=rf"architecture .*'encoder_decoder'.*does not match {model_class.__name__}"
    ):
        load_model(checkpoint, model_class())
    assert checkpoint.read_bytes() == before


def test_checkpoint_from_another_config(checkpoint):
    with pytest.raises(CheckpointError, match="trained with another config or dataset; retrain it"):
        load_model(checkpoint, EncoderDecoder(), fingerprint={"dataset": "xyz"})


def test_missing_truncated_or_foreign_checkpoint(checkpoint, tmp_path):
    with pytest.raises(CheckpointError, match=r"missing checkpoint .*nothing\.pt"):
        load_model(tmp_path / "nothing.pt", EncoderDecoder())
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes(checkpoint.read_bytes()[:2000])
    with pytest.raises(CheckpointError, match=r"truncated\.pt is not a readable checkpoint.*retrain"):
        load_model(truncated, EncoderDecoder())
    foreign = tmp_path / "state_dict.pt"
    torch.save(EncoderDecoder().state_dict(), foreign)
    with pytest.raises(CheckpointError, match=r"state_dict\.pt is not a husky_course checkpoint"):
        load_model(foreign, EncoderDecoder())


def test_bad_training_inputs_write_nothing(tmp_path):
    from husky_course.config import TrainConfig

    data = {
        "image": torch.zeros(4, 50, 50),
        "prim": torch.zeros(4, dtype=torch.long),
        "next": torch.zeros(4, 50, 50),
    }
    short = {**data, "prim": torch.zeros(3, dtype=torch.long)}
    with pytest.raises(ValueError, match="same number of rows.*'prim': 3"):
        fit(EncoderDecoder(), short, data, TrainConfig(epochs=1), run_dir=tmp_path / "run1", progress=False)
    with pytest.raises(ValueError, match="invalid training config"):
        fit(EncoderDecoder(), data, data, TrainConfig(epochs=0), run_dir=tmp_path / "run2", progress=False)
    assert not (tmp_path / "run1").exists() and not (tmp_path / "run2").exists()


# --- names: profiles, planners, backends --------------------------------------------------------
@pytest.mark.parametrize("name", ["huge", "", "FULL", "quick "])
def test_unknown_profile(name):
    with pytest.raises(ConfigError, match=rf"unknown profile '{name}': choose one of quick, full"):
        get_profile(name)


def test_unknown_profile_from_the_environment(monkeypatch):
    monkeypatch.setenv("HUSKY_PROFILE", "paper")
    with pytest.raises(ConfigError, match="unknown profile 'paper'"):
        get_profile()


def test_unknown_planner_and_bad_planner_arguments():
    with pytest.raises(PlannerError, match="unknown planner 'astar': choose one of .*random.*heuristic"):
        make_planner("astar")
    with pytest.raises(PlannerError, match="bad arguments for planner 'random'"):
        make_planner("random", speed=3)
    with pytest.raises(PlannerError, match="heuristic depth must be 1 or 2, got 3"):
        HeuristicPlanner(depth=3)


@pytest.mark.parametrize("k", [-1, 1.5, True, "2"])
def test_bad_look_ahead(k):
    with pytest.raises(PlannerError, match=f"look_ahead must be a non-negative integer, got {k!r}"):
        check_look_ahead(k)


def test_unknown_backend():
    with pytest.raises(ConfigError, match="unknown backend 'gpu': choose one of fast, pybullet"):
        make_simulator("gpu")
    with pytest.raises(ConfigError, match="unknown backend 'Fast'"):
        HuskyNavEnv(backend="Fast")
    with pytest.raises(ValueError, match="render_mode must be None or 'rgb_array', got 'human'"):
        HuskyNavEnv(render_mode="human")


# --- worlds, evaluation sets, the environment ------------------------------------------------------
@pytest.mark.parametrize("seed", [-1, -(2**40), 1.0, True, "3", None])
def test_bad_world_seed(seed):
    message = "a world seed must be a non-negative integer"
    with pytest.raises(ValueError, match=message):
        make_world(seed)
    with pytest.raises(ValueError, match=message):
        FastSimulator().load(seed)
    env = HuskyNavEnv()
    with pytest.raises(ValueError, match=message):
        env.reset(options={"world_seed": seed})
    env.close()


def test_negative_seed_for_env_reset():
    # gymnasium checks reset(seed=...) before the library does; its message is clear, its type is its own
    with pytest.raises((ValueError, gymnasium.error.Error), match="[Ss]eed must be"):
        HuskyNavEnv().reset(seed=-1)


@pytest.mark.parametrize(
    "n, seed, message",
    [
        (-1, 0, r"number of evaluation worlds must be in 1\.\.1000000, got -1"),
        (0, 0, r"number of evaluation worlds must be in 1\.\.1000000, got 0"),
        (10**6 + 1, 0, "number of evaluation worlds must be in"),
        (2.0, 0, "number of evaluation worlds must be an integer"),
        (5, -1, r"evaluation seed must be in 0\.\.2146, got -1"),
        (5, 2147, r"evaluation seed must be in 0\.\.2146, got 2147"),
    ],
)
def test_bad_evaluation_set(n, seed, message):
    with pytest.raises(ValueError, match=message):
        eval_world_seeds(n, seed)


def test_env_step_with_an_invalid_action():
    env = HuskyNavEnv()
    with pytest.raises(RuntimeError, match=r"episode is over: call reset\(\) before step\(\)"):
        env.step(0)
    env.reset(seed=3)
    for action in (25, -1, 2.0, "a", None, np.array([1, 2])):
        with pytest.raises(ValueError, match=r"invalid action .*expected an integer in 0\.\.24"):
            env.step(action)
    assert env.steps == 0, "a refused action moved the robot"
    env.close()


def test_simulator_without_a_world():
    with pytest.raises(RuntimeError, match=r"no world loaded: call load\(world_or_seed\) first"):
        FastSimulator().apply(np.zeros(3), 0)


# --- metrics and statistics ------------------------------------------------------------------------
def test_roc_auc_with_nan_scores():
    with pytest.raises(ValueError, match="scores contain NaN or inf"):
        roc_auc(np.array([0, 1, 1]), np.array([0.1, np.nan, 0.9]))
    with pytest.raises(ValueError, match="scores contain NaN or inf"):
        roc_auc(np.array([0, 1]), np.array([0.1, np.inf]))
    with pytest.raises(ValueError, match=r"labels \(3,\) and scores \(2,\) differ in length"):
        roc_auc(np.array([0, 1, 1]), np.array([0.1, 0.9]))


def test_roc_auc_with_nan_labels():
    with pytest.raises(ValueError, match="labels contain NaN"):
        roc_auc(np.array([0.0, np.nan, 1.0]), np.array([0.1, 0.5, 0.9]))


def test_bad_statistics_inputs():
    with pytest.raises(ValueError, match=r"n must be in 5\.\.1000000000, got 3"):
        clopper_pearson(5, 3)
    with pytest.raises(ValueError, match=r"confidence must be in \(0, 1\), got 1.5"):
        clopper_pearson(1, 3, confidence=1.5)
    with pytest.raises(ValueError, match="alternative must be"):
        clopper_pearson(1, 3, alternative="both")
    with pytest.raises(ValueError, match=r"same shape, got \(2, 50, 50\), \(3, 50, 50\)"):
        image_errors(np.zeros((2, 50, 50)), np.zeros((3, 50, 50)))


# --- the command line ------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "argv, message",
    [
        ([], "required: command"),
        (["fly"], "invalid choice: 'fly'"),
        (["train", "everything"], "invalid choice: 'everything'"),
        (["collect", "--out", "{tmp}/ds", "--videos", "abc"], "argument --videos: invalid int value: 'abc'"),
        (["evaluate", "--worlds", "3"], "required: --planner"),
        (["evaluate", "--planner", "random", "--worlds", "1e3"], "invalid int value: '1e3'"),
    ],
)
def test_cli_usage_errors_exit_2(argv, message, tmp_path, capsys):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "ds").exists()


@pytest.mark.parametrize(
    "argv, message",
    [
        (["collect", "--out", "{tmp}/ds", "--videos", "-3"], "number of videos must be a positive integer"),
        (["collect", "--out", "{tmp}/ds", "--videos", "3", "--backend", "gpu"], "unknown backend 'gpu'"),
        (["collect", "--out", "{tmp}/ds", "--videos", "3", "--profile", "huge"], "unknown profile 'huge'"),
        (["collect", "--out", "{tmp}/ds", "--videos", "3", "--workers", "0"], "workers must be a positive"),
        (
            ["collect", "--out", "{tmp}/ds", "--videos", "3", "--seed", "-1"],
            "collection seed -1 is out of range",
        ),
        (["stats", "{tmp}/ds"], "no finished dataset (no meta.json)"),
        (["evaluate", "--planner", "astar"], "unknown planner 'astar'"),
        (
            ["evaluate", "--planner", "random", "--worlds", "-2"],
            "number of evaluation worlds must be in 1..1000000",
        ),
        (["evaluate", "--planner", "random", "--worlds", "2", "--seed", "-1"], "evaluation seed must be in"),
        (["evaluate", "--planner", "random", "--worlds", "2", "--backend", "gpu"], "unknown backend 'gpu'"),
        (["evaluate", "--planner", "lookahead", "--look-ahead", "-1"], "look_ahead must be a non-negative"),
        (["evaluate", "--planner", "heuristic", "--look-ahead", "1"], "--look-ahead applies only to"),
        (["evaluate", "--planner", "random", "--profile", "huge"], "unknown profile 'huge'"),
    ],
)
def test_cli_bad_values_exit_2_and_write_nothing(argv, message, tmp_path, capsys):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv] + (
        ["--no-progress"] if argv[0] in ("collect", "evaluate") else []
    )
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert err.startswith("error: ") and message in err, err
    assert out == ""
    assert not (tmp_path / "ds").exists()
