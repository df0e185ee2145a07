"""``data/before_sensing.npz``: what the simulator showed and did before sensing existed, the walk that
made it (:func:`play`, which ``test_sensing.py`` walks again) and, run as a script, its recorder.

Record it with the library of commit fc4c264 (the last one before :mod:`husky_course.sim.sensing`)::

    git worktree add /tmp/before-sensing fc4c264
    PYTHONPATH=/tmp/before-sensing python tests/before_sensing.py

It plays the same 4 worlds x 3 steps on both backends and both courses (random primitives, seed 0)
and keeps the depth images (per backend) and the played-back paths and collisions (per course: the
backends share them). ``tests/test_sensing.py`` compares today's ideal senses with them. It uses only
API that fc4c264 already had.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from husky_course.config import SimConfig, sim_for_world
from husky_course.sim.backends import make_simulator

WORLDS, STEPS = 4, 3
RECORD = Path(__file__).parent / "data" / "before_sensing.npz"


def play(sim, check: Callable[[np.ndarray, int, int], None] | None = None) -> tuple[np.ndarray, ...]:
    """Depth images ``(12, 50, 50)``, paths ``(12, S, 3)`` and collisions ``(12,)`` of the walk;
    ``check(pose, index, step)``, if given, is called before each primitive is played."""
    rng = np.random.default_rng(0)
    depth, paths, collided = [], [], []
    for seed in range(WORLDS):
        pose = sim.load(seed).start.copy()
        for step in range(STEPS):
            depth.append(sim.depth(pose[None], step)[0])
            index = int(rng.integers(25))
            if check is not None:
                check(pose, index, step)
            r = sim.apply(pose, index, step)
            paths.append(r.path)
            collided.append(r.collided)
            pose = r.pose
    return np.stack(depth), np.stack(paths), np.array(collided)


def main() -> None:
    out: dict[str, np.ndarray] = {}
    for kind in ("static", "moving"):
        for backend in ("fast", "pybullet"):
            with make_simulator(backend, sim_for_world(SimConfig(), kind)) as sim:
                depth, paths, collided = play(sim)
            out[f"{kind}_{backend}_depth"] = depth
            if f"{kind}_path" in out:
                assert np.array_equal(out[f"{kind}_path"], paths), "the backends played different paths"
                assert np.array_equal(out[f"{kind}_collided"], collided), "the backends' collisions differ"
            out[f"{kind}_path"], out[f"{kind}_collided"] = paths, collided
    np.savez_compressed(RECORD, **out)
    print(f"wrote {RECORD} ({RECORD.stat().st_size:,} bytes)")


if __name__ == "__main__":
    main()
