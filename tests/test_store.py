"""The artifact store: keyed by content (a moved store is reused as it is), and loading never builds."""

from __future__ import annotations

import json
import shutil
from dataclasses import replace

import pytest

from husky_course import cli
from husky_course.config import TrainConfig, TrainingPlan, get_profile, with_world
from husky_course.data import store
from husky_course.data.io import DatasetError
from husky_course.training import builders, trainer
from husky_course.training.trainer import CheckpointError

QUICK = get_profile("quick")
ONE_EPOCH = TrainConfig(epochs=1, patience=1)
TINY = replace(  # the quick profile, small enough to build a store in seconds
    QUICK,
    data=replace(QUICK.data, videos=40, shard_videos=20),
    train=TrainingPlan(
        encoder_decoder=replace(ONE_EPOCH, batch_size=64), reward_net=replace(ONE_EPOCH, batch_size=16)
    ),
)


def _snapshot(root):
    return {str(p.relative_to(root)): p.stat().st_mtime_ns for p in root.rglob("*") if p.is_file()}


def _no_training(*args, **kwargs):
    raise AssertionError("fit() was called: something was rebuilt")


def test_a_copied_store_is_reused_without_rebuilding(tmp_path, monkeypatch):
    first = tmp_path / "checkout-a" / "artifacts"
    monkeypatch.setenv(store.ARTIFACTS_ENV, str(first))
    ed, rn = builders.get_reward_net(TINY, progress=False)
    assert "path" not in json.dumps(rn.fingerprint)  # keyed by the encoder's content, not its file

    moved = tmp_path / "elsewhere" / "re-cloned" / "artifacts"
    shutil.copytree(first, moved)
    shutil.rmtree(first)
    monkeypatch.setenv(store.ARTIFACTS_ENV, str(moved))
    before = _snapshot(moved)
    monkeypatch.setattr(builders, "fit", _no_training)
    monkeypatch.setattr(store, "collect", _no_training)
    ed2, rn2 = builders.get_reward_net(TINY, progress=False)
    loaded = builders.load("reward_net", TINY)
    assert _snapshot(moved) == before, "the copied store was written to"
    assert rn2.fingerprint == rn.fingerprint == loaded.fingerprint
    assert rn2.history.best_val == rn.history.best_val


def test_load_never_builds(tmp_path, monkeypatch):
    root = tmp_path / "artifacts"
    monkeypatch.setenv(store.ARTIFACTS_ENV, str(root))
    monkeypatch.setattr(store, "collect", _no_training)
    monkeypatch.setattr(trainer, "fit", _no_training)
    for name in builders.MODELS:
        command = rf"`python -m husky_course train {name} --profile quick`"
        with pytest.raises(CheckpointError, match=f"train it with {command}"):
            builders.load(name, TINY)
    assert not root.exists(), "loading created files"


def test_cli_collect_without_out_fills_the_store(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv(store.ARTIFACTS_ENV, str(tmp_path / "artifacts"))
    assert cli.main(["collect", "--profile", "quick", "--videos", "5", "--no-progress"]) == 0
    small = replace(QUICK, data=replace(QUICK.data, videos=5))
    assert (store.dataset_dir(small) / "meta.json").is_file()
    assert not store.dataset_dir(QUICK).exists()  # not under the 1,000-video name
    assert json.loads(capsys.readouterr().out)["videos"] == 5


def test_a_build_is_announced_in_one_line_first(tmp_path, monkeypatch, capsys):
    """A missing artifact: one line (what, roughly how long, the command) before its bar starts."""
    from dataclasses import replace

    from husky_course.config import get_profile
    from husky_course.data import store

    monkeypatch.setenv("HUSKY_ARTIFACTS", str(tmp_path / "artifacts"))
    profile = get_profile("quick")
    profile = replace(profile, data=replace(profile.data, videos=8))
    store.get_dataset(profile, workers=1, progress=False)
    printed = capsys.readouterr()
    assert printed.out == "", "outside a notebook stdout is left to the command (the CLI's JSON)"
    out = printed.err.strip().splitlines()
    assert len(out) == 1 and out[0].startswith("Building dataset (quick profile)")
    assert "under a minute on 2 CPU cores" in out[0]
    assert "`python -m husky_course collect --profile quick`" in out[0]
    store.get_dataset(profile, workers=1, progress=False)  # now it loads: nothing announced
    assert capsys.readouterr() == ("", "")


def test_a_missing_moving_dataset_names_the_moving_command(tmp_path, monkeypatch):
    monkeypatch.setenv(store.ARTIFACTS_ENV, str(tmp_path / "artifacts"))
    moving = with_world(QUICK, "moving")
    command = r"`python -m husky_course collect --profile quick --world moving`"
    with pytest.raises(DatasetError, match=command):
        store.load_profile_dataset(moving)
    with pytest.raises(DatasetError, match=r"collect --profile quick`"):  # the static course: no flag
        store.load_profile_dataset(QUICK)
    args = cli.build_parser().parse_args(["collect", "--profile", "quick", "--world", "moving"])
    assert args.world == "moving"  # the command the message names is one the CLI accepts


def test_the_dataset_key_holds_the_collection_code(monkeypatch):
    before = store.dataset_dir(QUICK)
    monkeypatch.setattr(store, "code_fingerprint", lambda *modules: "other code")
    assert store.dataset_dir(QUICK) != before
