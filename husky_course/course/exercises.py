"""Check functions for the exercises that have one right answer.

Each returns ``True`` and prints a short confirmation when the answer is right, and raises
``AssertionError`` with a hint when it is not, so a student can call it at the end of a cell.
"""

from __future__ import annotations

import math

import numpy as np

from ..config import CameraConfig, SensingConfig, SimConfig
from ..data.dataset import Dataset


def _ok(message: str) -> bool:
    print(f"correct: {message}")
    return True


def check_ray_factor(camera: CameraConfig, factor: float) -> bool:
    """Chapter 1, exercise 2: distance along the ray over depth, for the pixel farthest off-centre.

    Right within 0.1%: ``sqrt(1 + u**2 + v**2)`` for the corner pixel's tangents ``u, v``
    (:func:`~husky_course.sim.camera.pixel_tangents`).
    """
    from ..sim.camera import pixel_tangents

    u, v = pixel_tangents(camera)
    want = float(np.sqrt(1.0 + np.max(u**2) + np.max(v**2)))
    got = float(factor)
    if not math.isclose(got, want, rel_tol=1e-3):
        edge = float(np.sqrt(1.0 + np.max(u**2)))
        hint = (
            "the distance along a ray is never shorter than the depth: the factor is at least 1" if got < 1
            else "that is the factor at the middle of a side; a corner's ray leans in both u and v"
            if math.isclose(got, edge, rel_tol=1e-3)
            else "the ray (1, u, v) has length sqrt(1 + u^2 + v^2) per metre of depth"
        )
        raise AssertionError(f"{got:.4f} is not it: {hint}")
    return _ok(f"at a corner the ray is {want:.3f} times as long as the depth ({camera.fov_deg:.0f} deg)")


def naive_crossings(ds: Dataset) -> int:
    """Pairs ``(i, i + 1)`` with label 0 at ``i`` and ``i + 1`` in the pool whose images are of two videos."""
    i = np.flatnonzero(np.asarray(ds.labels[:-1]) == 0)
    return int((ds.episode[i + 1] != ds.episode[i]).sum())


def check_naive_pairs(ds: Dataset, count: int) -> bool:
    """Chapter 2, exercise 2: how many naive pairs ``(i, i + 1)`` (label 0) cross into the next video."""
    want = naive_crossings(ds)
    if int(count) != want:
        hint = (
            "a video that ends in a collision ends on a label-1 image, which the filter drops: which videos "
            "end on a label-0 image, and does the pool's last image have a next one?"
        )
        raise AssertionError(f"{count} is not it (pairs crossing into the next video): {hint}")
    return _ok(f"{want} of the naive pairs join the last image of one video to the first of the next")


def check_encoder_features(size: int, n: int) -> bool:
    """Chapter 3, exercise 4: how many numbers the encoder's fully connected layer gets from a
    ``size x size`` image (read from the paper's :class:`~husky_course.models.paper.Encoder` built
    at that size)."""
    from dataclasses import replace

    from ..models.base import DEFAULT_DIMS
    from ..models.paper import Encoder

    want = Encoder(replace(DEFAULT_DIMS, image_size=int(size))).fc.in_features
    if int(n) != want:
        raise AssertionError(
            f"{n} is not it: each convolution gives (side - kernel) // stride + 1 pixels a side "
            "(kernel 10 then 8, stride 2), and the second has 16 channels"
        )
    return _ok(f"a {size}x{size} image reaches the fully connected layer as {want} numbers")


def check_roc_auc(y: np.ndarray, p: np.ndarray, auc: float) -> bool:
    """Chapter 5, exercise 4: the ROC AUC of probabilities ``p`` for labels ``y``, to 1e-6."""
    from ..evaluation.metrics import roc_auc

    want, got = roc_auc(y, p), float(auc)
    if not math.isclose(got, want, abs_tol=1e-6):
        accuracy = float(((np.asarray(p) >= 0.5) == np.asarray(y, bool)).mean())
        hint = (
            "that is the AUC with safe images ranked above colliding ones: 1 minus the answer"
            if math.isclose(got, 1 - want, abs_tol=1e-6) else
            "that is the accuracy at threshold 0.5, not the AUC" if math.isclose(got, accuracy, abs_tol=1e-6)
            else "the share of (colliding, safe) pairs in which the colliding image has the higher "
            "probability; a tie counts one half"
        )
        raise AssertionError(f"{got:.6f} is not the AUC: {hint}")
    n_pos = int(np.sum(y))
    return _ok(f"ROC AUC {want:.4f} over {n_pos} colliding and {int(np.size(y)) - n_pos} safe images")


