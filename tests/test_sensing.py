"""A real robot's senses (husky_course.config.sensing, husky_course.sim.sensing): the noise is what the
config says, ideal is today's simulator bit for bit, the same seed gives the same bytes, both
backends see the same noise, and bad settings get a clear error."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest
from before_sensing import RECORD, play

from husky_course.config import (
    SENSING,
    CameraConfig,
    SensingConfig,
    SensingError,
    SimConfig,
    get_profile,
    get_sensing,
    sim_for_world,
    with_sensing,
    world_flag,
)
from husky_course.sim.camera import denormalize_depth, normalize_depth
from husky_course.sim.fast import FastSimulator
from husky_course.sim.primitives import make_library
from husky_course.sim.sensing import depth_edges, executed_local_path, executed_path, noisy_depth

REALISTIC = SENSING["realistic"]
CAMERA = CameraConfig()

#: Tolerances against :data:`before_sensing.RECORD`, fc4c264's depth images, paths and collisions. The
#: last bits of numpy's float64 sin and cos depend on the processor: with AVX-512 numpy uses its own
#: vectorised versions, without it the C library's (numpy issue 23523). Digests recorded on an AVX-512
#: machine failed on an AVX2 one with the same code, fc4c264's included. A pose 1e-16 off moves a depth
#: pixel by far less than 1e-6, while the two backends' renderers differ by up to 1.3e-5 (the test checks
#: it can tell them apart).
PATH_ATOL, DEPTH_ATOL = 1e-9, 1e-6


@pytest.mark.parametrize("kind", ["static", "moving"])
@pytest.mark.parametrize("backend", ["fast", "pybullet"])
def test_ideal_senses_are_the_simulator_before_sensing(kind, backend):
    """Bit for bit the renderer and the library on this machine, and the pre-sensing simulator's
    record to within the processor's rounding (:data:`PATH_ATOL`, :data:`DEPTH_ATOL`)."""
    from husky_course.sim.backends import make_simulator

    def bit_for_bit(pose: np.ndarray, index: int, step: int) -> None:
        """Ideal senses report the renderer's images and the library's paths, on any machine."""
        assert sim.depth(pose[None], step).tobytes() == sim._depth(pose[None], step).tobytes()
        path = sim.apply(pose, index, step).path.tobytes()
        assert path == sim.library.path_from(pose, index).tobytes()
        assert path == sim.play(pose, index, step).path.tobytes()

    with make_simulator(backend, sim_for_world(SimConfig(), kind)) as sim:
        assert sim.config.sensing == get_sensing("ideal")
        depth, paths, collided = play(sim, bit_for_bit)
    with np.load(RECORD, allow_pickle=False) as before:
        np.testing.assert_array_equal(collided, before[f"{kind}_collided"])
        np.testing.assert_allclose(paths, before[f"{kind}_path"], rtol=0, atol=PATH_ATOL)
        np.testing.assert_allclose(depth, before[f"{kind}_{backend}_depth"], rtol=0, atol=DEPTH_ATOL)
        other = "pybullet" if backend == "fast" else "fast"
        apart = np.abs(depth - before[f"{kind}_{other}_depth"]).max()
        assert apart > DEPTH_ATOL, f"the record cannot tell the backends apart ({apart:.1e})"


def flat_images(z: float, n: int) -> np.ndarray:
    return np.repeat(normalize_depth(np.full((1, 50, 50), z), CAMERA), n, axis=0)


def poses(n: int) -> np.ndarray:
    return np.c_[np.arange(n) * 0.01, np.zeros(n), np.zeros(n)]


@pytest.mark.parametrize("z", [1.0, 2.0, 3.5])
def test_depth_error_has_the_configured_mean_and_sigma(z):
    """sigma = sigma_k z**2 on 100,000 pixels: mean and sigma within 4 standard errors."""
    cfg = replace(REALISTIC, dropout=0.0, min_range=0.0)
    n = 40
    out = noisy_depth(flat_images(z, n), poses(n), np.zeros(n), 7, cfg, CAMERA)
    err = denormalize_depth(out, CAMERA).ravel() - denormalize_depth(flat_images(z, 1), CAMERA)[0, 0, 0]
    sigma = cfg.sigma_k * z**2
    count = err.size
    assert abs(err.mean()) < 4 * sigma / np.sqrt(count)
    assert abs(err.std() - sigma) < 4 * sigma / np.sqrt(2 * count) + cfg.depth_unit / 2
    grid = denormalize_depth(out, CAMERA).ravel() / cfg.depth_unit  # depth rounded to the unit (float32)
    assert np.abs(grid - np.round(grid)).max() < 1e-3


