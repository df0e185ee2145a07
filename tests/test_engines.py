"""The engines (:mod:`husky_course.engines`): local processes and a real local Ray cluster agree.

One Ray cluster (``ray.init(num_cpus=2)``) serves the whole session. Ray is installed by
``make install``: a missing Ray fails here, it is never skipped. Results are compared exactly:
datasets byte for byte, labels element for element, evaluation JSON number for number (all but
the two timing fields). One test SIGKILLs a Ray worker in the middle of a task and checks that the
job still finishes with the same numbers.
"""

from __future__ import annotations

import json
import os
import signal
import sys
import threading
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import ray  # installed by `make install` (the `ray` extra): an ImportError here is a failure
from checkpoints import trained
from serial_survival import survival_steps

from husky_course import engines
from husky_course.cli import main as cli_main
from husky_course.config import get_profile
from husky_course.data.collect import collect
from husky_course.data.dataset import STEP_ARRAYS, VIDEO_ARRAYS, load_dataset
from husky_course.data.labels import survival_at, survival_steps_parallel
from husky_course.engines import map_tasks, ray_init_args, resolve_engine
from husky_course.evaluation.episodes import evaluate
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator

QUICK = get_profile("quick")
TIMING = ("ms_per_decision", "ms_per_reset")
TASK_TITLE = "ray::_husky_task"  # a Ray worker's process title while it runs one of our tasks


@pytest.fixture(scope="session")
def ray_cluster():
    """One local Ray cluster of 2 CPUs for the session, shut down at its end."""
    ray.init(num_cpus=2, object_store_memory=256 * 2**20, include_dashboard=False, log_to_driver=False)
    yield
    ray.shutdown()


def _json(result) -> dict:
    return {k: v for k, v in result.to_json().items() if k not in TIMING}


def _square_plus(offset: int, x: int) -> int:
    time.sleep(0.01 * (x % 3))  # finish out of order
    return x * x + offset


def _torch_threads(_: int) -> int:
    import torch

    return torch.get_num_threads()


def _blas_threads(_: int) -> list[int]:
    from threadpoolctl import threadpool_info

    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


# Ray workers cannot import this test module: send its functions by value (the library's are
# imported by the workers from the installed package)
ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])


def test_unknown_engines_are_refused_in_one_line(monkeypatch, capsys):
    with pytest.raises(ValueError, match=r"unknown engine 'spark' .*choose one of local, ray"):
        resolve_engine("spark")
    monkeypatch.setenv(engines.ENV, "dask")
    with pytest.raises(ValueError, match=r"unknown engine 'dask' \(--engine or \$HUSKY_ENGINE\)"):
        resolve_engine()
    with pytest.raises(ValueError, match="unknown engine"):
        map_tasks(abs, [1], engine="threads")
    monkeypatch.delenv(engines.ENV)
    assert resolve_engine() == "local"
    with pytest.raises(SystemExit):
        cli_main(["evaluate", "--planner", "random", "--engine", "spark"])
    assert "invalid choice: 'spark'" in capsys.readouterr().err
    monkeypatch.setattr(engines.importlib.util, "find_spec", lambda name: None)
    with pytest.raises(ValueError, match=r"Ray is not installed: pip install -e \.\[ray\]"):
        resolve_engine("ray")
    assert cli_main(["evaluate", "--planner", "random", "--worlds", "2", "--engine", "ray"]) == 2
    assert "pip install -e .[ray]" in capsys.readouterr().err
    assert cli_main(["evaluate", "--planner", "random", "--worlds", "2", "--workers", "0"]) == 2
    assert "workers must be >= 1, got 0" in capsys.readouterr().err


