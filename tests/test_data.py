import json

import numpy as np
import pytest

from husky_course.cli import main as cli_main
from husky_course.config import ConfigError, get_profile
from husky_course.data import collect as collect_mod
from husky_course.data.collect import collect
from husky_course.data.dataset import load_dataset, stats
from husky_course.data.io import DatasetError
from husky_course.data.splits import encoder_decoder_pairs, pair_indices, reward_set

QUICK = get_profile("quick")  # resolved once, passed down

NAMES = (
    "images",
    "prims",
    "labels",
    "applied",
    "episode",
    "step",
    "poses",
    "world_seeds",
    "lengths",
    "collided",
)


def _arrays(path):
    ds = load_dataset(path)
    return {n: np.asarray(getattr(ds, n)) for n in NAMES}


def test_minus_one_convention_and_episode_boundaries(small_dataset_dir):
    ds = load_dataset(small_dataset_dir)
    assert ds.images.shape[1:] == (50, 50) and ds.images.dtype == np.float16
    assert 0 <= ds.images.min() and ds.images.max() <= 1
    # -1 exactly where the label is 1, and the real primitive is kept in `applied`
    np.testing.assert_array_equal(ds.prims == -1, ds.labels == 1)
    safe = ds.labels == 0
    np.testing.assert_array_equal(ds.prims[safe], ds.applied[safe])
    assert ds.applied.min() >= 0 and ds.applied.max() < 25
    for v in range(len(ds.lengths)):
        idx = ds.video(v)
        assert len(idx) == ds.lengths[v] and np.all(np.diff(idx) == 1)
        np.testing.assert_array_equal(ds.step[idx], np.arange(len(idx)))
        # at most one unsafe step, and it is the video's last
        assert ds.labels[idx[:-1]].sum() == 0
        assert ds.labels[idx[-1]] == ds.collided[v]
        if not ds.collided[v]:
            assert len(idx) == 10
    s = stats(ds)
    assert s["videos"] == 120 and s["images"] == len(ds) == ds.lengths.sum()
    assert s["unsafe"] == s["videos_ending_in_collision"]


def test_pairs_never_cross_videos_or_collisions(small_dataset_dir):
    ds = load_dataset(small_dataset_dir)
    t = pair_indices(ds)
    assert np.all(ds.labels[t] == 0) and np.all(ds.episode[t] == ds.episode[t + 1])
    # every safe image except the last of a surviving video has a successor
    survivors_last = np.cumsum(ds.lengths)[ds.collided == 0] - 1
    assert len(t) == (ds.labels == 0).sum() - len(survivors_last)
    split = encoder_decoder_pairs(ds, seed=1)
    assert len(np.intersect1d(split.train_t, split.val_t)) == 0
    assert len(np.intersect1d(ds.episode[split.train_t], ds.episode[split.val_t])) == 0  # by video
    assert 0.1 < len(split.val_t) / len(t) < 0.3
    assert len(split.train_t) + len(split.val_t) == len(t)
    again = encoder_decoder_pairs(ds, seed=1)
    np.testing.assert_array_equal(split.train_t, again.train_t)
    rs = reward_set(ds, seed=1)
    members = np.concatenate([rs.train, rs.val])
    assert ds.labels[members].sum() == ds.labels.sum()  # every unsafe image is in
    n_safe = (ds.labels[members] == 0).sum()
    assert n_safe == round(0.5 * (ds.labels == 0).sum())
    assert len(np.intersect1d(ds.episode[rs.train], ds.episode[rs.val])) == 0


def test_same_seed_same_bytes_for_any_worker_count(tmp_path):
    a = collect(tmp_path / "a", QUICK, videos=60, seed=4, workers=1, progress=False)
    b = collect(tmp_path / "b", QUICK, videos=60, seed=4, workers=2, progress=False)
    for name in NAMES:
        assert (a / f"{name}.npy").read_bytes() == (b / f"{name}.npy").read_bytes(), name
    c = collect(tmp_path / "c", QUICK, videos=60, seed=5, progress=False)
    assert (a / "images.npy").read_bytes() != (c / "images.npy").read_bytes()


