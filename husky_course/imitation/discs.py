"""Training the disc network (:class:`~husky_course.models.discs.DiscNet`) from simulated views.

Supervised learning with the simulator as the labeller, on the planner's own perception:

1. **views**: in each of ``DiscConfig.worlds`` training worlds (collection seed
   ``DiscConfig.collection_seed``, never an evaluation world), ``poses_per_world`` random decision
   poses (heading 0, ``x`` where a decision is taken, clear of every cylinder and wall), rendered
   by the fast simulator;
2. **pieces**: each image is read exactly as the planner reads it
   (:class:`~husky_course.planners.discs.PieceReader`: scan, pieces, features);
3. **labels**: the simulator says what each column's ray hit first
   (:meth:`~husky_course.sim.fast.FastSimulator.column_hits`); a piece is a cylinder's when most of
   its columns hit a cylinder, and its target is that cylinder's centre (in the piece's frame) and
   radius;
4. **fit**: :func:`~husky_course.training.trainer.fit`, one training world in ten validating.

The views (``pieces.npz``) and the network (``model.pt``, resumable per epoch) are artifacts under
``artifacts/<profile>/models/discs-<hash>/``; a killed build resumes and ends with the same bytes.
"""

from __future__ import annotations

import numpy as np
import torch

from ..config import Profile, with_world
from ..data.collect import world_seed_for
from ..data.io import atomic_save_npz, load_npz
from ..data.store import runs_dir
from ..models.discs import DiscNet
from ..planners.discs import PieceReader, majority_cylinder
from ..progress import announce_build, tqdm
from ..sim.fast import FastSimulator
from ..training.discs import disc_dir, disc_fingerprint, new_disc_net
from ..training.trainer import History, fit

KEYS = ("features", "cylinder", "centre", "radius", "world_seed")


def view_poses(world, count: int, rng: np.random.Generator, max_x: float) -> np.ndarray:
    """``count`` random decision poses ``(count, 3)`` in ``world``, clear of its cylinders and walls."""
    cfg = world.config
    lim = world.wall_y - cfg.robot_radius
    out: list[np.ndarray] = []
    while len(out) < count:
        xy = np.c_[rng.uniform(0.0, max_x, 4 * count), rng.uniform(-lim, lim, 4 * count)]
        gap = np.hypot(*(xy[:, None] - world.obstacles[None, :, :2]).transpose(2, 0, 1))
        clear = (gap > world.obstacles[None, :, 2] + cfg.robot_radius).all(1)
        out.extend(xy[clear])
    xy = np.asarray(out[:count])
    return np.c_[xy, np.zeros(count)]


def piece_views(profile: Profile, progress: bool = True) -> dict[str, np.ndarray]:
    """Every piece of every training view, with its features and its label (see the module)."""
    cfg, sim_cfg = profile.discs, profile.sim
    sim, reader = FastSimulator(sim_cfg), PieceReader(sim_cfg)
    max_x = (sim_cfg.max_primitives - 1) * sim_cfg.primitives.advance  # where decisions are taken
    out: dict[str, list] = {k: [] for k in KEYS}
    for v in tqdm(range(cfg.worlds), desc="disc views", unit="world", disable=not progress):
        seed = world_seed_for(cfg.collection_seed, v)
        world = sim.load(seed)
        poses = view_poses(world, cfg.poses_per_world, np.random.default_rng([cfg.collection_seed, v]), max_x)
        images = sim.depth(poses)
        _, kinds = sim.column_hits(poses)
        for pose, image, kind in zip(poses, images, kinds, strict=True):
            d, cols, pts, pieces = reader.pieces(image)
            for idx in pieces:
                feats, (mean, ray, across) = reader.features(pts[idx], cols[idx], d)
                hit = majority_cylinder(kind[cols[idx]])
                cyl = hit >= 0
                centre, radius = np.zeros(2), 0.0
                if cyl:
                    ox, oy, radius = world.obstacles[hit]
                    rel = np.array([ox, oy]) - pose[:2] - mean  # robot frame = world shifted (heading 0)
                    centre = np.array([rel @ ray, rel @ across])
                out["features"].append(feats)
                out["cylinder"].append(cyl)
                out["centre"].append(centre)
                out["radius"].append(radius)
                out["world_seed"].append(seed)
    return {
        "features": np.asarray(out["features"], np.float32),
        "cylinder": np.asarray(out["cylinder"], bool),
        "centre": np.asarray(out["centre"], np.float32),
        "radius": np.asarray(out["radius"], np.float32),
        "world_seed": np.asarray(out["world_seed"], np.int64),
    }


def _tensors(data: dict[str, np.ndarray], rows: np.ndarray) -> dict[str, torch.Tensor]:
    return {k: torch.from_numpy(data[k][rows]) for k in ("features", "cylinder", "centre", "radius")}


def get_discs(profile: Profile, progress: bool = True) -> tuple[DiscNet, History, str]:
    """The trained disc network ``(model, history, path)``, built first if it is missing (always on
    the static course's views: :func:`~husky_course.training.discs.disc_fingerprint`)."""
    profile = with_world(profile, "static")
    run = disc_dir(profile)
    if not (run / "model.pt").is_file():
        announce_build("discs", profile.name, "train discs")
    run.mkdir(parents=True, exist_ok=True)
    views = run / "pieces.npz"
    if not views.is_file():
        atomic_save_npz(views, piece_views(profile, progress))
    data = load_npz(views)
    in_val = data["world_seed"] % 10 == 0
    model = new_disc_net(profile)
    fp = disc_fingerprint(profile)
    history = fit(
        model, _tensors(data, np.flatnonzero(~in_val)), _tensors(data, np.flatnonzero(in_val)),
        profile.discs.train, run_dir=run, fingerprint=fp, log_dir=runs_dir("discs", fp, profile),
        progress=progress, desc="disc network",
    )
    return model, history, str(run / "model.pt")