def check_shifted_labels(ds: Dataset, labels: np.ndarray) -> bool:
    """Chapter 4, exercise 1: the off-by-one labels written from ``ds.prims``.

    The right answer gives image ``t`` the label of image ``t + 1`` of the same video (1 where
    ``ds.prims[t + 1] == -1``) and 0 to the last image of a video.
    """
    from .diagnosis import shifted_labels  # imported here: it pulls in torch

    labels = np.asarray(labels).astype(np.uint8).ravel()
    want = shifted_labels(ds)
    if labels.shape != want.shape:
        raise AssertionError(f"one label per image: expected {want.shape}, got {labels.shape}")
    wrong = np.flatnonzero(labels != want)
    if wrong.size:
        i = int(wrong[0])
        raise AssertionError(
            f"{wrong.size} labels differ, first at image {i} "
            f"(video {int(ds.episode[i])}, step {int(ds.step[i])}): did you stop at the end of each video?"
        )
    return _ok(f"{int(want.sum())} images get a collision label one step early")


def pairs_per_horizon(lengths: np.ndarray, horizon: int) -> np.ndarray:
    """Image pairs ``(t, t + h)`` for ``h = 1..horizon`` in videos of the given lengths.

    A video of ``L`` images stores ``L - 1`` safe transitions before its last image, so image
    ``s`` has a stored successor ``h`` steps ahead exactly when ``s + h <= L - 1``.
    """
    lengths = np.asarray(lengths, int)
    return np.array([int(np.maximum(lengths - h, 0).sum()) for h in range(1, horizon + 1)])


def check_pairs_per_horizon(lengths: np.ndarray, counts: list[int] | np.ndarray) -> bool:
    """Chapter 6, exercise 3: the image pairs at each horizon, from the videos' lengths alone."""
    want = pairs_per_horizon(lengths, len(counts))
    got = np.asarray(counts, int)
    if not np.array_equal(got, want):
        raise AssertionError(
            f"expected {want.tolist()}, got {got.tolist()}: an image has a stored successor h steps ahead "
            "only if it is at least h images before the end of its video"
        )
    return _ok(f"pairs per horizon {want.tolist()}")


def worlds_for_certificate(rate: float, confidence: float = 0.95) -> int:
    """Fewest collision-free worlds that certify a collision rate below ``rate`` at ``confidence``."""
    return math.ceil(math.log(1.0 - confidence) / math.log(1.0 - rate))


def check_worlds_for_certificate(n: int, rate: float = 0.01, confidence: float = 0.95) -> bool:
    """Chapter 7, exercise 4: worlds needed (0 collisions) for a 95% upper bound below ``rate``."""
    want = worlds_for_certificate(rate, confidence)
    if int(n) != want:
        hint = "too few: 1 - 0.05**(1/n) is still above the rate" if n < want else "more than needed"
        raise AssertionError(f"{n} is {hint}")
    return _ok(
        f"{want} worlds without a collision certify a rate below {rate:.0%} with {confidence:.0%} confidence"
    )


def check_dead_reckoning(
    config: SimConfig, point: tuple[float, float], primitive: int, answer: object
) -> bool:
    """Chapter 8, exercise 1: a map point moved into the robot's frame after ``primitive``."""
    from ..sim.primitives import make_library

    end = make_library(config.primitives).local_paths[int(primitive), -1]
    want = np.asarray(point, float) - end[:2]
    got = np.asarray(answer, float).ravel()
    if got.shape != (2,) or not np.allclose(got, want, atol=1e-6):
        raise AssertionError(
            f"expected {np.round(want, 4).tolist()}, got {np.round(got, 4).tolist()}: every primitive "
            "ends at heading 0, so the point moves by minus the primitive's end position"
        )
    return _ok(f"the point is at {np.round(want, 3).tolist()} after primitive {primitive}")


