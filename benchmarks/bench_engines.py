"""Evaluation throughput on each engine, measured side by side in one run, and Ray's cost per task.

Run: ``python benchmarks/bench_engines.py [--planner heuristic] [--worlds 400] [--workers 2]``.
The worlds are the tuning set (evaluation set ``EvalPlan.tuning_seed``) unless ``--seed`` says.
Evaluates one planner on the same held-out worlds with the local engine (1 worker, then a pool of
``--workers`` processes) and on a local Ray cluster of ``--workers`` CPUs (started and warmed up
before the clock starts: its start-up time is printed apart), checks that the numbers agree, and
prints worlds/s and the ratios. Then times ``--noop-tasks`` tasks that do nothing on Ray (ms/task:
what one task costs beyond its work) and extrapolates, on paper, to a cluster of N machines.
"""

from __future__ import annotations

import argparse
import time

from husky_course.config import EvalPlan, get_profile
from husky_course.engines import ENGINE, map_tasks, shutdown_ray
from husky_course.evaluation.episodes import evaluate
from husky_course.planners.registry import LEARNED_PLANNERS, make_planner

TIMING = ("ms_per_decision", "ms_per_reset")


def timed_eval(planner, worlds: int, seed: int, engine: str, workers: int) -> tuple[float, dict]:
    t0 = time.perf_counter()
    result = evaluate(planner, worlds, seed, progress=False, engine=engine, workers=workers)
    elapsed = time.perf_counter() - t0
    return elapsed, {k: v for k, v in result.to_json().items() if k not in TIMING}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--planner", default="heuristic")
    ap.add_argument("--profile", default="quick", help="whose checkpoints a learned planner loads")
    ap.add_argument("--worlds", type=int, default=400)
    ap.add_argument("--seed", type=int, default=EvalPlan.tuning_seed, help="evaluation set (default: tuning)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--noop-tasks", type=int, default=500)
    args = ap.parse_args()
    kwargs = {"profile": get_profile(args.profile)} if args.planner in LEARNED_PLANNERS else {}
    planner = make_planner(args.planner, **kwargs)
    w = args.workers

    rows = {}
    rows["local, 1 worker"] = timed_eval(planner, args.worlds, args.seed, "local", 1)
    rows[f"local, {w} workers"] = timed_eval(planner, args.worlds, args.seed, "local", w)
    t0 = time.perf_counter()
    map_tasks(abs, range(4 * w), engine="ray", workers=w, progress=False)  # start the cluster
    startup = time.perf_counter() - t0
    # warm up (not timed): every worker has imported the library (and torch) and unpickled the planner
    warm = 2 * w * ENGINE.worlds_per_task
    evaluate(planner, warm, args.seed, progress=False, engine="ray", workers=w)
    rows[f"ray, {w} CPUs"] = timed_eval(planner, args.worlds, args.seed, "ray", w)

    base = rows["local, 1 worker"][0]
    reference = rows["local, 1 worker"][1]
    print(
        f"evaluation of {args.planner!r} on {args.worlds} worlds of evaluation set {args.seed}, "
        f"{ENGINE.worlds_per_task} worlds per task "
        f"(Ray cluster start-up {startup:.1f} s, not counted)"
    )
    for label, (seconds, numbers) in rows.items():
        same = "same numbers" if numbers == reference else "NUMBERS DIFFER"
        print(
            f"  {label:16s}: {seconds:7.2f} s  {args.worlds / seconds:8.1f} worlds/s  "
            f"x{base / seconds:5.2f} vs local 1 worker  ({same})"
        )
    t_local_w, t_ray = rows[f"local, {w} workers"][0], rows[f"ray, {w} CPUs"][0]
    print(f"  ratio ray/local ({w} workers each): x{t_local_w / t_ray:.2f}")

    n = args.noop_tasks
    t0 = time.perf_counter()
    map_tasks(abs, range(n), engine="ray", workers=w, progress=False)
    per_task_ms = 1e3 * (time.perf_counter() - t0) / n
    per_world_ms = 1e3 * t_ray / args.worlds * w  # CPU time per world on Ray
    task_ms = ENGINE.worlds_per_task * per_world_ms
    share = 100 * per_task_ms / task_ms
    print(
        f"Ray overhead: {per_task_ms:.2f} ms per no-op task ({n} tasks, {w} CPUs); a task of "
        f"{ENGINE.worlds_per_task} worlds does {task_ms:.0f} ms of work ({share:.2f}% overhead)"
    )
    per_cpu = args.worlds / t_ray / w
    dispatch = 1e3 / per_task_ms * ENGINE.worlds_per_task  # worlds/s one driver can hand out
    print(
        f"On paper: N machines of c CPUs give about N * c * {per_cpu:.1f} worlds/s until the driver's "
        f"dispatch limit (~{dispatch:.0f} worlds/s at this overhead); e.g. 100,000 worlds on 10 machines "
        f"of 16 CPUs: {100_000 / min(10 * 16 * per_cpu, dispatch):.0f} s, on this machine: "
        f"{100_000 / (args.worlds / t_ray) / 60:.0f} min"
    )
    shutdown_ray()


if __name__ == "__main__":
    main()
