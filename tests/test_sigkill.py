"""A real SIGKILL in the middle of data collection and of training, then a restart.

Each test starts the work in a child process, kills it with SIGKILL as soon as it has written its
first resumable checkpoint (a shard, an epoch), starts it again in this process and checks that
the result is identical to an uninterrupted run.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
import torch

from husky_course.config import TrainConfig, get_profile
from husky_course.data.collect import collect
from husky_course.data.dataset import STEP_ARRAYS, VIDEO_ARRAYS
from husky_course.models.paper import EncoderDecoder
from husky_course.training.trainer import fit

QUICK = get_profile("quick")  # resolved once, passed down

REPO = Path(__file__).resolve().parents[1]


def _start(code: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.Popen([sys.executable, "-c", textwrap.dedent(code)], env=env, cwd=REPO)


def _kill_when(proc: subprocess.Popen, ready, timeout: float = 120.0) -> bool:
    """SIGKILL ``proc`` once ``ready()`` is true; False if it finished first."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if ready():
            proc.send_signal(signal.SIGKILL)
            proc.wait()
            return True
        if proc.poll() is not None:
            return False
        time.sleep(0.005)
    proc.kill()
    raise AssertionError("the child never reached the point where it should be killed")


def test_sigkill_during_collection_then_resume(tmp_path):
    out = tmp_path / "killed"
    proc = _start(
        f"""
        from husky_course.config import get_profile
        from husky_course.data.collect import collect
        collect({str(out)!r}, get_profile("quick"), videos=3000, seed=5, workers=1, progress=False)
        """
    )
    killed = _kill_when(
        proc,
        lambda: len(list((out / "shards").glob("shard_*.npz"))) >= 2 if (out / "shards").is_dir() else False,
    )
    assert killed, "collection finished before it could be killed; make it longer"
    assert proc.returncode == -signal.SIGKILL
    assert not (out / "meta.json").exists()
    collect(out, QUICK, videos=3000, seed=5, workers=1, progress=False)  # resume
    ref = tmp_path / "ref"
    collect(ref, QUICK, videos=3000, seed=5, workers=1, progress=False)
    for name in STEP_ARRAYS + VIDEO_ARRAYS:
        assert (out / f"{name}.npy").read_bytes() == (ref / f"{name}.npy").read_bytes(), name


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_sigkill_during_training_then_resume(tmp_path):
    run = tmp_path / "run"
    code = f"""
        import torch
        from husky_course.config import TrainConfig, get_profile
        from husky_course.models.paper import EncoderDecoder
        from husky_course.training.trainer import fit
        torch.set_num_threads(1)
        g = torch.Generator().manual_seed(0)
        def data(n, seed):
            g = torch.Generator().manual_seed(seed)
            image = torch.rand(n, 50, 50, generator=g)
            return {{"image": image, "prim": torch.randint(0, 25, (n,), generator=g),
                    "next": torch.roll(image, 1, 2)}}
        torch.manual_seed(0)
        cfg = TrainConfig(lr=3e-3, batch_size=32, epochs=8, patience=20)
        fit(EncoderDecoder(), data(256, 0), data(64, 1), cfg, run_dir={str(run)!r}, progress=False)
        """
    proc = _start(code)
    assert _kill_when(proc, lambda: (run / "last.pt").is_file()), "training finished before the kill"
    assert not (run / "model.pt").exists()

    def data(n: int, seed: int) -> dict[str, torch.Tensor]:
        g = torch.Generator().manual_seed(seed)
        image = torch.rand(n, 50, 50, generator=g)
        return {
            "image": image,
            "prim": torch.randint(0, 25, (n,), generator=g),
            "next": torch.roll(image, 1, 2),
        }

    cfg = TrainConfig(lr=3e-3, batch_size=32, epochs=8, patience=20)
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        torch.manual_seed(99)  # a different init: everything must come from last.pt
        resumed = EncoderDecoder()
        hist = fit(resumed, data(256, 0), data(64, 1), cfg, run_dir=run, progress=False)
        torch.manual_seed(0)
        ref = EncoderDecoder()
        ref_hist = fit(ref, data(256, 0), data(64, 1), cfg, progress=False)
    finally:
        torch.set_num_threads(threads)
    np.testing.assert_allclose(hist.train_loss, ref_hist.train_loss, rtol=1e-6)
    for a, b in zip(resumed.state_dict().values(), ref.state_dict().values(), strict=True):
        torch.testing.assert_close(a, b)
