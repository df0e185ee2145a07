"""Devices: ``--device``/``HUSKY_DEVICE`` resolved in one place; checkpoints portable across devices.

This machine may have no GPU: the CUDA round trip is then skipped (saying so), and what is checked
is everything a CPU-only run can prove — the choice is resolved and refused clearly, training and
batched inference on the CPU give the same numbers whichever way the CPU was chosen, the model
ends on the CPU and its checkpoint holds only CPU tensors.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from husky_course import device as devices
from husky_course.cli import main
from husky_course.config import TrainConfig
from husky_course.models.paper import EncoderDecoder
from husky_course.training.inference import encode, predict_next
from husky_course.training.trainer import fit, read_checkpoint

HAS_CUDA = torch.cuda.is_available()


def _pairs(n: int = 64, seed: int = 0) -> dict[str, torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    image = torch.rand(n, 50, 50, generator=g)
    return {"image": image, "prim": torch.randint(0, 25, (n,), generator=g), "next": image.roll(1, 2)}


def test_names_resolve_and_bad_ones_are_refused(monkeypatch):
    monkeypatch.delenv(devices.ENV, raising=False)
    assert devices.resolve_device("cpu") == torch.device("cpu")
    assert devices.resolve_device("auto").type == ("cuda" if HAS_CUDA else "cpu")
    assert devices.resolve_device().type == ("cuda" if HAS_CUDA else "cpu")  # the default is auto
    monkeypatch.setenv(devices.ENV, "cpu")
    assert devices.resolve_device() == torch.device("cpu")
    with pytest.raises(ValueError, match="unknown device 'tpu'"):
        devices.resolve_device("tpu")
    if not HAS_CUDA:
        with pytest.raises(ValueError, match="no CUDA GPU"):
            devices.resolve_device("cuda")


def test_cli_choice_wins_over_the_environment(monkeypatch):
    monkeypatch.setenv(devices.ENV, "auto")
    monkeypatch.setattr(devices, "_chosen", None)
    devices.set_device("cpu")
    assert devices.resolve_device() == torch.device("cpu")
    if not HAS_CUDA:
        with pytest.raises(ValueError, match="no CUDA"):
            devices.set_device("cuda")  # refused at once, before any work


def test_training_on_the_chosen_cpu_equals_the_default_and_saves_cpu_tensors(tmp_path, monkeypatch):
    monkeypatch.setattr(devices, "_chosen", None)
    monkeypatch.setenv(devices.ENV, "cpu")
    cfg = TrainConfig(epochs=2, batch_size=16, lr=1e-3, patience=5, seed=0)
    runs = []
    for i, device in enumerate((None, "cpu")):
        torch.manual_seed(0)
        model = EncoderDecoder()
        fit(model, _pairs(), _pairs(32, 1), cfg, run_dir=tmp_path / f"r{i}", progress=False, device=device)
        assert next(model.parameters()).device.type == "cpu"
        runs.append(model)
        state = read_checkpoint(tmp_path / f"r{i}" / "model.pt")["state_dict"]
        assert all(t.device.type == "cpu" for t in state.values())
    for a, b in zip(runs[0].state_dict().values(), runs[1].state_dict().values(), strict=True):
        assert torch.equal(a, b)


def test_batched_inference_leaves_the_model_where_it_was(monkeypatch):
    monkeypatch.setattr(devices, "_chosen", None)
    torch.manual_seed(0)
    model = EncoderDecoder().eval()
    x = torch.rand(5, 50, 50)
    z = encode(model.encoder, x, batch=2)
    with torch.no_grad():
        assert np.allclose(z, model.encoder(x).numpy(), atol=1e-6)
    out = predict_next(model, x.numpy(), np.arange(5), batch=2)
    assert out.shape == (5, 50, 50) and next(model.parameters()).device.type == "cpu"


@pytest.mark.skipif(not HAS_CUDA, reason="no CUDA GPU on this machine: the GPU round trip cannot run")
def test_a_checkpoint_trained_on_the_gpu_loads_and_decides_on_the_cpu(tmp_path):
    cfg = TrainConfig(epochs=1, batch_size=16, lr=1e-3, patience=5, seed=0)
    torch.manual_seed(0)
    gpu = EncoderDecoder()
    fit(gpu, _pairs(), _pairs(32, 1), cfg, run_dir=tmp_path / "gpu", progress=False, device="cuda")
    cpu = EncoderDecoder()
    fit(cpu, _pairs(), _pairs(32, 1), cfg, run_dir=tmp_path / "gpu", progress=False, device="cpu")  # loads
    for a, b in zip(gpu.state_dict().values(), cpu.state_dict().values(), strict=True):
        assert torch.equal(a, b)


def test_cli_device_errors_are_one_line(capsys):
    with pytest.raises(SystemExit):
        main(["evaluate", "--planner", "random", "--device", "tpu"])
    assert "invalid choice: 'tpu'" in capsys.readouterr().err
    if not HAS_CUDA:
        code = main(["train", "encoder_decoder", "--profile", "quick", "--device", "cuda", "--no-progress"])
        assert code != 0
        assert "no CUDA GPU" in capsys.readouterr().err
