"""Decision time of Algorithm 1 (batched vs a naive loop) and of the planners with memory.

Run: ``python benchmarks/bench_decision.py [--profile quick] [--look-ahead 3] [--repeats 200]
[--episodes 20]``.

Times one decision of ``lookahead`` (25 primitives, ``look_ahead`` = 3) with the library's batched
implementation and with the line-by-line reference (one decoder and encoder call per primitive),
for both readings of the reward line, and prints milliseconds and the speed-up. Then times one
decision of the distilled planner, the memory student, the mapping planner and the disc planner, side
by side, along a real episode's images (the memory planners' maps grow as they go), on
``--episodes`` worlds of the tuning set (evaluation set ``EvalPlan.tuning_seed``). Uses trained
checkpoints if the profile has them, otherwise seeded untrained models (same cost; the disc planner
is left out without its trained network). Then the mapping planner's search two ways at every
decision of those episodes: its path tables against the clearance grid read at 21 samples per edge.
Last, the moving disc planner's decision two ways at every decision of as many moving-course
episodes: its draws sharing the standing points' clearances against each draw computing its own; and
that planner's decision with its ghosts (``ArrivalsConfig.ghosts``) against without, each along its own
runs on the same moving tuning worlds.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import torch

from husky_course.config import get_profile
from husky_course.models.safety import JointModel
from husky_course.planners.learned import algorithm1, algorithm1_reference
from husky_course.training.inference import single_thread


def timed(fn, repeats: int) -> float:
    for _ in range(5):
        fn()
    start = time.perf_counter()
    for _ in range(repeats):
        fn()
    return (time.perf_counter() - start) / repeats * 1000.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="quick")
    parser.add_argument("--look-ahead", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=200)
    parser.add_argument("--episodes", type=int, default=20, help="tuning-set episodes to decide along")
    args = parser.parse_args()
    try:
        from husky_course.training import builders

        model = builders.load("joint", get_profile(args.profile)).model
        source = f"trained joint model ({args.profile})"
    except Exception:  # no checkpoint yet: an untrained model costs the same
        torch.manual_seed(0)
        model = JointModel().eval()
        source = "untrained joint model"
    obs = np.random.default_rng(0).uniform(0, 1, (50, 50)).astype(np.float32)
    print(f"{source}; 25 primitives, look_ahead {args.look_ahead}; torch threads in the block: 1")
    k, slow_repeats = args.look_ahead, max(args.repeats // 10, 5)
    for reward in ("applied", "next_image"):
        with single_thread():
            fast = timed(lambda r=reward: algorithm1(model, obs, k, r), args.repeats)
            slow = timed(lambda r=reward: algorithm1_reference(model, obs, k, r), slow_repeats)
        print(
            f"  reward={reward:10s} batched {fast:7.2f} ms   naive loop {slow:8.2f} ms"
            f"   speed-up {slow / fast:5.1f}x"
        )
    decisions(get_profile(args.profile), args.episodes)
    searches(get_profile(args.profile), args.episodes)
    draws(get_profile(args.profile), args.episodes)
    ghost_cost(get_profile(args.profile), args.episodes)


def decisions(profile, episodes: int = 20) -> None:
    """ms per decision of the distilled, memory, mapping and disc planners along ``episodes`` tuning
    episodes."""
    from husky_course.evaluation.episodes import eval_world_seeds, run_episode
    from husky_course.models.safety import SurvivalNet
    from husky_course.planners.learned import DistilledPlanner
    from husky_course.planners.memory import MemoryPlanner
    from husky_course.planners.registry import make_planner
    from husky_course.sim.fast import FastSimulator
    from husky_course.training.memory import new_memory_net

    planners = {}
    for name in ("distilled", "memory"):
        try:
            planners[name] = make_planner(name, profile=profile)
        except Exception:  # no checkpoint: an untrained network costs the same
            torch.manual_seed(0)
            net = SurvivalNet() if name == "distilled" else new_memory_net(profile)
            planners[name] = DistilledPlanner(net) if name == "distilled" else MemoryPlanner(net, profile.sim)
    planners["mapping"] = make_planner("mapping", config=profile.sim)
    try:  # the disc planner's network is only trained, never replaced by an untrained one
        planners["discs"] = make_planner("discs", profile=profile)
    except Exception as exc:  # noqa: BLE001
        print(f"(no disc planner: {exc})")
    sim = FastSimulator(profile.sim)
    seed = profile.eval.tuning_seed
    print(f"one decision, single thread, over {episodes} episodes of evaluation set {seed} (tuning):")
    for name, planner in planners.items():
        seeds = eval_world_seeds(episodes, seed)
        times = [t for s in seeds for t in run_episode(planner, sim, int(s)).decision_times]
        mean, worst = 1e3 * float(np.mean(times)), 1e3 * float(np.max(times))
        print(f"  {name:10s} {mean:7.2f} ms mean   {worst:7.2f} ms max")


def searches(profile, episodes: int = 20) -> None:
    """The mapping planner's search on its own maps along ``episodes`` tuning episodes, two ways side by
    side at every decision: its path tables (every sample of every edge) against the clearance grid
    read at 21 samples of every edge (the tracker's reading, and the static planners' before)."""
    import time

    from husky_course.evaluation.episodes import eval_world_seeds, run_episode
    from husky_course.planners.mapping import MappingPlanner
    from husky_course.sim.fast import FastSimulator
    from husky_course.sim.lattice import expand_with

    times: list[tuple[float, float]] = []

    class BothSearches(MappingPlanner):
        def _search(self, horizon: int):  # noqa: ANN202
            every = max(1, (self._library.local_paths.shape[1] - 1) // (self.path_samples - 1))
            t0 = time.perf_counter()
            lattice = super()._search(horizon)
            t1 = time.perf_counter()
            expand_with(self._edge_check(horizon), self._library, np.zeros(3), horizon, every=every)
            times.append((t1 - t0, time.perf_counter() - t1))
            return lattice

    sim, planner = FastSimulator(profile.sim), BothSearches(profile.sim)
    for s in eval_world_seeds(episodes, profile.eval.tuning_seed):
        run_episode(planner, sim, int(s))
    table, grid = (1e3 * float(np.mean(t)) for t in zip(*times, strict=True))
    print(f"the mapping planner's search, {len(times)} decisions: path tables {table:.2f} ms, "
          f"clearance grid {grid:.2f} ms: {grid / table:.1f}x")


def draws(profile, episodes: int = 20) -> None:
    """The moving disc planner's decisions along ``episodes`` tuning episodes of the moving course, two
    ways side by side at every decision: its draws sharing the standing points' clearances (each lattice
    state's row computed once per decision, ``TrackingPlanner._start_check``) against each draw computing
    its own; the same choice and keys both ways, bit for bit."""
    import time

    from husky_course.config import with_world
    from husky_course.evaluation.episodes import eval_world_seeds, run_episode
    from husky_course.planners.registry import make_planner
    from husky_course.sim.fast import FastSimulator

    moving = with_world(profile, "moving")
    try:  # chapter 10's disc planner: the disc network of ``profile``, on the moving course
        planner = make_planner("discs", profile=profile, config=moving.sim)
    except Exception as exc:  # noqa: BLE001
        print(f"(no moving disc planner: {exc})")
        return
    decide, times = planner._decide, []

    def both(horizon: int) -> tuple[int, np.ndarray]:
        t0 = time.perf_counter()
        choice, keys = decide(horizon)  # shares them (and drops them when it returns)
        t1 = time.perf_counter()
        alone = planner._decide_over_draws(horizon)  # the same draws, each computing its own
        times.append((t1 - t0, time.perf_counter() - t1))
        if alone[0] != choice or not np.array_equal(alone[1], keys):
            raise AssertionError("sharing the standing clearances changed a decision")
        return choice, keys

    planner._decide = both
    sim = FastSimulator(moving.sim)
    with single_thread():
        for s in eval_world_seeds(episodes, profile.eval.tuning_seed):
            run_episode(planner, sim, int(s))
    shared, alone = (1e3 * float(np.mean(t)) for t in zip(*times, strict=True))
    print(f"the moving disc planner's decision, {len(times)} decisions: draws sharing the standing "
          f"clearances {shared:.2f} ms, each draw its own {alone:.2f} ms: {alone / shared:.2f}x (same keys)")


def ghost_cost(profile, episodes: int = 20) -> None:
    """ms per decision of the moving disc planner with its ghosts and without (``ghosts=False``), each along
    its own runs on the same ``episodes`` moving tuning worlds, single thread, side by side."""
    from husky_course.config import with_world
    from husky_course.evaluation.episodes import eval_world_seeds, run_episode
    from husky_course.planners.registry import make_planner
    from husky_course.sim.fast import FastSimulator

    moving = with_world(profile, "moving")
    try:
        planners = {f"ghosts {'on' if on else 'off'}": make_planner("discs", profile=profile,
                                                                   config=moving.sim, ghosts=on)
                    for on in (True, False)}
    except Exception as exc:  # noqa: BLE001
        print(f"(no moving disc planner: {exc})")
        return
    sim, ms = FastSimulator(moving.sim), {}
    with single_thread():
        for name, planner in planners.items():
            times = [t for s in eval_world_seeds(episodes, profile.eval.tuning_seed)
                     for t in run_episode(planner, sim, int(s)).decision_times]
            ms[name] = (1e3 * float(np.mean(times)), 1e3 * float(np.max(times)), len(times))
    line = ", ".join(f"{n} {m:.2f} ms mean ({w:.2f} max, {k} decisions)" for n, (m, w, k) in ms.items())
    print(f"the moving disc planner's decision along its own runs: {line}: "
          f"{ms['ghosts on'][0] / ms['ghosts off'][0]:.2f}x with its ghosts")


if __name__ == "__main__":
    main()
