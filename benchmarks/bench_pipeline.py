"""The whole pipeline, stage by stage: collect, train every model, label, evaluate every planner.

Run: ``python benchmarks/bench_pipeline.py [--profile full] [--worlds 500] [--tiny]``.

Everything is built from scratch in a temporary artifact store (nothing is reused), and each
stage's wall time is printed as it finishes, with the total against the course's target
(<= 30 min on 2 cores for the full profile). The evaluation uses the profile's tuning worlds
(evaluation set ``EvalPlan.tuning_seed``, never the book's reporting set). ``--tiny`` shrinks the
profile to a few videos and one epoch per model: every stage runs, nothing is worth its numbers
(the smoke run of ``tests/test_benchmarks.py``).
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
from dataclasses import fields, replace


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=None, help="evaluation worlds (default: the profile's)")
    parser.add_argument("--tiny", action="store_true", help="a few videos, one epoch per model (smoke run)")
    args = parser.parse_args()
    store = tempfile.mkdtemp(prefix="husky-pipeline-")
    os.environ["HUSKY_ARTIFACTS"] = store  # before importing the library's resolver users

    from husky_course.config import TrainConfig, get_profile
    from husky_course.course import diagnosis
    from husky_course.data.store import get_dataset
    from husky_course.evaluation.episodes import evaluate
    from husky_course.planners.registry import LEARNED_PLANNERS, make_planner
    from husky_course.training import builders

    profile = get_profile(args.profile)
    if args.tiny:
        plan = profile.train
        one_epoch = {f.name: replace(getattr(plan, f.name), epochs=1) for f in fields(plan)
                     if isinstance(getattr(plan, f.name), TrainConfig)}
        profile = replace(profile, data=replace(profile.data, videos=40), train=replace(plan, **one_epoch))
    worlds = args.worlds or profile.eval.worlds
    seed = profile.eval.tuning_seed
    stages: list[tuple[str, float]] = []

    def stage(name: str, fn) -> object:
        start = time.perf_counter()
        out = fn()
        stages.append((name, time.perf_counter() - start))
        print(f"  {name:34s} {stages[-1][1]:8.1f} s", flush=True)
        return out

    print(f"profile {profile.name}{' (tiny)' if args.tiny else ''}, fresh store {store}, "
          f"evaluation set {seed} (tuning)")
    try:
        stage("collect the dataset", lambda: get_dataset(profile, progress=False))
        stage("train encoder + decoder", lambda: builders.get_encoder_decoder(profile, False))
        stage("train the paper's reward net", lambda: builders.get_reward_net(profile, False))
        stage("train safety CNN (image)", lambda: builders.get_safety_net(False, profile, False))
        stage("train safety CNN (image + prim)", lambda: builders.get_safety_net(True, profile, False))
        stage("train the joint model", lambda: builders.get_joint(profile, False))
        stage("chapter 4's variants and probes", lambda: diagnosis.get_diagnosis(profile, False))
        stage("train the RNN look-ahead", lambda: builders.get_rnn(profile, False))
        stage("simulator survival labels", lambda: builders.get_survival_labels(profile, False))
        stage("train the distilled planner", lambda: builders.get_distilled(profile, False))
        for name in ("random", "heuristic", "lookahead", "rnn", "distilled", "oracle"):
            kwargs = {"look_ahead": 2, "profile": profile} if name in LEARNED_PLANNERS else {}
            planner = make_planner(name, **kwargs)
            result = stage(f"evaluate {name} ({worlds} worlds)",
                           lambda p=planner: evaluate(p, worlds, seed, progress=False))
            print(f"      success {result.success_rate:.3f}", flush=True)  # type: ignore[attr-defined]
    finally:
        shutil.rmtree(store, ignore_errors=True)
    total = sum(t for _, t in stages)
    target = " (target <= 30 min)" if profile.name == "full" else ""
    print(f"  {'total':34s} {total:8.1f} s = {total / 60:.1f} min{target}")


if __name__ == "__main__":
    main()
