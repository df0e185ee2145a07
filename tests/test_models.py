"""Models, the trainer and checkpoints (issue 3)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from husky_course.config import TrainConfig, get_profile
from husky_course.evaluation.metrics import classification, image_errors, reliability, roc_auc
from husky_course.models.base import count_parameters, encode_primitive
from husky_course.models.paper import EncoderDecoder, LatentRewardNet
from husky_course.models.safety import JointModel, SafetyNet
from husky_course.training.trainer import CheckpointError, History, fit, load_model, save_model

QUICK = get_profile("quick")  # resolved once, passed down


def _tiny_pairs(n: int = 96, seed: int = 0) -> dict[str, torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    image = torch.rand(n, 50, 50, generator=g)
    prim = torch.randint(0, 25, (n,), generator=g)
    nxt = torch.roll(image, shifts=1, dims=2)  # a learnable "next image"
    return {"image": image, "prim": prim, "next": nxt}


def test_shapes_and_parameter_counts():
    torch.manual_seed(0)
    x = torch.rand(4, 50, 50)
    ed = EncoderDecoder()
    assert ed.encoder(x).shape == (4, 15)
    with torch.no_grad():
        out = ed(x, torch.tensor([0, 3, 12, 24]))
    assert out.shape == (4, 50, 50) and float(out.min()) >= 0 and float(out.max()) <= 1
    # encoder: BN(2) + conv1(32*100+32) + conv2(16*32*64+16) + fc(784*15+15)
    assert count_parameters(ed.encoder) == 2 + 3232 + 32784 + 11775
    assert (
        count_parameters(ed.decoder) == 16 * 64 + 64 + 64 * 256 + 256 + 256 * 1024 + 1024 + 1024 * 2500 + 2500
    )
    rn = LatentRewardNet()
    pair = rn(torch.randn(5, 15))
    assert pair.shape == (5, 2)
    torch.testing.assert_close(pair.sum(1), torch.ones(5))
    joint = JointModel()
    probs = joint.collision_probs(x)
    assert probs.shape == (4, 25) and bool(((probs >= 0) & (probs <= 1)).all())


def test_encoder_fast_path_equals_the_layers():
    """Encoder's fused BatchNorm + first convolution: same outputs, gradients and running statistics
    as running ``features`` layer by layer (the paper's definition), in training and in evaluation."""
    torch.manual_seed(0)
    fast, ref = EncoderDecoder().encoder, EncoderDecoder().encoder
    ref.load_state_dict(fast.state_dict())
    with torch.no_grad():  # a BatchNorm away from its initial identity, so its scale and shift matter
        for e in (fast, ref):
            e.features[0].weight.fill_(1.7)
            e.features[0].bias.fill_(-0.3)
    x = torch.rand(6, 1, 50, 50) * 0.8 + 0.1
    for step in range(2):  # two training steps: running statistics accumulate identically
        fast.train(), ref.train()
        out_fast = fast.unchecked(x + 0.05 * step)
        out_ref = ref.fc(ref.features(x + 0.05 * step))
        torch.testing.assert_close(out_fast, out_ref, rtol=1e-5, atol=1e-5)
        (out_fast**2).sum().backward()
        (out_ref**2).sum().backward()
        for (name, a), (_, b) in zip(fast.named_parameters(), ref.named_parameters(), strict=True):
            torch.testing.assert_close(a.grad, b.grad, rtol=1e-4, atol=1e-5, msg=lambda m, n=name: f"{n} {m}")
        for (name, a), (_, b) in zip(fast.named_buffers(), ref.named_buffers(), strict=True):
            torch.testing.assert_close(a, b, msg=lambda m, n=name: f"{n}: {m}")
    assert int(fast.features[0].num_batches_tracked) == 2
    fast.eval(), ref.eval()  # evaluation runs the layers; the fused path agrees with running statistics too
    with torch.no_grad():
        torch.testing.assert_close(fast._norm_conv(x), ref.features[:2](x), rtol=1e-5, atol=1e-5)
        torch.testing.assert_close(fast(x[:, 0]), ref.fc(ref.features(x)), rtol=1e-5, atol=1e-5)


def test_primitive_encoding_and_bad_inputs():
    torch.testing.assert_close(
        encode_primitive(torch.tensor([0, 12, 24]), 25), torch.tensor([[-1.0], [0.0], [1.0]])
    )
    with pytest.raises(ValueError, match="0..24"):
        encode_primitive(torch.tensor([25]), 25)
    with pytest.raises(TypeError):
        encode_primitive(torch.tensor([1.5]), 25)
    ed = EncoderDecoder()
    with pytest.raises(ValueError, match="shape"):
        ed.encoder(torch.rand(2, 40, 40))
    with pytest.raises(ValueError, match="floating"):
        ed.encoder(torch.zeros(2, 50, 50, dtype=torch.int64))


def test_training_lowers_the_loss_and_is_deterministic():
    data = _tiny_pairs()
    cfg = TrainConfig(lr=3e-3, batch_size=32, epochs=6, patience=10)
    runs = []
    for _ in range(2):
        torch.manual_seed(0)
        model = EncoderDecoder()
        runs.append(fit(model, data, _tiny_pairs(32, seed=1), cfg, progress=False))
    assert runs[0].train_loss[-1] < runs[0].train_loss[0] - 0.01
    assert runs[0].train_loss == runs[1].train_loss  # same seed, same losses on CPU


def test_checkpoint_round_trip(tmp_path):
    data, val = _tiny_pairs(), _tiny_pairs(32, seed=1)
    cfg = TrainConfig(lr=3e-3, batch_size=32, epochs=3, patience=10)
    torch.manual_seed(0)
    model = EncoderDecoder()
    hist = fit(model, data, val, cfg, run_dir=tmp_path, fingerprint={"x": 1}, progress=False)
    assert (tmp_path / "model.pt").is_file() and not (tmp_path / "last.pt").exists()
    reloaded = EncoderDecoder()
    again = load_model(tmp_path / "model.pt", reloaded, fingerprint={"x": 1, "train": cfg.__dict__})
    assert again.train_loss == hist.train_loss
    for a, b in zip(model.state_dict().values(), reloaded.state_dict().values(), strict=True):
        torch.testing.assert_close(a, b)
    # a finished run is loaded, not retrained
    torch.manual_seed(5)
    third = EncoderDecoder()
    assert (
        fit(third, data, val, cfg, run_dir=tmp_path, fingerprint={"x": 1}, progress=False).train_loss
        == hist.train_loss
    )


def test_killed_run_resumes_to_the_same_result(tmp_path, monkeypatch):
    data, val = _tiny_pairs(), _tiny_pairs(32, seed=1)
    cfg = TrainConfig(lr=3e-3, batch_size=32, epochs=4, patience=10)
    torch.manual_seed(0)
    ref = EncoderDecoder()
    ref_hist = fit(ref, data, val, cfg, run_dir=tmp_path / "ref", progress=False)

    import husky_course.training.trainer as training

    calls = {"n": 0}
    real_save = training._save

    def dying_save(path, payload):
        real_save(path, payload)
        calls["n"] += 1
        if calls["n"] == 2:  # killed right after the second epoch's checkpoint
            raise KeyboardInterrupt

    monkeypatch.setattr(training, "_save", dying_save)
    torch.manual_seed(0)
    with pytest.raises(KeyboardInterrupt):
        fit(EncoderDecoder(), data, val, cfg, run_dir=tmp_path / "run", progress=False)
    monkeypatch.setattr(training, "_save", real_save)
    assert (tmp_path / "run" / "last.pt").is_file() and not (tmp_path / "run" / "model.pt").exists()
    torch.manual_seed(123)  # different init: the resume must load everything from last.pt
    again = EncoderDecoder()
    hist = fit(again, data, val, cfg, run_dir=tmp_path / "run", progress=False)
    assert hist.train_loss == ref_hist.train_loss
    for a, b in zip(ref.state_dict().values(), again.state_dict().values(), strict=True):
        torch.testing.assert_close(a, b)


def test_wrong_architecture_or_config_is_refused(tmp_path):
    model = EncoderDecoder()
    save_model(tmp_path / "m.pt", model, {"data": "abc"}, History())
    with pytest.raises(CheckpointError, match="architecture"):
        load_model(tmp_path / "m.pt", JointModel())
    with pytest.raises(CheckpointError, match="another config"):
        load_model(tmp_path / "m.pt", EncoderDecoder(), fingerprint={"data": "xyz"})
    (tmp_path / "bad.pt").write_bytes(b"not a checkpoint")
    with pytest.raises(CheckpointError, match="not a readable"):
        load_model(tmp_path / "bad.pt", EncoderDecoder())
    with pytest.raises(CheckpointError, match="missing"):
        load_model(tmp_path / "none.pt", EncoderDecoder())


def test_safety_nets_and_joint_loss():
    torch.manual_seed(0)
    batch = {
        "image": torch.rand(8, 50, 50),
        "prim": torch.randint(0, 25, (8,)),
        "label": torch.tensor([0, 1] * 4).float(),
        "next": torch.rand(8, 50, 50),
        "has_next": torch.tensor([True, False] * 4),
    }
    for model in (SafetyNet(True), SafetyNet(False), JointModel()):
        loss = model.loss(batch)
        assert loss.ndim == 0 and torch.isfinite(loss)
    with pytest.raises(ValueError, match="prim"):
        SafetyNet(True).logit(batch["image"])


def test_metrics():
    y = np.array([0, 0, 1, 1])
    assert roc_auc(y, np.array([0.1, 0.4, 0.35, 0.8])) == 0.75
    assert roc_auc(y, np.array([0.5, 0.5, 0.5, 0.5])) == 0.5
    c = classification(y, np.array([0.1, 0.2, 0.9, 0.4]))
    assert c.accuracy == 0.75 and c.majority == 0.5
    r = reliability(y, np.array([0.05, 0.05, 0.95, 0.95]), bins=10)
    assert r["count"].sum() == 4 and float(r["ece"]) == pytest.approx(0.05)
    img = np.full((2, 50, 50), 0.3)
    e = image_errors(img, img)
    assert e.mae == 0 and e.column_iou == 1.0 and e.depth_error_m == 0
    with pytest.raises(ValueError, match="NaN"):
        roc_auc(y, np.array([0.1, np.nan, 0.2, 0.3]))


def test_diagnosis_is_cached_and_round_trips():
    """Chapter 4's variants and probes: built once (``make test`` trains them up front), then read."""
    import json

    from husky_course.course import diagnosis

    first = diagnosis.get_diagnosis(QUICK, progress=False)
    assert [r.variant for r in first.variants] == list(diagnosis.VARIANTS)
    assert set(first.probes) == {
        "raw image (2,500 pixels)",
        "frozen latent (15)",
        "untrained encoder's latent (15)",
    }
    again = diagnosis.get_diagnosis(QUICK, progress=False)  # from results.json: no training
    assert again.to_dict() == json.loads(json.dumps(first.to_dict()))
    assert [r.history.seconds for r in again.variants] == [r.history.seconds for r in first.variants]
    faithful, off_by_one = again.variants[0].quality, again.variants[1].quality
    assert faithful.n == off_by_one.n > 0  # both scored on the same validation images, true labels
    # what the slip does: trained to flag the frame *before* a collision and scored on the true labels,
    # the off-by-one net ranks collisions far worse than the faithful one, no better than chance
    assert off_by_one.auc < min(0.5, faithful.auc - 0.2), (off_by_one.auc, faithful.auc)
    assert diagnosis.failed(off_by_one) and not diagnosis.failed(faithful)


def test_sign_test_of_paired_outcomes():
    from husky_course.course.diagnosis import sign_test

    a = np.array([1, 1, 1, 1, 1, 1, 0, 1], bool)
    b = np.array([0, 0, 0, 0, 0, 0, 0, 1], bool)
    assert sign_test(a, b) == (6, 0, pytest.approx(2 / 2**6))  # six discordant pairs, all one way
    assert sign_test(b, a)[:2] == (0, 6) and sign_test(a, a) == (0, 0, 1.0)
    assert sign_test([1, 0, 1], [0, 1, 1]) == (1, 1, 1.0)
    assert sign_test([1] * 3 + [0] * 2, [0] * 3 + [1] * 2)[2] == 1.0  # 3 against 2
    assert abs(sign_test([1] * 25 + [0] * 5, [0] * 25 + [1] * 5)[2] - 0.000325) < 1e-5  # 25 against 5
    with pytest.raises(ValueError, match="equal shapes"):
        sign_test(a, b[:3])
