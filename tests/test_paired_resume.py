"""``benchmarks/exp_moving_paired.py --save F`` keeps every finished world: a killed run loses only its
unfinished ones, and a run given ``F`` again reuses the worlds it holds (quick profile, tiny sizes)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "benchmarks" / "exp_moving_paired.py"


def paired(*args: str) -> subprocess.CompletedProcess:
    """The script at a tiny size in the quick profile, one worker, as a reader runs it."""
    env = {**os.environ, "HUSKY_PROFILE": "quick", "PYTHONUNBUFFERED": "1"}
    return subprocess.run([sys.executable, str(SCRIPT), "--profile", "quick", "--workers", "1", *args],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=300,
                          stdin=subprocess.DEVNULL)


def table(stdout: str) -> str:
    """The printed comparison without its timing."""
    return re.sub(r"\(\d+ s\)", "", stdout[stdout.index("discs on moving"):])


def test_a_saved_run_resumes_with_the_same_results(tmp_path: Path) -> None:
    saved = tmp_path / "paired.npz"
    first = paired("--worlds", "2", "--variants", "samples=0", "--save", str(saved))
    assert first.returncode == 0, first.stderr[-3000:]
    with np.load(saved, allow_pickle=False) as f:
        assert len(f["worlds"]) == 2 and len(f["seed"]) == len(f["driver"]) == len(f["fatal"])
    resumed = paired("--worlds", "3", "--variants", "samples=0", "--save", str(saved))
    assert resumed.returncode == 0, resumed.stderr[-3000:]
    assert "resuming from" in resumed.stdout and "2 of the 3 worlds done" in resumed.stdout
    fresh = paired("--worlds", "3", "--variants", "samples=0")
    assert fresh.returncode == 0, fresh.stderr[-3000:]
    assert "resuming" not in fresh.stdout
    assert table(resumed.stdout) == table(fresh.stdout)
    with np.load(saved, allow_pickle=False) as f:
        assert len(f["worlds"]) == 3


def test_a_saved_run_of_other_variants_or_code_is_refused(tmp_path: Path) -> None:
    saved = tmp_path / "paired.npz"
    assert paired("--worlds", "1", "--variants", "samples=0", "--save", str(saved)).returncode == 0
    other = paired("--worlds", "1", "--variants", "margin=0.05", "--save", str(saved))
    assert other.returncode != 0
    assert "name another --save file" in other.stderr
    with np.load(saved, allow_pickle=False) as f:  # the same variants, made by other code
        arrays = {k: f[k] for k in f.files}
    np.savez(saved, **{**arrays, "code": np.array("other code")})
    stale = paired("--worlds", "1", "--variants", "samples=0", "--save", str(saved))
    assert stale.returncode != 0
    assert "made by other code" in stale.stderr