def test_ray_address_is_honoured(monkeypatch):
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    local = ray_init_args(3)
    assert local["num_cpus"] == 3 and "address" not in local and local["object_store_memory"] > 0
    monkeypatch.setenv("RAY_ADDRESS", "ray://head.example:10001")
    assert ray_init_args(3) == {
        "address": "ray://head.example:10001",
        "ignore_reinit_error": True,
        "log_to_driver": False,
    }
    calls = []
    monkeypatch.setattr(ray, "is_initialized", lambda: False)
    monkeypatch.setattr(ray, "init", lambda **kw: calls.append(kw))
    monkeypatch.setattr(engines, "_started_here", False)
    engines._ray(2)
    assert calls == [ray_init_args(2)] and calls[0]["address"] == "ray://head.example:10001"
    assert engines._started_here is False  # a cluster we attached to is never shut down by us


def test_results_come_back_in_task_order(ray_cluster):
    tasks = list(range(12))
    expected = [x * x + 5 for x in tasks]
    assert map_tasks(_square_plus, tasks, engine="local", shared=5, progress=False) == expected
    assert map_tasks(_square_plus, tasks, engine="local", workers=2, shared=5, progress=False) == expected
    assert map_tasks(_square_plus, tasks, engine="ray", workers=2, shared=5, progress=False) == expected
    assert map_tasks(abs, [], engine="ray", progress=False) == []


def test_every_task_runs_with_one_torch_thread(ray_cluster):
    import torch

    before = torch.get_num_threads()
    assert map_tasks(_torch_threads, [0, 1], engine="ray", workers=2, progress=False) == [1, 1]
    assert map_tasks(_torch_threads, [0, 1], engine="local", workers=2, progress=False) == [1, 1]
    assert map_tasks(_torch_threads, [0, 1], engine="local", workers=1, progress=False) == [1, 1]
    assert torch.get_num_threads() == before  # serial work in this process: restored afterwards


