"""Experiment: does one round of data aggregation (DAgger) improve the distilled planner?

Run: ``python benchmarks/exp_dagger.py [--profile full] [--worlds 3000] [--eval-worlds 500] [--epochs N]
[--max-images N]``.

Runs the trained ``distilled`` planner in ``--worlds`` training-range worlds that no dataset video
used (collection seed 1), labels every state it visited with the simulator (survival over 3 steps
for every primitive), retrains the same network on the dataset plus these states, and evaluates
both networks on the same worlds of the tuning set (evaluation set ``EvalPlan.tuning_seed``: a
choice is never made on the book's reporting set). ``--epochs`` overrides the retraining's epochs
and ``--max-images`` keeps only the first images of each dataset split (both for a smoke run).
Prints the states collected, the times and both success rates, and says whether the round helped.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np
import torch

from husky_course.config import get_profile
from husky_course.data import splits
from husky_course.data.collect import world_seed_for
from husky_course.data.labels import survival_at
from husky_course.data.store import get_dataset
from husky_course.evaluation.episodes import evaluate, run_episode
from husky_course.models.safety import SurvivalNet
from husky_course.planners.learned import DistilledPlanner
from husky_course.sim.fast import FastSimulator
from husky_course.training import builders, datasets
from husky_course.training.trainer import fit


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=3000)
    parser.add_argument("--eval-worlds", type=int, default=500)
    parser.add_argument("--epochs", type=int, default=None, help="retraining epochs (default: the profile's)")
    parser.add_argument("--max-images", type=int, default=None, help="images kept per split (default: all)")
    args = parser.parse_args()
    profile = get_profile(args.profile)
    ds = get_dataset(profile, progress=False)
    base = builders.load("distilled", profile).model
    sim, planner = FastSimulator(profile.sim), DistilledPlanner(base)
    start = time.perf_counter()
    images, poses, seeds = [], [], []
    for v in range(args.worlds):
        world_seed = world_seed_for(profile.data.seed + 1, v)  # a collection seed the dataset did not use
        episode = run_episode(planner, sim, world_seed, record=True)
        images += episode.observations
        poses += list(episode.poses[: len(episode.observations)])
        seeds += [world_seed] * len(episode.observations)
    print(f"states visited by the planner: {len(images)} ({time.perf_counter() - start:.0f} s)")
    start = time.perf_counter()
    labels = survival_at(
        np.array(seeds), np.array(poses), profile.model.distill_horizon, profile.sim, progress=False
    )
    print(f"labelled in {time.perf_counter() - start:.0f} s")
    tr, va = splits.split_all(ds, profile.data.seed)
    tr, va = tr[: args.max_images], va[: args.max_images]
    surv = torch.from_numpy(builders.get_survival_labels(profile, progress=False))
    pool = datasets.images_tensor(ds)
    new_images, new_labels = torch.from_numpy(np.array(images, np.float16)), torch.from_numpy(labels)
    cut = int(0.9 * len(new_images))
    train = {
        "image": torch.cat([pool[torch.from_numpy(tr)], new_images[:cut]]),
        "survival": torch.cat([surv[torch.from_numpy(tr)], new_labels[:cut]]),
    }
    val = {
        "image": torch.cat([pool[torch.from_numpy(va)], new_images[cut:]]),
        "survival": torch.cat([surv[torch.from_numpy(va)], new_labels[cut:]]),
    }
    torch.manual_seed(profile.train.distilled.seed)
    model = SurvivalNet(profile.model.distill_horizon)
    start = time.perf_counter()
    cfg = profile.train.distilled
    cfg = cfg if args.epochs is None else replace(cfg, epochs=args.epochs)
    fit(model, train, val, cfg, progress=False)
    print(f"retrained in {time.perf_counter() - start:.0f} s")
    rates, seed = {}, profile.eval.tuning_seed
    print(f"tuning set: {args.eval_worlds} worlds of evaluation set {seed}")
    for name, net in (("distilled", base), ("distilled + 1 DAgger round", model)):
        result = evaluate(DistilledPlanner(net), args.eval_worlds, seed=seed, progress=False)
        rates[name] = result
        print(f"  {name:28s} success {result.success_rate:.3f}  mean primitives {result.mean_prims:.2f}")
    before, after = rates.values()
    lo, hi = before.success_ci95
    verdict = "outside" if not lo <= after.success_rate <= hi else "inside"
    print(f"the DAgger round's success rate is {verdict} the original's 95% interval [{lo:.3f}, {hi:.3f}]")


if __name__ == "__main__":
    main()
