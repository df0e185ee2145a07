"""Experiment: how the moving disc planner breaks ties of its draws' mean safe steps, from the same states.

Run: ``python benchmarks/exp_moving_ties.py [--profile full] [--worlds 1000] [--start 0] [--seed 1]
[--collection S] [--driver map] [--learned 3000] [--episodes 2000] [--episodes-start 1000] [--workers 2]``
(the disc planner needs its network: ``python -m husky_course train discs``).

With ``ArrivalsConfig.samples`` draws of what it doubts (the undecided first sights' walks, the tracked
walkers' speeds) the disc planner ranks each first primitive by its mean safe steps over the draws. Most
decisions end in a tie at the top: every draw's plan survives the whole horizon for several primitives.
``ties="map"`` broke it by the map's own rank (its best plan's clearance bins and lateral cost, with the
map's velocities, then the lowest index); ``ties="draws"`` by the draws' clearance bins, the fewest over
the draws first, then their mean (:func:`~husky_course.planners.tracking._ranked`).

1. **Same states.** The planner as ``--driver`` sets its ties drives worlds of the tuning set (evaluation
   set ``--seed``; or training worlds of collection ``--collection``). At every decision from which the
   true world still has a way through to the end, every first primitive is judged in the true world (a
   way through remains after it: the oracle's lattice search over the rest of the episode), and each
   rule chooses among the primitives tied at the top from the same draws. The driver's fatal choice ends
   the world (its later states are lost). Printed: each rule's fatal choices, and the decisions where
   only it / only the driver's rule was fatal, with an exact sign test.
2. **Learned** (``--learned N``): a network in place of a rule. Two hidden layers of 32 score each tied
   primitive from its draws' statistics, the map's rank, its geometry and the decision's (step, doubted
   and tracked discs), trained on the same kind of decisions in ``N`` training worlds of collection seed
   ``--learned-seed`` (6: no dataset, network or certificate uses it) to put its choice on a primitive
   that keeps a way through (softmax over the tied ones, the winners' share maximised), one world in ten
   validating; judged on the states of 1.
3. **Episodes** (``--episodes N``): the planner with each ``ties`` on worlds ``--episodes-start`` onwards
   of the same set: success, and the worlds won only with one.

Measured (full profile; the planner with ``ties="map"`` driving, as it was), fatal choices from the same
states: ``--worlds 1000 --learned 1000`` (tuning worlds 0-999, 8,924 winnable decisions) and ``--collection
6 --worlds 3000`` (26,636 winnable decisions); only the rule / only the driver, p:

=========================================  =====================  =====================
rule among the tied primitives             tuning worlds 0-999    collection 6, 3,000
=========================================  =====================  =====================
the map's own rank (the driver)            148                    438
the draws' mean clearance bins             141 (13 / 20, 0.30)    391 (24 / 71, < 0.001)
the draws' fewest bins, then mean          136 (17 / 29, 0.10)    384 (25 / 79, < 0.001)
learned (1,000 worlds of collection 6)     143 (9 / 14, 0.41)     —
=========================================  =====================  =====================

In 93 of the driver's 148 fatal choices on tuning worlds 0-999 another primitive tied with it at the top
mean kept a way through; in 69 of those one also tied with it in the map's own safe steps and clearance
bins (the lateral cost and the index chose). Of the tied primitives, 1.1% lose at the driver's other
decisions, 63% at its fatal ones. The rule was chosen among throwaway prototypes on the same recorded
statistics (tuning worlds 0-999, checked on collection 6), none of which did better: the most primitives
between a choice and the nearest untied one; the map's clearance bins smoothed over neighbouring
primitives; the first step's clearance to any map point; the map's bins first, then the draws' fewest;
ties widened to means within a few draws' share of a step of the top; a mean safe steps plus a share of
the draws' mean bins. The network (a first prototype trained on 3,000 worlds did no better) was given
the draws' statistics among its features and still chose worse than the rule it could have learned.
Episodes: see ``ArrivalsConfig.ties``.
"""

from __future__ import annotations

import argparse

import numpy as np
import torch

from husky_course.config import OracleConfig, Profile, get_profile, with_world
from husky_course.course.diagnosis import sign_test
from husky_course.data.collect import world_seed_for
from husky_course.engines import map_tasks
from husky_course.evaluation.episodes import eval_world_seeds, run_episode
from husky_course.evaluation.rollout import Rollout
from husky_course.evaluation.statistics import clopper_pearson
from husky_course.planners.mapping import MappingPlanner
from husky_course.planners.registry import make_planner
from husky_course.planners.tracking import _bins, _ranked, _steps
from husky_course.sim.fast import FastSimulator
from husky_course.sim.lattice import expand, survival

RULES = ("the map's own rank", "the draws' mean clearance bins", "the draws' fewest bins, then mean")


