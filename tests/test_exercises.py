"""Every checked exercise of every chapter, called the way the chapter tells students to call it.

The calls are read from the chapters' exercise sections (``chapters/NN_*.py``), so a chapter that
changes a call is tested as it now reads. For each call, the check must accept the reference
answer (computed here the way a student would, not by the check's own code) and reject a wrong one.
A separate test checks that the chapter's own imports define the name the call starts with.
"""

from __future__ import annotations

import ast
import math
import re
from pathlib import Path

import numpy as np
import pytest

import husky_course
from husky_course.config import get_profile, with_world
from husky_course.course import exercises
from husky_course.data.dataset import load_dataset
from husky_course.data.splits import val_videos

QUICK = get_profile("quick")  # resolved once, passed down
MOVING = with_world(QUICK, "moving")
CHAPTERS = sorted((Path(__file__).resolve().parents[1] / "chapters").glob("[0-9][0-9]_*.py"))
CALL = re.compile(r"`((?:[\w.]+\.)?exercises\.(check_\w+)\([^`]*\))`")


def exercise_calls(path: Path) -> list[tuple[str, str]]:
    """``(call, check name)`` for every check call in the chapter's exercise section."""
    text = path.read_text()
    section = text[text.index("## Exercises"):]
    prose = " ".join(line.removeprefix("#").strip() for line in section.splitlines())
    return [(m.group(1), m.group(2)) for m in CALL.finditer(prose)]


def chapter_imports(path: Path) -> dict:
    """The namespace the chapter's top-level import statements create."""
    tree = ast.parse(path.read_text())
    body = [node for node in tree.body if isinstance(node, (ast.Import, ast.ImportFrom))]
    namespace: dict = {}
    exec(compile(ast.Module(body=body, type_ignores=[]), str(path), "exec"), namespace)
    return namespace


CASES = [(p.name[:2], call, name) for p in CHAPTERS for call, name in exercise_calls(p)]


def test_every_chapter_has_a_checked_exercise():
    toc = (Path(__file__).resolve().parents[1] / "_toc.yml").read_text()
    assert len(CHAPTERS) == toc.count("file: notebooks/") >= 11
    assert {p.name[:2] for p in CHAPTERS} == {chapter for chapter, _, _ in CASES}


@pytest.fixture(scope="module")
def ds(small_dataset_dir):
    return load_dataset(small_dataset_dir)


# ---- the reference answers, worked out as a student would, and one wrong answer each ----------


def _ray_factor(ds):
    from husky_course.sim.camera import pixel_tangents

    u, v = pixel_tangents(QUICK.sim.camera)
    factor = float(np.sqrt(1 + u[None, :] ** 2 + v[:, None] ** 2).max())
    edge = 1 / math.cos(math.radians(QUICK.sim.camera.fov_deg / 2))  # one tangent only
    return {"cfg": QUICK.sim}, {"your_factor": factor}, {"your_factor": edge}


def _naive_pairs(ds):
    count = sum(
        1 for i in range(len(ds.labels) - 1) if ds.labels[i] == 0 and ds.episode[i + 1] != ds.episode[i]
    )
    return {"ds": ds}, {"your_count": count}, {"your_count": int(ds.collided.sum())}


def _encoder_features(ds):
    side = 64
    for kernel in (10, 8):
        side = (side - kernel) // 2 + 1
    return {}, {"your_n": 16 * side * side}, {"your_n": 16 * 7 * 7}


def _shifted_labels(ds):
    labels = np.zeros(len(ds.prims), np.uint8)
    for i in range(len(ds.prims) - 1):
        labels[i] = ds.episode[i + 1] == ds.episode[i] and ds.prims[i + 1] == -1
    return {"ds": ds}, {"your_labels": labels}, {"your_labels": ds.labels}


def _roc_auc(ds):
    rng = np.random.default_rng(0)
    y = (rng.random(300) < 0.3).astype(np.uint8)
    p = np.round(np.clip(0.25 * y + 0.75 * rng.random(300), 0, 1), 2)  # rounded: some ties
    pos, neg = p[y == 1], p[y == 0]
    auc = float(((pos[:, None] > neg[None, :]) + 0.5 * (pos[:, None] == neg[None, :])).mean())
    return {"y": y, "p_joint": p}, {"your_auc": auc}, {"your_auc": 1 - auc}


