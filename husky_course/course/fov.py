"""Choosing the camera's field of view: can the robot see what its next primitive would hit?

For a set of robot poses (e.g. those of the dataset), every primitive that collides is traced to
the obstacle (or wall) it touches first; that obstacle counts as *visible* if at least one column
of the depth image, rendered with a given field of view, shows it. A planner that sees only the
current image cannot avoid what is invisible, so this fraction caps it.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..config import SimConfig
from ..sim.fast import FastSimulator


def _first_hit_body(sim: FastSimulator, path: np.ndarray) -> int:
    """``1`` for a wall, ``2 + i`` for obstacle ``i``, ``0`` if the path is safe."""
    world = sim._require_world()
    k = sim.contact_along(path)
    if k < 0:
        return 0
    x, y = path[k, :2]
    obs = world.obstacles
    inside = np.hypot(obs[:, 0] - x, obs[:, 1] - y) < obs[:, 2] + world.config.robot_radius
    return 2 + int(np.flatnonzero(inside)[0]) if inside.any() else 1


def hit_visibility(
    world_seeds: np.ndarray, poses: np.ndarray, fovs: list[float], config: SimConfig | None = None
) -> dict[float, float]:
    """Fraction of colliding (pose, primitive) pairs whose hit obstacle is in view, per FOV.

    Parameters
    ----------
    world_seeds, poses : ndarray
        One world seed and one robot pose ``(x, y, yaw)`` per sample.
    fovs : list of float
        Fields of view to compare (degrees).
    """
    config = config or SimConfig()
    sims = {f: FastSimulator(replace(config, camera=replace(config.camera, fov_deg=f))) for f in fovs}
    base = FastSimulator(config)
    seen = dict.fromkeys(fovs, 0)
    total = 0
    for seed, pose in zip(np.asarray(world_seeds), np.asarray(poses, float), strict=True):
        world = base.load(int(seed))
        bodies = [_first_hit_body(base, base.library.path_from(pose, k)) for k in range(base.library.n)]
        hits = {b for b in bodies if b >= 2}
        if not hits:
            continue
        n_hit = sum(b >= 2 for b in bodies)
        total += n_hit
        for f, sim in sims.items():
            sim.load(world)
            _, kind = sim.column_hits(pose[None])
            visible = set(np.unique(kind[0]).tolist())
            seen[f] += sum(1 for b in bodies if b >= 2 and b in visible)
    return {f: (seen[f] / total if total else float("nan")) for f in fovs}