def instrument(planner) -> None:
    """Keep each decision's draws (their keys) and the map's own keys on ``planner._seen``."""
    decide, keys_if = planner._decide, planner._keys_if

    def record(horizon: int, speeds: np.ndarray) -> np.ndarray:
        keys = keys_if(horizon, speeds)
        planner._draws.append(keys)
        return keys

    def seen(horizon: int) -> tuple[int, np.ndarray]:
        planner._draws = []
        choice, ranked = decide(horizon)
        planner._seen = (np.array(planner._draws), MappingPlanner._decide(planner, horizon)[1], horizon)
        return choice, ranked

    planner._keys_if, planner._decide = record, seen


def statistics(planner, step: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(tied, choices, features)`` of the decision just made: which primitives tie at the top mean, each
    rule's choice (:data:`RULES`), and per primitive the learned rule's features ``(n, F)``."""
    draws, keys, horizon = planner._seen
    if not len(draws):  # nothing doubted: the map's choice, every rule's
        draws = keys[None]
    mean, bins = _steps(draws).mean(0), _bins(draws)
    least, average = bins.min(0), bins.mean(0)
    top = np.round(mean, 6)
    tied = (top == top.max()) & (keys > -1e8)
    choices = [_ranked(mean, keys)[0], _ranked(mean, keys, (average, average))[0],
               _ranked(mean, keys, (least, average))[0]]
    rank = np.argsort(np.argsort(-_ranked(mean, keys)[1]))
    lib, n = planner._library, len(keys)
    own = np.c_[_steps(keys), _bins(keys)]
    per = np.c_[mean, least, average, own, lib.offsets, np.minimum(rank, 24), rank == 0]
    best = np.where(tied[:, None], per, -np.inf).max(0)
    state = [step, horizon, planner.doubtful.sum(), planner.tracked.sum()]
    features = np.c_[per, per - best, np.tile(state, (n, 1))].astype(np.float32)
    return tied, np.array(choices), features


def decisions(args: tuple[Profile, list[int], str]) -> list[dict]:
    """Every winnable decision of the driver in each world of ``seeds``: its rules' choices, the tied
    primitives, their features and every primitive's outcome in the true world."""
    profile, seeds, driver = args
    sim, limit = FastSimulator(profile.sim), profile.sim.max_primitives
    planner = make_planner("discs", config=profile.sim, profile=profile, ties=driver)
    instrument(planner)
    out = []
    for seed in seeds:
        rollout = Rollout(planner, sim, seed, limit)
        for d in rollout:
            steps = limit - d.step
            lattice = expand(rollout.world, sim.library, d.pose, steps, OracleConfig.cap, d.step)
            win = survival(lattice) == steps
            if not win.any():
                break  # no way through from here: not a decision any rule could win
            tied, choices, features = statistics(planner, d.step)
            out.append({"seed": seed, "action": d.action, "win": win, "tied": tied, "choices": choices,
                        "features": features})
            if not win[d.action]:
                break
    return out


def learn(rows: list[dict], seed: int, epochs: int = 200) -> tuple[torch.nn.Module, np.ndarray, np.ndarray]:
    """The learned rule: a small network trained (listwise) on ``rows``' decisions whose tied primitives
    both keep and lose a way through; one world in ten validates (the best epoch is kept)."""
    rows = [r for r in rows if (r["tied"] & r["win"]).any() and (r["tied"] & ~r["win"]).any()]
    x = np.array([r["features"] for r in rows])
    mu, sd = x.reshape(-1, x.shape[2]).mean(0), x.reshape(-1, x.shape[2]).std(0) + 1e-6
    tied, win = np.array([r["tied"] for r in rows]), np.array([r["win"] for r in rows])
    val = np.array([r["seed"] % 10 == 0 for r in rows])
    torch.manual_seed(seed)
    net = torch.nn.Sequential(torch.nn.Linear(x.shape[2], 32), torch.nn.ReLU(), torch.nn.Linear(32, 32),
                              torch.nn.ReLU(), torch.nn.Linear(32, 1))
    opt = torch.optim.Adam(net.parameters(), 1e-3, weight_decay=1e-3)
    X, T, W = torch.tensor((x - mu) / sd), torch.tensor(tied), torch.tensor(win)

    def loss(i: np.ndarray) -> torch.Tensor:
        s = net(X[i]).squeeze(-1).masked_fill(~T[i], -1e9)
        return (torch.logsumexp(s, 1) - torch.logsumexp(s.masked_fill(~(T[i] & W[i]), -1e9), 1)).mean()

    best, kept, train = np.inf, None, np.flatnonzero(~val)
    for epoch in range(epochs):
        order = np.random.default_rng([seed, epoch]).permutation(train)
        for batch in np.array_split(order, max(1, len(order) // 128)):
            opt.zero_grad()
            loss(batch).backward()
            opt.step()
        with torch.no_grad():
            v = float(loss(np.flatnonzero(val))) if val.any() else -epoch
        if v < best:
            best, kept = v, {k: t.clone() for k, t in net.state_dict().items()}
    net.load_state_dict(kept)
    return net.eval(), mu, sd


def judged(rows: list[dict], choices: np.ndarray, name: str) -> str:
    """One line: ``choices``' fatal choices against the driver's at the same states."""
    driver = np.array([not r["win"][r["action"]] for r in rows])
    fatal = np.array([not r["win"][c] for r, c in zip(rows, choices, strict=True)])
    only, only_driver, p = sign_test(fatal, driver)
    changed = sum(int(c != r["action"]) for r, c in zip(rows, choices, strict=True))
    return (f"  {name:40s} {int(fatal.sum()):5d}  ({only} / {only_driver}, p = {p:.3f}; "
            f"{changed} choices differ)")


def episodes(args: tuple[Profile, list[int], str]) -> list[bool]:
    """Success of the disc planner with ``ties`` in each world of ``seeds``."""
    profile, seeds, ties = args
    sim = FastSimulator(profile.sim)
    planner = make_planner("discs", config=profile.sim, profile=profile, ties=ties)
    return [run_episode(planner, sim, s, profile.sim.max_primitives).success for s in seeds]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=1000, help="0: episodes only")
    parser.add_argument("--start", type=int, default=0, help="first world of the set's sequence")
    parser.add_argument("--seed", type=int, default=1, help="evaluation set (1: the tuning set)")
    parser.add_argument("--collection", type=int, help="judge on training worlds of this collection instead")
    parser.add_argument("--driver", choices=("map", "draws"), default="map", help="the driver's ties")
    parser.add_argument("--learned", type=int, default=0, help="the learned rule's training worlds (0: none)")
    parser.add_argument("--learned-seed", type=int, default=6)
    parser.add_argument("--episodes", type=int, default=0, help="worlds of episodes per setting (0: none)")
    parser.add_argument("--episodes-start", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    profile = with_world(get_profile(args.profile), "moving")

    def gather(seeds: list[int], what: str) -> list[dict]:
        parts = [(profile, seeds[i : i + 10], args.driver) for i in range(0, len(seeds), 10)]
        return [r for p in map_tasks(decisions, parts, workers=args.workers, desc=what, unit="10 worlds")
                for r in p]

    if args.worlds > 0:  # the same states (0: episodes only)
        if args.collection is None:
            seeds = [int(s) for s in eval_world_seeds(args.start + args.worlds, args.seed)[args.start :]]
            where = f"worlds {args.start}-{args.start + args.worlds - 1} of evaluation set {args.seed}"
        else:
            seeds = [world_seed_for(args.collection, v) for v in range(args.start, args.start + args.worlds)]
            where = f"worlds {args.start}-{args.start + args.worlds - 1} of collection {args.collection}"
        rows = gather(seeds, "decisions")
        driver = sum(not r["win"][r["action"]] for r in rows)
        print(f"discs (ties {args.driver!r} driving) on {where}, moving course, {args.profile} profile: "
              f"{len(rows)} winnable decisions, {driver} fatal choices of the driver")
        print(f"  {'rule among the tied primitives':40s} fatal  (only the rule / only the driver, p)")
        for i, name in enumerate(RULES):
            print(judged(rows, np.array([r["choices"][i] for r in rows]), name))
        if args.learned:
            train = gather([world_seed_for(args.learned_seed, v) for v in range(args.learned)], "training")
            net, mu, sd = learn(train, args.learned_seed)
            with torch.no_grad():
                score = [net(torch.tensor((r["features"] - mu) / sd)).squeeze(-1).numpy() for r in rows]
            picks = np.array([int(np.argmax(np.where(r["tied"], s, -np.inf)))
                              for r, s in zip(rows, score, strict=True)])
            print(judged(rows, picks, f"learned ({args.learned} worlds of collection {args.learned_seed})"))
    if args.episodes:
        worlds = [int(s) for s in eval_world_seeds(args.episodes_start + args.episodes, args.seed)]
        worlds = worlds[args.episodes_start :]
        won = {}
        for ties in ("map", "draws"):
            parts = [(profile, worlds[i : i + 10], ties) for i in range(0, len(worlds), 10)]
            done = map_tasks(episodes, parts, workers=args.workers, desc=f"ties {ties}", unit="10 worlds")
            won[ties] = np.array([w for p in done for w in p])
            lo, hi = clopper_pearson(int(won[ties].sum()), len(worlds))
            last = args.episodes_start + args.episodes - 1
            print(f"episodes, worlds {args.episodes_start}-{last} of evaluation set {args.seed}: "
                  f"ties {ties!r} {won[ties].mean():.3f} [{lo:.3f}, {hi:.3f}]", flush=True)
        a, b = won["draws"], won["map"]
        print(f"  worlds won only with 'draws': {int((a & ~b).sum())}, only with 'map': "
              f"{int((b & ~a).sum())}, p = {sign_test(~a, ~b)[2]:.3f}")


if __name__ == "__main__":
    main()