def _pairs_per_horizon(ds):
    lengths = ds.lengths[val_videos(ds)]
    counts = [sum(1 for n in lengths for s in range(n) if s + h <= n - 1)
              for h in range(1, QUICK.model.rnn_horizon + 1)]
    return {"lengths": lengths}, {"your_counts": counts}, {"your_counts": [c + 1 for c in counts]}


def _worlds_for_certificate(ds):
    n = 1
    while 1 - 0.05 ** (1 / n) >= 0.01:
        n += 1
    return {}, {"n": n}, {"n": n - 1}


def _dead_reckoning(ds):
    from husky_course.sim.primitives import make_library

    end = make_library(QUICK.sim.primitives).local_paths[20, -1, :2]
    point = np.array([2.0, 0.5])
    return {"profile": QUICK}, {"your_point": point - end}, {"your_point": point + end}


def _binomial_upper(k: int, n: int, alpha: float) -> float:
    """The p at which P(X <= k) = alpha for X ~ Binomial(n, p), by bisection."""
    lo, hi = k / n, 1.0
    for _ in range(100):
        p = (lo + hi) / 2
        cdf = sum(math.comb(n, j) * p**j * (1 - p) ** (n - j) for j in range(k + 1))
        lo, hi = (p, hi) if cdf > alpha else (lo, p)
    return (lo + hi) / 2


def _bonferroni(ds):
    corrected, plain = _binomial_upper(3, 500, 0.05 / 6), _binomial_upper(3, 500, 0.05)
    return {}, {"your_bound": corrected}, {"your_bound": plain}


def _kl_inverse(ds):
    from husky_course.evaluation.pac_bayes import bernoulli_kl

    lo, hi = 0.1, 1.0
    for _ in range(100):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if bernoulli_kl(0.1, mid) <= 0.02 else (lo, mid)
    return {}, {"your_p": lo}, {"your_p": 0.1}


def _worlds_for_pac_bayes(ds):
    from husky_course.evaluation.pac_bayes import MIN_WORLDS, pac_bayes_kl_bound

    n = MIN_WORLDS
    while pac_bayes_kl_bound(0.2, 20, n, 0.009) > 0.25:
        n += 1
    return {}, {"your_n": n}, {"your_n": n + 1}


def _mover_position(ds):
    from husky_course.evaluation.episodes import eval_world_seeds
    from husky_course.sim.world import make_world

    world_seed = int(eval_world_seeds(1, QUICK.eval.seed)[0])  # chapter 10's world
    world = make_world(world_seed, MOVING.sim.world)
    i = int(world.moving[0])
    _, y0, r = world.obstacles[i]
    lo, hi = -world.wall_y + r, world.wall_y - r
    y = y0 + world.speeds[i] * 3.5
    while not lo <= y <= hi:  # unfold the bounces
        y = 2 * hi - y if y > hi else 2 * lo - y
    context = {"world_seed": world_seed, "moving": MOVING, "i": i}
    return context, {"your_y": float(y)}, {"your_y": float(y0 + world.speeds[i] * 3.5 + 0.1)}


def _sample_time(ds):
    samples = MOVING.sim.primitives.samples
    return {"moving": MOVING}, {"your_t": 4 + 25 / (samples - 1)}, {"your_t": 4 + 25 / samples}


def _arc_centre(ds):
    arc, r = exercises.cylinder_arc(0, MOVING.sim)  # as the chapter hands it out
    a, b = arc[0], arc[-1]
    mid, half = (a + b) / 2, np.hypot(*(b - a)) / 2
    normal = np.array([a[1] - b[1], b[0] - a[0]]) / (2 * half)
    eye = np.array([MOVING.sim.camera.mount_forward, 0.0])
    centres = [mid + s * np.sqrt(r**2 - half**2) * normal for s in (1, -1)]
    far = max(centres, key=lambda c: np.hypot(*(c - eye)))  # behind the points, seen from the camera
    return {"arc": arc, "r": r, "moving": MOVING}, {"your_centre": far}, {"your_centre": arc.mean(0)}