def test_dropout_rate_and_min_range():
    n = 40
    cfg = replace(REALISTIC, dropout=0.05)
    out = noisy_depth(flat_images(2.0, n), poses(n), np.zeros(n), 3, cfg, CAMERA)
    share, count = float((out == 1.0).mean()), out.size
    assert abs(share - 0.05) < 4 * np.sqrt(0.05 * 0.95 / count)
    close = noisy_depth(flat_images(0.08, 2), poses(2), np.zeros(2), 3, cfg, CAMERA)
    assert (close == 1.0).all()  # under the D435's minimum depth: no reading


def test_edge_dropout_only_on_the_far_side_of_an_edge():
    z = np.full((50, 50), 1.0)
    z[:, 25:] = 3.0  # a step: columns 25.. are the far side
    edges = depth_edges(z, 0.3)
    assert edges[:, 25].all() and not edges[:, 24].any() and edges.sum() == 50
    cfg = replace(REALISTIC, dropout=0.0, edge_dropout=1.0, sigma_k=0.0)
    out = noisy_depth(normalize_depth(z[None], CAMERA), poses(1), np.zeros(1), 0, cfg, CAMERA)[0]
    assert (out[:, 25] == 1.0).all() and (out[:, 26:] < 1.0).all() and (out[:, :25] < 1.0).all()


def test_same_seed_same_bytes_other_seed_other_noise():
    sim_a = FastSimulator(replace(SimConfig(), sensing=REALISTIC))
    sim_b = FastSimulator(replace(SimConfig(), sensing=REALISTIC))
    sim_c = FastSimulator(replace(SimConfig(), sensing=replace(REALISTIC, seed=1)))
    shots = []
    for sim in (sim_a, sim_b, sim_c):
        world = sim.load(11)
        r = sim.apply(world.start, 20, 0)
        shots.append((sim.depth(world.start[None], 0).tobytes(), r.path.tobytes()))
    assert shots[0] == shots[1]
    assert shots[0][0] != shots[2][0] and shots[0][1] != shots[2][1]
    world = sim_a.load(11)
    a, b = sim_a.depth(world.start[None], 0), sim_a.depth(world.start[None], 1)
    assert not np.array_equal(a, b)  # another step, another draw (a static world: same true image)
    two = sim_a.depth(np.stack([world.start, world.start + (0.1, 0, 0)]), 0)
    assert np.array_equal(two[0], a[0])  # a batch: each pose its own draw, the same as alone


def test_executed_path_slips_as_configured():
    lib = make_library()
    local = lib.local_paths[20]
    assert np.array_equal(executed_local_path(local, 1.0, 0.0), local)
    slipped = executed_local_path(local, 1.05, np.radians(3))
    lengths = [np.linalg.norm(np.diff(p[:, :2], axis=0), axis=1).sum() for p in (local, slipped)]
    assert lengths[1] / lengths[0] == pytest.approx(1.05, rel=1e-9)
    assert slipped[-1, 2] - local[-1, 2] == pytest.approx(np.radians(3))
    pose = np.array([1.0, -2.0, 0.3])
    assert np.array_equal(executed_path(lib, pose, 20, get_sensing("ideal"), 5, 0.0), lib.path_from(pose, 20))
    real = executed_path(lib, pose, 20, REALISTIC, 5, 0.0)
    assert np.array_equal(real[0], pose) and np.abs(real[-1] - lib.end_pose(pose, 20)).max() > 1e-4


def test_executed_motion_spread_matches_the_config():
    """End-point spread over many draws: length factor sigma and heading sigma as configured."""
    lib = make_library()
    pose = np.zeros(3)
    ends = np.array([executed_path(lib, pose, 12, REALISTIC, w, 0.0)[-1] for w in range(2000)])
    length = np.hypot(ends[:, 0], ends[:, 1]) / np.hypot(*lib.end_pose(pose, 12)[:2])
    heading = np.degrees(ends[:, 2])
    n = len(ends)
    assert abs(length.std() - REALISTIC.slip_scale) < 4 * REALISTIC.slip_scale / np.sqrt(2 * n)
    assert abs(heading.std() - REALISTIC.slip_heading_deg) < 4 * REALISTIC.slip_heading_deg / np.sqrt(2 * n)


