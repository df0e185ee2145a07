import numpy as np
import pytest

from husky_course.config import CameraConfig, ConfigError, PrimitiveConfig, get_profile
from husky_course.sim.camera import linearize_depth_buffer, normalize_depth
from husky_course.sim.fast import FastSimulator
from husky_course.sim.primitives import PrimitiveError, make_library
from husky_course.sim.world import make_world


def test_library_has_25_primitives_that_return_to_heading():
    lib = make_library()
    assert lib.n == 25
    assert lib.local_paths.shape == (25, PrimitiveConfig().samples, 3)
    np.testing.assert_allclose(lib.local_paths[:, 0], 0.0, atol=1e-12)  # all start at the origin
    np.testing.assert_allclose(lib.local_paths[:, -1, 2], 0.0, atol=1e-12)  # end at initial heading
    np.testing.assert_allclose(lib.local_paths[:, -1, 0], 1.0)  # ten primitives cross 10 m
    assert np.all(np.diff(lib.local_paths[..., 0], axis=1) > 0)  # always forward
    lengths = lib.path_lengths()
    assert lengths.min() == pytest.approx(1.0) and lengths.max() < 1.5
    np.testing.assert_allclose(lengths, lengths[::-1])  # symmetric library
    steps = np.linalg.norm(np.diff(lib.local_paths[..., :2], axis=1), axis=-1)
    assert steps.max() < 0.03  # dense enough that no obstacle (r >= 0.15) can be skipped


def test_playback_is_rigid_motion():
    lib = make_library()
    pose = np.array([2.0, -1.0, 0.7])
    path = lib.path_from(pose, 3)
    np.testing.assert_allclose(path[0], pose)
    local_len = lib.path_lengths()[3]
    assert np.linalg.norm(np.diff(path[:, :2], axis=0), axis=1).sum() == pytest.approx(local_len)


@pytest.mark.parametrize("bad", [-1, 25, 2.0, "3", None, True])
def test_bad_primitive_index(bad):
    with pytest.raises(PrimitiveError, match="primitive index"):
        make_library().check_index(bad)


def test_world_is_reproducible_and_start_is_free():
    a, b, c = make_world(7), make_world(7), make_world(8)
    np.testing.assert_array_equal(a.obstacles, b.obstacles)
    assert not np.array_equal(a.obstacles, c.obstacles)
    cfg = a.config
    assert a.obstacles.shape == (20, 3)
    assert cfg.obstacle_height == pytest.approx(7.5)
    sim = FastSimulator()
    for seed in range(300):
        w = sim.load(seed)
        assert sim.contact_along(w.start[None]) == -1
        assert np.all(np.abs(w.obstacles[:, 1]) <= cfg.width / 2)
        assert np.all((w.obstacles[:, 0] >= cfg.obstacle_x_min) & (w.obstacles[:, 0] <= cfg.length))


@pytest.mark.parametrize("bad", [-1, 1.5, "a"])
def test_bad_world_seed(bad):
    with pytest.raises(ValueError, match="seed"):
        make_world(bad)


def test_unknown_profile():
    with pytest.raises(ConfigError, match="unknown profile"):
        get_profile("huge")


def test_depth_range_and_orientation():
    sim = FastSimulator()
    world = sim.load(0)
    d = sim.depth(world.start[None])[0]
    assert d.dtype == np.float32 and d.shape == (50, 50)
    assert 0.0 <= d.min() and d.max() <= 1.0 and np.isfinite(d).all()
    # the ground is below the horizon: bottom rows are close, and get closer downwards
    assert d[-1].mean() < d[30].mean() < 1.0
    # a single obstacle to the robot's left appears in the left half of the image
    from husky_course.sim.world import World

    lone = World(0, world.config, np.array([[3.0, 1.5, 0.3]]), np.zeros(3))
    sim.load(lone)
    _, kind = sim.column_hits(np.zeros((1, 3)))
    cols = np.flatnonzero(kind[0] == 2)  # columns that see the obstacle
    assert cols.size and cols.max() < 25
    img = sim.depth(np.zeros((1, 3)))[0]
    assert img[10, cols].max() < img[10, 25]  # closer than what the centre column sees


def test_depth_linearisation():
    cam = CameraConfig()
    np.testing.assert_allclose(linearize_depth_buffer(np.array([0.0, 1.0]), cam), [cam.near, cam.far])
    assert normalize_depth(np.array([cam.near, cam.far, 99.0]), cam).tolist() == [0.0, 1.0, 1.0]
    with pytest.raises(ValueError, match="near"):
        linearize_depth_buffer(np.zeros(1), CameraConfig(near=0.0))


def test_collision_against_walls_and_obstacles():
    from husky_course.sim.world import World

    sim = FastSimulator()
    world = sim.load(0)
    sim.load(World(0, world.config, np.zeros((0, 3)), np.zeros(3)))  # walls only
    y = world.wall_y - world.config.robot_radius
    assert sim.contact_along(np.array([[5.0, y - 1e-3, 0.0]])) == -1
    assert sim.contact_along(np.array([[5.0, y + 1e-3, 0.0]])) == 0
    sim.load(world)
    x, oy, r = world.obstacles[0]
    gap = r + world.config.robot_radius
    assert sim.contact_along(np.array([[x, oy + gap - 1e-3, 0.0]])) == 0