def _depth_sigma(ds):
    """As chapter 11's exercise asks: pixels within 5 cm of 2 m, each one's spread over the views."""
    from husky_course.config import SENSING, with_sensing
    from husky_course.course import senses
    from husky_course.evaluation.episodes import eval_world_seeds
    from husky_course.sim.fast import FastSimulator

    real, ideal = FastSimulator(with_sensing(QUICK, "realistic").sim), FastSimulator(QUICK.sim)
    seed = int(eval_world_seeds(1, QUICK.eval.seed)[0])
    start = real.load(seed).start
    ideal.load(seed)
    views, truth = senses.repeated_views(real, start, 60), senses.repeated_views(ideal, start, 1)[0]
    near = (np.abs(truth - 2.0) < 0.05) & (views < QUICK.sim.camera.far).all(axis=0)
    sigma = float(views[:, near].std(axis=0, ddof=1).mean())
    return {"REALISTIC": SENSING["realistic"]}, {"your_sigma": sigma}, {"your_sigma": sigma**2}


ANSWERS = {
    "check_ray_factor": _ray_factor,
    "check_naive_pairs": _naive_pairs,
    "check_encoder_features": _encoder_features,
    "check_shifted_labels": _shifted_labels,
    "check_roc_auc": _roc_auc,
    "check_pairs_per_horizon": _pairs_per_horizon,
    "check_worlds_for_certificate": _worlds_for_certificate,
    "check_dead_reckoning": _dead_reckoning,
    "check_bonferroni": _bonferroni,
    "check_kl_inverse": _kl_inverse,
    "check_worlds_for_pac_bayes": _worlds_for_pac_bayes,
    "check_mover_position": _mover_position,
    "check_sample_time": _sample_time,
    "check_arc_centre": _arc_centre,
    "check_depth_sigma": _depth_sigma,
}


def _namespace(context: dict, answer: dict) -> dict:
    return {"husky_course": husky_course, "exercises": exercises, **context, **answer}


@pytest.mark.parametrize(("chapter", "call", "name"), CASES, ids=[f"ch{c}-{n}" for c, _, n in CASES])
def test_reference_answer_passes(chapter, call, name, ds, capsys):
    assert name in ANSWERS, f"chapter {chapter} calls {name}, which this test has no answer for"
    context, right, _ = ANSWERS[name](ds)
    assert eval(call, _namespace(context, right)) is True
    assert capsys.readouterr().out.startswith("correct: ")


@pytest.mark.parametrize(("chapter", "call", "name"), CASES, ids=[f"ch{c}-{n}" for c, _, n in CASES])
def test_wrong_answer_is_rejected(chapter, call, name, ds):
    context, _, wrong = ANSWERS[name](ds)
    with pytest.raises(AssertionError) as info:
        eval(call, _namespace(context, wrong))
    assert len(str(info.value)) > 20  # a hint, not a bare failure


@pytest.mark.parametrize("path", CHAPTERS, ids=[p.name[:2] for p in CHAPTERS])
def test_chapter_imports_what_its_exercises_call(path):
    namespace = chapter_imports(path)
    for call, _ in exercise_calls(path):
        root = call.split(".")[0]
        assert root in namespace, f"{path.name} tells students to call {call} but never imports {root}"


def test_wrong_answers_get_a_specific_hint(ds):
    _, right, _ = _ray_factor(ds)
    with pytest.raises(AssertionError, match="middle of a side"):
        exercises.check_ray_factor(QUICK.sim.camera, _ray_factor(ds)[2]["your_factor"])
    with pytest.raises(AssertionError, match="at least 1"):
        exercises.check_ray_factor(QUICK.sim.camera, 0.5)
    assert exercises.check_ray_factor(QUICK.sim.camera, right["your_factor"] * (1 + 5e-4))  # within 0.1%
    context, right, _ = _roc_auc(ds)
    with pytest.raises(AssertionError, match="1 minus"):
        exercises.check_roc_auc(context["y"], context["p_joint"], 1 - right["your_auc"])
    accuracy = float(((context["p_joint"] >= 0.5) == context["y"].astype(bool)).mean())
    with pytest.raises(AssertionError, match="accuracy"):
        exercises.check_roc_auc(context["y"], context["p_joint"], accuracy)
    with pytest.raises(AssertionError, match="kernel 10 then 8"):
        exercises.check_encoder_features(50, 785)
    assert exercises.check_encoder_features(50, 784)  # the paper's own 50 x 50: 16 x 7 x 7
