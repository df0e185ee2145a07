"""The fast backend against the PyBullet reference: depth images and collision labels."""

import numpy as np
import pytest

from husky_course.fast_sim import RENDER_POLYGON_VERTICES, FastSimulator
from husky_course.pybullet_sim import PyBulletSimulator


@pytest.fixture(scope="module")
def sims():
    fast, ref = FastSimulator(), PyBulletSimulator()
    yield fast, ref
    ref.close()


def _views(fast, n_worlds=50, per_world=5, seed=0):
    """Collision-free robot poses on random-policy paths, mid-primitive ones included (yaw != 0)."""
    rng = np.random.default_rng(seed)
    for w in range(n_worlds):
        world = fast.load(10_000 + w)
        paths = fast.library.paths_from(
            np.c_[rng.uniform(0, 9, 40), rng.uniform(-3.5, 3.5, 40), np.zeros(40)],
            rng.integers(0, 25, 40),
        )
        cand = paths[np.arange(40), rng.integers(0, paths.shape[1], 40)]
        free = cand[~fast.contacts(cand[:, None])[:, 0]][:per_world]
        yield world, free


def test_depth_agrees_with_pybullet(sims):
    fast, ref = sims
    strict, tolerant = [], []
    for world, poses in _views(fast):
        fast.load(world)
        ref.load(world)
        a, b = fast.depth(poses), ref.depth(poses)
        err = np.abs(a - b)
        strict += list(np.percentile(err.reshape(len(a), -1), 99, axis=1))
        # the same error, forgiving a silhouette that falls on the other side of a pixel centre:
        # compare each pixel with the PyBullet pixel or its left/right neighbour
        shifted = np.stack([np.roll(b, s, axis=2) for s in (-1, 0, 1)])
        err_t = np.abs(a[None] - shifted).min(0)
        tolerant += list(np.percentile(err_t.reshape(len(a), -1), 99, axis=1))
    strict, tolerant = np.array(strict), np.array(tolerant)
    print(
        f"views {len(strict)}: strict p99<=0.02 in {np.mean(strict <= 0.02):.1%}, "
        f"tolerant in {np.mean(tolerant <= 0.02):.1%}; median strict p99 {np.median(strict):.4f}"
    )
    assert len(strict) >= 200
    # Measured here: 90% of views meet p99 <= 0.02 pixel for pixel, 98% when a silhouette may
    # move by one column. The rest differ by one whole column (an obstacle edge or a one-pixel
    # gap) whose true silhouette lies within ~0.07 px of TinyRenderer's sample point: the
    # rasteriser's own rounding, which an analytic ray caster cannot reproduce exactly.
    assert np.mean(strict <= 0.02) >= 0.85
    assert np.mean(tolerant <= 0.02) >= 0.95
    assert np.median(strict) <= 0.005


def test_collision_labels_identical(sims):
    fast, ref = sims
    rng = np.random.default_rng(1)
    n, hits = 0, 0
    for w in range(60):
        world = fast.load(20_000 + w)
        ref.load(world)
        for _ in range(25):
            pose = np.array([rng.uniform(0, 9), rng.uniform(-4, 4), rng.uniform(-0.3, 0.3)])
            if fast.contact_along(pose[None]) >= 0:
                continue
            k = int(rng.integers(25))
            a, b = fast.apply(pose, k), ref.apply(pose, k)
            assert a.collided == b.collided, (world.seed, pose, k)
            np.testing.assert_allclose(a.pose, b.pose)
            n += 1
            hits += a.collided
    assert n >= 1000 and 0.1 < hits / n < 0.9


def test_render_polygon_is_what_pybullet_draws():
    """Re-measure TinyRenderer's cylinder polygon by rendering one cylinder from above."""
    import pybullet as p

    cid = p.connect(p.DIRECT)
    try:
        vis = p.createVisualShape(p.GEOM_CYLINDER, radius=1.0, length=1.0, physicsClientId=cid)
        p.createMultiBody(0, -1, vis, [0, 0, 0.5], physicsClientId=cid)
        n, half = 600, 1.2
        fov = np.degrees(2 * np.arctan(half / 20.0))
        view = p.computeViewMatrix([0, 0, 21.0], [0, 0, 0], [0, 1, 0])
        proj = p.computeProjectionMatrixFOV(fov, 1, 1.0, 100)
        seg = np.asarray(
            p.getCameraImage(n, n, view, proj, renderer=p.ER_TINY_RENDERER, physicsClientId=cid)[4]
        ).reshape(n, n)
    finally:
        p.disconnect(cid)
    kept = []
    for k in range(32):
        a = 2 * np.pi * k / 32
        x, y = 0.99 * np.cos(a), 0.99 * np.sin(a)
        j, i = int(round((x / half + 1) * n / 2)), int(round((1 - y / half) * n / 2))
        if seg[i, j] >= 0:
            kept.append(k)
    assert tuple(kept) == RENDER_POLYGON_VERTICES
