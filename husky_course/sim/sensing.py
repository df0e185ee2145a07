"""A real robot's senses in the simulator: a noisy depth camera and slipping wheels (chapter 11).

The models and the figures they take from a sensor's datasheet are in
:mod:`husky_course.config.sensing`. Both are applied by the simulator's shared code
(:meth:`husky_course.sim.base.Simulator.depth` and :meth:`~husky_course.sim.base.Simulator.apply`),
so the fast backend and PyBullet see the same noise on the same views and play back the same
executed paths. Under ideal sensing nothing here runs, and every array is the renderer's, bit for bit.

Every draw is a pure function of (sensing seed, world seed, step, what is drawn): the same episode
gives the same bytes, and a batch of views at one step (a figure's candidates) gets one independent
draw per pose.
"""

from __future__ import annotations

import zlib

import numpy as np

from ..config import CameraConfig, SensingConfig
from .camera import denormalize_depth, normalize_depth
from .primitives import PrimitiveLibrary

_CAMERA, _WHEELS = 1, 2  #: the two streams of random numbers


def sensing_rng(
    cfg: SensingConfig, world_seed: int, t: float, stream: int, salt: int = 0,
) -> np.random.Generator:
    """The generator for one draw: a pure function of the sensing seed, the world seed, the time
    ``t`` (steps; fractions kept to a thousandth), the stream and a ``salt`` (a pose's hash)."""
    entropy = [int(cfg.seed), int(world_seed), int(round(float(t) * 1000)), int(stream), int(salt)]
    if min(entropy) < 0:
        raise ValueError(f"seeds and times must be >= 0 for the sensing noise, got {entropy}")
    return np.random.default_rng(np.random.SeedSequence(entropy))


def _pose_salt(pose: np.ndarray) -> int:
    return zlib.crc32(np.ascontiguousarray(pose, np.float64).tobytes())


def depth_edges(z: np.ndarray, jump: float) -> np.ndarray:
    """Pixels ``(H, W)`` of depth ``z`` (m) deeper than a 4-neighbour by over ``jump``: the far side
    of a depth edge, where a stereo camera's second view is occluded (its "shadow")."""
    edge = np.zeros(z.shape, bool)
    dv, dh = np.diff(z, axis=0), np.diff(z, axis=1)  # next minus this
    edge[1:] |= dv > jump  # deeper than the pixel above
    edge[:-1] |= -dv > jump  # deeper than the pixel below
    edge[:, 1:] |= dh > jump
    edge[:, :-1] |= -dh > jump
    return edge


def noisy_depth(
    images: np.ndarray, poses: np.ndarray, times: np.ndarray, world_seed: int, cfg: SensingConfig,
    camera: CameraConfig,
) -> np.ndarray:
    """What the modelled depth camera reports for the renderer's ``images`` ``(B, H, W)`` (normalised).

    Per pixel that sees something within ``far``: depth ``z`` plus Gaussian error of standard
    deviation ``sigma_k * z**2``, rounded to ``depth_unit``; then "no reading" (``far``, a normalised
    1) where the true depth is under ``min_range``, at random with probability ``dropout``, and on the
    far side of a depth edge (:func:`depth_edges`) with probability ``edge_dropout``.
    """
    if cfg.camera_ideal:
        return images
    images = np.asarray(images, np.float32)
    poses = np.asarray(poses, float).reshape(-1, 3)
    z = denormalize_depth(images, camera)
    out = np.empty_like(images)
    for b in range(len(images)):
        rng = sensing_rng(cfg, world_seed, float(times[b]), _CAMERA, _pose_salt(poses[b]))
        zb = z[b]
        gauss, coin, edge_coin = rng.standard_normal(zb.shape), rng.random(zb.shape), rng.random(zb.shape)
        seen = images[b] < 1.0
        noisy = np.where(seen, zb + cfg.sigma_k * zb**2 * gauss, camera.far)
        if cfg.depth_unit > 0:
            noisy = np.round(noisy / cfg.depth_unit) * cfg.depth_unit
        invalid = (zb < cfg.min_range) | (coin < cfg.dropout)
        if cfg.edge_dropout > 0:
            invalid |= depth_edges(zb, cfg.edge_jump) & (edge_coin < cfg.edge_dropout)
        out[b] = normalize_depth(np.where(invalid | ~seen, camera.far, noisy), camera)
    return out


def executed_local_path(local: np.ndarray, scale: float, heading: float) -> np.ndarray:
    """A primitive's recorded poses ``local`` ``(S, 3)`` (start frame) as the wheels execute them:
    every step along it ``scale`` times as long, and turned by a heading error that grows evenly from
    0 at the start to ``heading`` (rad) at the end."""
    local = np.asarray(local, float)
    phi = heading * np.linspace(0.0, 1.0, len(local))
    d = np.diff(local[:, :2], axis=0) * scale
    c, s = np.cos(phi[:-1]), np.sin(phi[:-1])
    turned = np.stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]], axis=1)
    out = np.empty_like(local)
    out[0] = local[0]
    out[1:, :2] = local[0, :2] + np.cumsum(turned, axis=0)
    out[:, 2] = local[:, 2] + phi
    return out


def slip(cfg: SensingConfig, world_seed: int, t: float, pose: np.ndarray) -> tuple[float, float]:
    """The executed primitive's length factor and heading error (rad) at time ``t`` from ``pose``."""
    if cfg.wheels_ideal:
        return 1.0, 0.0
    rng = sensing_rng(cfg, world_seed, t, _WHEELS, _pose_salt(np.asarray(pose, float)))
    e, h = rng.standard_normal(2)
    return 1.0 + cfg.slip_scale * float(e), float(np.radians(cfg.slip_heading_deg) * h)


def executed_path(
    library: PrimitiveLibrary, pose: np.ndarray, index: int, cfg: SensingConfig, world_seed: int, t: float,
) -> np.ndarray:
    """World poses ``(S, 3)`` of primitive ``index`` from ``pose`` as the wheels execute it at time ``t``
    (under ideal wheels: :meth:`~husky_course.sim.primitives.PrimitiveLibrary.path_from` itself)."""
    if cfg.wheels_ideal:
        return library.path_from(pose, index)
    scale, heading = slip(cfg, world_seed, t, pose)
    local = executed_local_path(library.local_paths[library.check_index(index)], scale, heading)
    pose = np.asarray(pose, float)
    c, s = np.cos(pose[2]), np.sin(pose[2])
    out = np.empty_like(local)
    out[:, 0] = pose[0] + c * local[:, 0] - s * local[:, 1]
    out[:, 1] = pose[1] + s * local[:, 0] + c * local[:, 1]
    out[:, 2] = pose[2] + local[:, 2]
    return out