def check_bonferroni(collisions: int, worlds: int, candidates: int, bound: float) -> bool:
    """Chapter 8, exercise 2: the collision bound of the best of ``candidates`` planners, 95% overall."""
    from ..evaluation.statistics import clopper_pearson

    want = clopper_pearson(collisions, worlds, 1 - 0.05 / candidates, "upper")[1]
    if not math.isclose(float(bound), want, abs_tol=5e-4):
        plain = clopper_pearson(collisions, worlds, 0.95, "upper")[1]
        uncorrected = math.isclose(float(bound), plain, abs_tol=5e-4)
        hint = " (that is the bound without the correction)" if uncorrected else ""
        raise AssertionError(
            f"{bound} is not the corrected bound{hint}: use confidence 1 - 0.05 / {candidates}"
        )
    return _ok(f"at most {want:.2%} collisions, for the best of {candidates} at 95% overall")


def check_kl_inverse(q: float, c: float, answer: float) -> bool:
    """Chapter 9, exercise 1: the largest ``p`` with ``kl(q || p) <= c``, to 1e-4."""
    from ..evaluation.pac_bayes import bernoulli_kl, kl_inverse

    want = kl_inverse(q, c)
    got = float(answer)
    if not math.isclose(got, want, abs_tol=1e-4):
        hint = (
            "below q: the inverse looks for p >= q" if got < q else
            f"kl(q || your p) = {bernoulli_kl(q, min(max(got, 0.0), 1.0)):.4g}, not {c}"
        )
        raise AssertionError(f"{got} is not kl_inverse({q}, {c}) ({hint})")
    return _ok(f"kl_inverse({q}, {c}) = {want:.4f}")


def check_worlds_for_pac_bayes(train_cost: float, kl: float, bound: float, n: int, delta: float) -> bool:
    """Chapter 9, exercise 2: fewest worlds ``n`` for which the PAC-Bayes-kl bound is at most ``bound``."""
    from ..evaluation.pac_bayes import MIN_WORLDS, pac_bayes_kl_bound

    n = int(n)
    if n < MIN_WORLDS:
        raise AssertionError(f"the bound is proven for at least {MIN_WORLDS} worlds, got {n}")
    if pac_bayes_kl_bound(train_cost, kl, n, delta) > bound:
        raise AssertionError(f"with {n} worlds the bound is above {bound}: more worlds are needed")
    if n > MIN_WORLDS and pac_bayes_kl_bound(train_cost, kl, n - 1, delta) <= bound:
        raise AssertionError(f"{n - 1} worlds already give a bound of at most {bound}: find the fewest")
    return _ok(f"{n} worlds: bound {pac_bayes_kl_bound(train_cost, kl, n, delta):.4f} <= {bound}")


def check_mover_position(world_seed: int, sim: SimConfig, index: int, t: float, y: float) -> bool:
    """Chapter 10, exercise 1: where moving cylinder ``index`` of world ``world_seed`` is at time ``t``.

    The right answer walks from the cylinder's start at its speed and reflects at ``|y| = W/2 - r``
    (within 1 mm of :meth:`husky_course.sim.world.World.obstacles_at`).
    """
    from ..sim.world import make_world

    world = make_world(world_seed, sim.world)
    if index not in world.moving:
        movers = world.moving.tolist()
        raise AssertionError(f"cylinder {index} does not move in this world: pick one of {movers}")
    true = float(world.obstacles_at(float(t))[index, 1])
    if abs(float(y) - true) > 1e-3:
        lo = -world.wall_y + world.obstacles[index, 2]
        raise AssertionError(
            f"not quite: it starts at y = {world.obstacles[index, 1]:.3f} with speed "
            f"{world.speeds[index]:+.3f} m per step and bounces between {lo:.3f} and {-lo:.3f} "
            "(its surface touching a wall)"
        )
    return _ok(f"cylinder {index} is at y = {true:.3f} m at time {t}")


def check_sample_time(step: int, sample: int, samples: int, t: float) -> bool:
    """Chapter 10, exercise 2: the time of recorded sample ``sample`` of the primitive started at ``step``."""
    true = step + sample / (samples - 1)
    if abs(float(t) - true) > 1e-9:
        raise AssertionError(
            "not quite: a primitive takes one step; its first sample is at its start, its last at its end"
        )
    return _ok(f"sample {sample} of {samples} of the primitive started at step {step} is at time {true:.4f}")