def test_interrupted_run_resumes_to_identical_result(tmp_path, monkeypatch):
    from dataclasses import replace

    from husky_course.config import get_profile

    prof = get_profile("quick")
    prof = replace(prof, data=replace(prof.data, shard_videos=10))
    ref = collect(tmp_path / "ref", prof, videos=50, seed=2, progress=False)
    real_job, done = collect_mod._shard_job, []

    def crashing_job(job):
        if len(done) == 3:
            raise KeyboardInterrupt("killed")
        done.append(real_job(job))
        return done[-1]

    monkeypatch.setattr(collect_mod, "_shard_job", crashing_job)
    out = tmp_path / "run"
    with pytest.raises(KeyboardInterrupt):
        collect(out, prof, videos=50, seed=2, progress=False)
    assert not (out / "meta.json").exists()
    shards = sorted((out / "shards").glob("shard_*.npz"))
    assert len(shards) == 3
    (out / "shards" / ".shard_00003.npz.999.tmp").write_bytes(b"half a shard")  # a killed write
    with pytest.raises(DatasetError, match="no meta.json"):
        load_dataset(out)  # a reader never mistakes an unfinished run for a dataset
    monkeypatch.setattr(collect_mod, "_shard_job", real_job)
    collect(out, prof, videos=50, seed=2, progress=False)
    for name in NAMES:
        assert (ref / f"{name}.npy").read_bytes() == (out / f"{name}.npy").read_bytes(), name


def test_bad_inputs_are_clear_and_lose_nothing(tmp_path, small_dataset_dir, capsys):
    with pytest.raises(ConfigError, match="expected a Profile"):
        collect(tmp_path / "x", "huge")
    with pytest.raises(ValueError, match="positive integer"):
        collect(tmp_path / "x", QUICK, videos=-5)
    with pytest.raises(ConfigError, match="unknown backend"):
        collect(tmp_path / "x", QUICK, videos=5, backend="unity")
    with pytest.raises(ValueError, match="workers"):
        collect(tmp_path / "x", QUICK, videos=5, workers=0)
    with pytest.raises(ValueError, match="collection seed"):
        collect(tmp_path / "x", QUICK, videos=5, seed=10**6)
    # a directory holding a dataset made with another config is refused, and left untouched
    out = collect(tmp_path / "d", QUICK, videos=8, progress=False)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    with pytest.raises(DatasetError, match="different config"):
        collect(out, QUICK, videos=9, progress=False)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    # truncated and corrupted arrays
    trunc = out / "labels.npy"
    trunc.write_bytes(trunc.read_bytes()[:-3])
    with pytest.raises(DatasetError, match="labels.npy"):
        load_dataset(out)
    with pytest.raises(DatasetError, match="truncated or corrupted"):
        load_dataset(out, verify=False)
    meta = json.loads((out / "meta.json").read_text())
    assert meta["videos"] == 8 and meta["backend"] == "fast" and "package_version" in meta
    # the CLI turns these into one-line errors with exit code 2
    assert cli_main(["stats", str(out)]) == 2
    assert "labels.npy" in capsys.readouterr().err
    assert cli_main(["collect", "--profile", "nope", "--out", str(tmp_path / "y")]) == 2
    assert cli_main(["stats", str(small_dataset_dir), "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed["videos"] == 120


def test_uniform_policy_replays_the_collection(small_dataset_dir):
    from husky_course.course.policies import policy_lengths

    ds = load_dataset(small_dataset_dir)  # collection seed 3, 120 videos
    lengths, played = policy_lengths(QUICK.sim, "uniform", 40, 3)
    np.testing.assert_array_equal(lengths, ds.lengths[:40])
    for v, prims in enumerate(played):
        np.testing.assert_array_equal(prims, ds.applied[ds.video(v)])


def test_random_network_policy_is_seeded_and_stops_at_a_collision():
    import torch

    from husky_course.course.policies import play_network_video, policy_lengths, random_network
    from husky_course.data.collect import world_seed_for
    from husky_course.sim.fast import FastSimulator

    state = torch.random.get_rng_state()
    lengths, played = policy_lengths(QUICK.sim, "random network", 12, 3)
    assert torch.equal(torch.random.get_rng_state(), state)  # the global torch stream is left alone
    again, played_again = policy_lengths(QUICK.sim, "random network", 12, 3)
    np.testing.assert_array_equal(lengths, again)
    assert all(np.array_equal(a, b) for a, b in zip(played, played_again, strict=True))
    assert ((lengths >= 1) & (lengths <= QUICK.sim.max_primitives)).all()
    sim = FastSimulator(QUICK.sim)
    for v, prims in enumerate(played):
        world = sim.load(world_seed_for(3, v))
        net = random_network(QUICK.sim, 3, v)
        with torch.no_grad():  # the first choice is the fresh network's argmax on the start image
            first = int(net(torch.from_numpy(sim.depth(world.start[None]).astype(np.float32)))[0].argmax())
        assert prims[0] == first
        pose, hits = world.start.copy(), []
        for step, a in enumerate(prims):
            result = sim.apply(pose, int(a), step)
            hits.append(result.collided)
            pose = result.pose
        assert not any(hits[:-1]) and (hits[-1] or len(prims) == QUICK.sim.max_primitives)
    np.testing.assert_array_equal(play_network_video(sim, 3, 5, QUICK.sim.max_primitives), played[5])
    with pytest.raises(ValueError, match="unknown policy"):
        policy_lengths(QUICK.sim, "softmax", 3, 3)
