"""``benchmarks/exp_moving_variants.py --base F`` keeps the planner's own episodes: a second run with the
same key reads them (and prints the same table), a file of another key is never read (quick profile, tiny
sizes)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "benchmarks" / "exp_moving_variants.py"


def variants(base: Path) -> subprocess.CompletedProcess:
    """The script on two tuning worlds in the quick profile, one worker, its base kept in ``base``."""
    env = {**os.environ, "HUSKY_PROFILE": "quick", "PYTHONUNBUFFERED": "1"}
    args = ["--profile", "quick", "--workers", "1", "--worlds", "2", "--base", str(base),
            "--variants", "doubt:nothing doubted"]
    done = subprocess.run([sys.executable, str(SCRIPT), *args], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=300, stdin=subprocess.DEVNULL)
    assert done.returncode == 0, done.stderr[-3000:]
    return done


def table(stdout: str) -> list[str]:
    """The printed success lines."""
    return re.findall(r"^  \(as it is\) .*$|^  doubt:.*$", stdout, flags=re.M)


def test_a_kept_base_is_read_under_its_key_only(tmp_path: Path) -> None:
    base = tmp_path / "base.npz"
    first = variants(base)
    assert "read from" not in first.stdout and base.exists()
    assert len(table(first.stdout)) == 2
    again = variants(base)
    assert f"read from {base}" in again.stdout
    assert table(again.stdout) == table(first.stdout)
    with np.load(base, allow_pickle=False) as f:
        won = f["won"]
    np.savez(base, key="another", won=~won)  # another key's file, holding the opposite outcomes
    stale = variants(base)
    assert "holds another key" in stale.stdout and "read from" not in stale.stdout
    assert table(stale.stdout) == table(first.stdout)
    with np.load(base, allow_pickle=False) as f:
        assert str(f["key"]) != "another" and (f["won"] == won).all()