def test_both_backends_see_the_same_noise():
    """The noise is applied by the shared code: where the two renderers agree (all but a few edge
    pixels), the realistic images agree, and the executed paths are identical."""
    from husky_course.sim.pybullet_backend import PyBulletSimulator

    cfg = replace(SimConfig(), sensing=REALISTIC)
    fast, ref = FastSimulator(cfg), PyBulletSimulator(cfg)
    rng = np.random.default_rng(5)
    try:
        agree = []
        for w in rng.integers(0, 10_000, 8):
            world = fast.load(int(w))
            ref.load(int(w))
            pose = world.start + (rng.uniform(0, 2), rng.uniform(-0.5, 0.5), rng.uniform(-0.3, 0.3))
            a, b = fast.depth(pose[None], 2)[0], ref.depth(pose[None], 2)[0]
            agree.append(np.mean(np.abs(a - b) <= 1e-3))
            k = int(rng.integers(25))
            assert np.array_equal(fast.apply(pose, k, 2).path, ref.apply(pose, k, 2).path)
    finally:
        ref.close()
    print(f"pixels agreeing within 1e-3: min {min(agree):.4f} over {len(agree)} views")
    assert min(agree) >= 0.98


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"sigma_k": -0.01}, "sigma_k must be a finite number >= 0"),
        ({"dropout": 1.5}, "dropout must be at most 1"),
        ({"slip_scale": float("nan")}, "slip_scale must be a finite number"),
        ({"edge_jump": 0.0}, "edge_jump"),
    ],
)
def test_bad_settings_are_refused(change, message):
    with pytest.raises(SensingError, match=message):
        SensingConfig(**change)


def test_unknown_sensing_is_refused_everywhere():
    with pytest.raises(SensingError, match="unknown sensing 'noisy': choose one of ideal, realistic"):
        get_sensing("noisy")
    with pytest.raises(SensingError, match="unknown sensing"):
        with_sensing(get_profile("quick"), "noisy")
    from husky_course.sim.env import HuskyNavEnv

    with pytest.raises(SensingError, match="unknown sensing"):
        HuskyNavEnv(sensing="noisy")
    proc = subprocess.run([sys.executable, "-m", "husky_course", "evaluate", "--planner", "random",
                           "--sensing", "noisy"], capture_output=True, text=True, check=False)
    assert proc.returncode == 2 and "invalid choice: 'noisy'" in proc.stderr


def test_the_cli_and_the_env_take_the_sensing():
    command = [sys.executable, "-m", "husky_course", "evaluate", "--planner", "random", "--worlds", "3",
               "--sensing", "realistic", "--json", "--no-progress"]
    proc = subprocess.run(command, capture_output=True, text=True, check=True)
    assert json.loads(proc.stdout)["sensing"] == "realistic"
    from husky_course.sim.env import HuskyNavEnv

    env = HuskyNavEnv()
    obs_ideal, info = env.reset(seed=4)
    assert info["sensing"] == "ideal"
    obs_real, info = env.reset(seed=4, options={"sensing": "realistic"})
    assert info["sensing"] == "realistic" and not np.array_equal(obs_ideal, obs_real)
    assert world_flag(with_sensing(get_profile("quick"), "realistic").sim) == " --sensing realistic"
    assert world_flag(with_sensing(get_profile("quick"), REALISTIC.scaled(2)).sim) == ""


def test_play_is_the_library_and_apply_the_wheels():
    ideal, real = FastSimulator(SimConfig()), FastSimulator(replace(SimConfig(), sensing=REALISTIC))
    for sim in (ideal, real):
        world = sim.load(9)
        nominal = sim.play(world.start, 17, 0)
        assert np.array_equal(nominal.path, sim.library.path_from(world.start, 17))
    world = ideal.load(9)
    assert np.array_equal(ideal.apply(world.start, 17, 0).path, ideal.play(world.start, 17, 0).path)
    world = real.load(9)
    assert not np.array_equal(real.apply(world.start, 17, 0).path, real.play(world.start, 17, 0).path)


def test_the_oracle_replans_under_slipping_wheels():
    """It plans from its true position (heading set to the library's 0) at every step; before, its
    replay of the plan through the slipping wheels could fail, and a heading off 0 stopped the lattice."""
    from husky_course.evaluation.episodes import evaluate
    from husky_course.planners.registry import make_planner

    sim = FastSimulator(replace(SimConfig(), sensing=REALISTIC))
    result = evaluate(make_planner("oracle"), 20, 3, sim=sim, progress=False)
    assert result.mean_prims > 8 and result.success_rate >= 0.75, result.to_json()


@pytest.mark.parametrize(
    "name, world", [("seen-so-far", "static"), ("snapshot", "moving"), ("seen-motion", "moving")]
)
def test_privileged_references_search_from_their_true_position_under_slip(name, world):
    """The references that search the lattice from the true pose set its heading to the library's 0 under
    slipping wheels, as the oracle does (the lattice refused a heading off 0)."""
    from husky_course.config import get_profile, with_sensing, with_world
    from husky_course.evaluation.episodes import evaluate
    from husky_course.planners.registry import make_planner

    profile = with_sensing(with_world(get_profile("quick"), world), "realistic")
    result = evaluate(make_planner(name), 6, 3, sim=FastSimulator(profile.sim), progress=False)
    assert result.mean_prims > 5, result.to_json()