def test_every_worker_runs_numpy_with_one_blas_thread(ray_cluster, monkeypatch):
    """Two workers on two cores with numpy's own BLAS threads (one per core each) fight over the
    cores (``benchmarks/bench_threads.py``); each worker gets one, and ``None`` leaves what it has
    (here two: ``make test`` itself starts numpy with one, through ``OMP_NUM_THREADS``)."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=2, user_api="blas"):
        own = _blas_threads(0)
        assert own and set(own) == {2}, f"numpy's BLAS should report two threads here: {own}"
        one = [[1] * len(own)] * 2
        for engine in ("local", "ray"):
            assert map_tasks(_blas_threads, [0, 1], engine=engine, workers=2, progress=False) == one
        serial = map_tasks(_blas_threads, [0], engine="local", workers=1, progress=False)
        assert serial == [own]  # serial work in this process: as it is
        monkeypatch.setattr(engines, "ENGINE", replace(engines.ENGINE, worker_blas_threads=None))
        assert map_tasks(_blas_threads, [0, 1], engine="local", workers=2, progress=False) == [own, own]


def test_collection_is_the_same_bytes_on_ray(tmp_path, ray_cluster):
    prof = replace(QUICK, data=replace(QUICK.data, shard_videos=15))
    a = collect(tmp_path / "local", prof, videos=60, seed=4, workers=1, progress=False)
    b = collect(tmp_path / "ray", prof, videos=60, seed=4, workers=2, progress=False, engine="ray")
    for name in STEP_ARRAYS + VIDEO_ARRAYS:
        assert (a / f"{name}.npy").read_bytes() == (b / f"{name}.npy").read_bytes(), name
    assert load_dataset(a).meta["sha256"] == load_dataset(b).meta["sha256"]


def test_survival_labels_are_the_same_on_ray(small_dataset_dir, ray_cluster):
    ds = load_dataset(small_dataset_dir)
    idx = np.arange(0, len(ds), 3)[:840]  # three chunks of states
    seeds, poses = ds.world_seeds[ds.episode[idx]], np.asarray(ds.poses[idx], float)
    local = survival_at(seeds, poses, 2, QUICK.sim, workers=1, progress=False, engine="local")
    on_ray = survival_at(seeds, poses, 2, QUICK.sim, workers=2, progress=False, engine="ray")
    assert local.shape == (len(idx), 25) and local.max() == 2
    np.testing.assert_array_equal(local, on_ray)


def test_the_cli_engine_reaches_labels_and_evaluation(small_dataset_dir, ray_cluster, monkeypatch, capsys):
    """``train --engine ray`` reaches the labels through :func:`resolve_engine`, not through arguments."""
    monkeypatch.setattr(engines, "_chosen", None)  # restored after the test: --engine sets it
    started, real = [], engines._ray
    monkeypatch.setattr(engines, "_ray", lambda workers: started.append(workers) or real(workers))
    argv = ["evaluate", "--planner", "heuristic", "--worlds", "6", "--seed", "2", "--json", "--no-progress"]
    assert cli_main(argv) == 0
    here = {k: v for k, v in json.loads(capsys.readouterr().out).items() if k not in TIMING}
    assert not started
    assert cli_main([*argv, "--engine", "ray", "--workers", "2"]) == 0
    assert {k: v for k, v in json.loads(capsys.readouterr().out).items() if k not in TIMING} == here
    assert started == [2] and resolve_engine() == "ray"
    ds = load_dataset(small_dataset_dir)
    idx = np.arange(0, len(ds), 5)[:100]
    labels = survival_steps_parallel(ds, 2, idx, config=QUICK.sim, progress=False)  # no engine argument
    assert started == [2, 2]
    np.testing.assert_array_equal(labels, survival_steps(ds, 2, idx, QUICK.sim))


@pytest.mark.parametrize("name", ["random", "heuristic", "oracle", "memory"])
def test_evaluation_is_the_same_numbers_on_any_engine(name, ray_cluster):
    planner = trained(name) if name == "memory" else make_planner(name)
    here = evaluate(planner, 20, seed=3, sim=FastSimulator(QUICK.sim), progress=False)
    on_ray = evaluate(planner, 20, seed=3, progress=False, engine="ray", workers=2, worlds_per_task=3)
    assert _json(on_ray) == _json(here)
    assert [e.actions for e in on_ray.episodes] == [e.actions for e in here.episodes]
    if name in ("random", "memory"):  # a local pool too: worlds in another order, other processes
        pooled = evaluate(planner, 20, seed=3, progress=False, workers=2, worlds_per_task=7, keep_paths=False)
        assert _json(pooled) == _json(here)
        assert all(len(e.path) == 0 for e in pooled.episodes) and len(here.episodes[0].path) > 0


def _ray_task_pids() -> list[int]:
    """Processes running one of our Ray tasks now (their title is in /proc/PID/cmdline)."""
    pids = []
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit():
            continue
        try:
            cmdline = (proc / "cmdline").read_bytes()
        except OSError:
            continue
        if cmdline.startswith(TASK_TITLE.encode()):
            pids.append(int(proc.name))
    return pids


def test_a_killed_ray_worker_does_not_change_the_result(ray_cluster):
    planner = make_planner("heuristic")
    expected = _json(evaluate(planner, 48, seed=4, progress=False))
    out: dict = {}

    def job() -> None:
        try:
            out["result"] = evaluate(planner, 48, seed=4, progress=False, engine="ray", worlds_per_task=6)
        except BaseException as exc:  # reported below, in the test's thread
            out["error"] = exc

    thread = threading.Thread(target=job)
    thread.start()
    killed = None
    deadline = time.monotonic() + 60
    while killed is None and thread.is_alive() and time.monotonic() < deadline:
        pids = _ray_task_pids()
        if pids:
            killed = pids[0]
            os.kill(killed, signal.SIGKILL)
        time.sleep(0.002)
    thread.join(120)
    assert killed is not None, "the evaluation finished before a worker could be killed; make it longer"
    assert not thread.is_alive(), "the evaluation did not finish after its worker was killed"
    assert "error" not in out, f"the job failed after a worker was killed: {out.get('error')!r}"
    assert killed not in _ray_task_pids()  # it really died (Ray started another worker for the retry)
    assert _json(out["result"]) == expected
