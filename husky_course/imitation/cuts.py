"""Training the cut network (:class:`~husky_course.models.cuts.CutNet`) from simulated views.

Supervised, with the simulator as the labeller, on the planner's own perception, after the disc
network (:mod:`husky_course.imitation.discs`), whose read of each piece is one of its inputs:

1. **views**: the disc network's own training views (the same worlds and poses);
2. **boundaries**: each image is cut into pieces as the planner cuts it
   (:meth:`~husky_course.planners.discs.PieceReader.pieces`), the trained disc network reads each
   piece, and every boundary between two consecutive points of a piece gets its features
   (:func:`~husky_course.planners.cuts.cut_features`);
3. **labels**: a boundary is a cut when the columns on either side hit two different cylinders
   (:meth:`~husky_course.sim.fast.FastSimulator.column_hits`);
4. **fit**: :func:`~husky_course.training.trainer.fit`, one training world in ten validating.

The boundaries (``boundaries.npz``) and the network (``model.pt``) are artifacts under
``artifacts/<profile>/models/cuts-<hash>/``, their key holding the disc network's.
"""

from __future__ import annotations

import numpy as np
import torch

from ..config import Profile, with_world
from ..data.collect import world_seed_for
from ..data.io import atomic_save_npz, load_npz
from ..data.store import runs_dir
from ..models.cuts import CutNet
from ..models.discs import DiscNet
from ..planners.cuts import cut_features
from ..planners.discs import DiscMap
from ..progress import announce_build, tqdm
from ..sim.fast import FastSimulator
from ..training.cuts import cut_dir, cut_fingerprint, new_cut_net
from ..training.trainer import History, fit
from .discs import get_discs, view_poses


def boundary_views(profile: Profile, discs: DiscNet, progress: bool = True) -> dict[str, np.ndarray]:
    """Every boundary of every piece of the disc network's training views, with its label."""
    cfg, sim_cfg = profile.discs, profile.sim
    sim, reader = FastSimulator(sim_cfg), DiscMap(discs, sim_cfg)
    max_x = (sim_cfg.max_primitives - 1) * sim_cfg.primitives.advance
    feats, cuts, seeds = [], [], []
    for v in tqdm(range(cfg.worlds), desc="cut views", unit="world", disable=not progress):
        seed = world_seed_for(cfg.collection_seed, v)
        world = sim.load(seed)
        poses = view_poses(world, cfg.poses_per_world, np.random.default_rng([cfg.collection_seed, v]), max_x)
        _, kinds = sim.column_hits(poses)
        for image, kind in zip(sim.depth(poses), kinds, strict=True):
            d, cols, pts, pieces = reader.reader.pieces(image)
            if not pieces:
                continue
            f, piece, at = cut_features(reader, d, cols, pts, pieces)
            left = np.array([pieces[k][i] for k, i in zip(piece, at, strict=True)], int)
            a, b = kind[cols[left]], kind[cols[left + 1]]
            feats.append(f)
            cuts.append((a != b) & (a >= 2) & (b >= 2))
            seeds.append(np.full(len(f), seed, np.int64))
    return {"features": np.concatenate(feats).astype(np.float32), "cut": np.concatenate(cuts),
            "world_seed": np.concatenate(seeds)}


def get_cuts(profile: Profile, progress: bool = True) -> tuple[CutNet, History, str]:
    """The trained cut network ``(model, history, path)``, built first if it is missing, the disc
    network it reads with first of all (:func:`~husky_course.imitation.discs.get_discs`; both on the
    static course's views)."""
    profile = with_world(profile, "static")
    run = cut_dir(profile)
    if not (run / "model.pt").is_file():
        announce_build("cuts", profile.name, "train cuts")
    discs = get_discs(profile, progress)[0]
    run.mkdir(parents=True, exist_ok=True)
    views = run / "boundaries.npz"
    if not views.is_file():
        atomic_save_npz(views, boundary_views(profile, discs, progress))
    data = load_npz(views)
    in_val = data["world_seed"] % 10 == 0
    model = new_cut_net(profile)
    fp = cut_fingerprint(profile)

    def rows(mask: np.ndarray) -> dict[str, torch.Tensor]:
        return {k: torch.from_numpy(data[k][mask]) for k in ("features", "cut")}

    history = fit(model, rows(~in_val), rows(in_val), profile.discs.cut_train, run_dir=run, fingerprint=fp,
                  log_dir=runs_dir("cuts", fp, profile), progress=progress, desc="cut network")
    return model, history, str(run / "model.pt")