def cylinder_points(centre: np.ndarray, r: float, sim: SimConfig) -> np.ndarray:
    """The scan points ``(m, 2)`` (robot frame) that a lone cylinder of radius ``r`` at ``centre``
    gives the camera: each column's ray cut with its circle, as
    :class:`~husky_course.planners.perception.DepthScan` reads a rendered image."""
    from ..sim.camera import pixel_tangents

    cam = sim.camera
    u = pixel_tangents(cam)[0]
    d = np.c_[np.ones_like(u), u] / np.hypot(1.0, u)[:, None]
    eye = np.array([cam.mount_forward, 0.0])
    rel = eye - np.asarray(centre, float)
    b = d @ rel
    disc = b**2 - (rel @ rel - r**2)
    hit = disc > 0
    return eye + (-b[hit] - np.sqrt(disc[hit]))[:, None] * d[hit]


def cylinder_arc(seed: int, sim: SimConfig) -> tuple[np.ndarray, float]:
    """Chapter 10, exercise 5: the scan points ``(m, 2)`` that one cylinder gives the camera
    (:func:`cylinder_points`), and its radius ``r``. The cylinder, drawn from ``seed``, stands
    1.5-3 m ahead within 1 m of the axis, and at least two columns hit it."""
    rng = np.random.default_rng(seed)
    while True:
        centre = np.array([rng.uniform(1.5, 3.0), rng.uniform(-1.0, 1.0)])
        r = float(rng.uniform(*sim.world.radius_range))
        points = cylinder_points(centre, r, sim)
        if len(points) >= 2:
            return points, r


def check_arc_centre(arc: np.ndarray, r: float, centre: np.ndarray, sim: SimConfig) -> bool:
    """Chapter 10, exercise 5: the centre of the cylinder of radius ``r`` whose surface gave ``arc``.

    Right when every point lies on the circle (within 1 cm) and the centre is behind the points,
    as seen from the camera (two circles of radius ``r`` pass through two points; only one is the
    cylinder's).
    """
    arc, centre = np.asarray(arc, float), np.asarray(centre, float).ravel()[:2]
    off = np.abs(np.hypot(*(arc - centre).T) - r)
    if off.max() > 0.01:
        raise AssertionError(
            f"not quite: the points lie {off.max():.3f} m off your circle at worst; every point of the arc "
            "is at distance r from the centre"
        )
    eye = np.array([sim.camera.mount_forward, 0.0])
    if np.hypot(*(centre - eye)) < np.hypot(*(arc.mean(0) - eye)):
        raise AssertionError("that circle passes through the points, but its centre is in front of them: "
                             "the camera sees the cylinder's near side")
    mean_off = float(np.hypot(*(arc.mean(0) - centre)))
    return _ok(f"centre ({centre[0]:.3f}, {centre[1]:.3f}); the points' mean is {mean_off:.3f} m from it")


def check_depth_sigma(sensing: SensingConfig, depth: float, sigma: float) -> bool:
    """Chapter 11: the depth camera's error (standard deviation, m) at ``depth`` m, estimated from
    repeated views. Right within 15% of ``sensing.sigma_k * depth**2`` (an estimate from a few hundred
    views is within a few percent of it)."""
    want = sensing.sigma_k * depth**2
    got = float(sigma)
    if want <= 0:
        raise AssertionError("these senses are ideal: the camera has no error; use the realistic ones")
    if not abs(got - want) <= 0.15 * want:
        camera = CameraConfig()
        hint = (
            "that looks like a variance: take its square root" if math.isclose(got, want**2, rel_tol=0.3)
            else "that looks like normalised depth: multiply by far - near to get metres"
            if math.isclose(got * (camera.far - camera.near), want, rel_tol=0.15)
            else "take one pixel's depth over the views (the scene stays), then its standard deviation"
        )
        raise AssertionError(f"{got:.4f} m is not it: {hint}")
    return _ok(f"sigma = {want * 100:.1f} cm at {depth:g} m: the error grows with the square of the depth")
