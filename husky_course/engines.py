"""Where embarrassingly parallel work runs: ``HUSKY_ENGINE`` (or the CLI's ``--engine``) is read here only.

``local`` (the default) runs tasks in this process (one worker) or in a pool of local processes;
``ray`` runs each task as a Ray task, on a local cluster started on demand or, when
``RAY_ADDRESS`` is set, on the cluster it names. Data collection (one task per shard), simulator
labels (chunks of states) and evaluation (chunks of worlds) all go through :func:`map_tasks`, and
every task depends on its own arguments alone, so the results are the same bytes on either engine
and for any number of workers.

A task must be a picklable, module-level function of picklable arguments: simulators (PyBullet's
included) are built inside the task from a backend name and a config, never shipped live. Each task
runs with one torch thread and one thread of numpy's BLAS (:func:`_one_thread`), so parallel tasks do
not fight over cores. Ray is an optional extra (``pip install -e .[ray]``; ``make install`` installs
it) imported only when the ``ray`` engine is used: ``import husky_course`` never needs it.
"""

from __future__ import annotations

import contextlib
import functools
import importlib.util
import os
import sys
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

from .checks import is_int
from .progress import tqdm

ENV = "HUSKY_ENGINE"
ENGINES = ("local", "ray")


@dataclass(frozen=True)
class EngineConfig:
    """How parallel work is cut into tasks; no result depends on these numbers.

    They are kept here rather than in :mod:`husky_course.config` because they are not part of any
    profile or artifact key: only speed and robustness change with them.
    """

    worlds_per_task: int = 25  #: evaluation worlds per task (a Ray task costs about a millisecond)
    max_retries: int = 3  #: times Ray re-runs a task whose worker process died
    object_store_mb: int = 512  #: object store of a local Ray cluster started on demand
    #: threads of numpy's BLAS (OpenBLAS) in a worker process (``None``: the library's own, one per core).
    #: Two workers on two cores, each with two BLAS threads, fight over the cores: one per worker made the
    #: moving disc planner's evaluation 2.0x as fast, the same episodes (``benchmarks/bench_threads.py``)
    worker_blas_threads: int | None = 1


ENGINE = EngineConfig()
_chosen: str | None = None  # set by the CLI's --engine; wins over the environment
_started_here = False  # whether this process started the Ray cluster it is attached to


def resolve_engine(name: str | None = None) -> str:
    """The engine for ``name`` (``local`` or ``ray``).

    ``None`` means the CLI's choice (:func:`set_engine`), else ``$HUSKY_ENGINE``, else ``local``.
    Raises ``ValueError`` for an unknown name, or for ``ray`` when Ray is not installed.
    """
    name = (name or _chosen or os.environ.get(ENV) or "local").strip().lower()
    if name not in ENGINES:
        raise ValueError(f"unknown engine {name!r} (--engine or ${ENV}): choose one of {', '.join(ENGINES)}")
    if name == "ray" and importlib.util.find_spec("ray") is None:
        raise ValueError("engine 'ray' asked for, but Ray is not installed: pip install -e .[ray]")
    return name


def set_engine(name: str | None) -> str:
    """Choose the engine for this process (the CLI's ``--engine``); checked now, not at first use."""
    global _chosen
    engine = resolve_engine(name)
    _chosen = name
    return engine


@contextlib.contextmanager
def _one_thread(worker: bool, blas: int | None = None) -> Iterator[None]:
    """Run the body with one torch thread (the previous count is restored afterwards) and, in a
    ``worker`` process, ``blas`` threads of numpy's BLAS (``None``: as it is).

    Torch is not imported for a task that does not use it: in a ``worker`` process where it is not
    loaded yet, ``OMP_NUM_THREADS=1`` makes a torch imported later start with one thread. In the
    caller's own process (serial local work) nothing changes unless torch is already loaded.
    """
    with contextlib.ExitStack() as stack:
        if worker and blas is not None:
            from threadpoolctl import threadpool_limits

            stack.enter_context(threadpool_limits(limits=int(blas), user_api="blas"))
        if "torch" not in sys.modules:
            if worker:
                os.environ["OMP_NUM_THREADS"] = "1"
            yield
            return
        import torch

        before = torch.get_num_threads()
        torch.set_num_threads(1)
        try:
            yield
        finally:
            torch.set_num_threads(before)


def _call(fn: Callable[..., Any], shared: Any, task: Any, worker: bool = True,
          blas: int | None = None) -> Any:
    with _one_thread(worker, blas):
        return fn(task) if shared is None else fn(shared, task)


def limit_worker_threads() -> None:
    """Give this process one torch thread and :data:`ENGINE`'s BLAS threads for good: the initializer
    of a script's own ``multiprocessing.Pool`` (the library's tasks get them from :func:`map_tasks`)."""
    os.environ["OMP_NUM_THREADS"] = "1"
    if "torch" in sys.modules:
        sys.modules["torch"].set_num_threads(1)
    if ENGINE.worker_blas_threads is not None:
        from threadpoolctl import threadpool_limits

        threadpool_limits(limits=int(ENGINE.worker_blas_threads), user_api="blas")


def _pool_job(job: tuple) -> tuple[int, Any]:
    """One task in a local pool process: ``(index, result)``."""
    i, fn, shared, task, blas = job
    return i, _call(fn, shared, task, blas=blas)


def ray_init_args(workers: int, config: EngineConfig = ENGINE) -> dict[str, Any]:
    """The arguments :func:`map_tasks` gives ``ray.init``.

    With ``RAY_ADDRESS`` set: attach to that cluster (its CPUs decide the parallelism, ``workers``
    is not used). Otherwise: a local cluster of ``workers`` CPUs and a modest object store.
    """
    address = os.environ.get("RAY_ADDRESS", "").strip()
    if address:
        return {"address": address, "ignore_reinit_error": True, "log_to_driver": False}
    return {
        "num_cpus": int(workers),
        "object_store_memory": int(config.object_store_mb) * 2**20,
        "include_dashboard": False,
        "ignore_reinit_error": True,
        "log_to_driver": False,
    }


def _ray(workers: int) -> Any:
    """The ``ray`` module, initialised: an existing connection is reused, else one is made."""
    global _started_here
    import ray

    if not ray.is_initialized():
        args = ray_init_args(workers)
        ray.init(**args)
        _started_here = "address" not in args  # a cluster we attached to is never shut down by us
    return ray


def shutdown_ray() -> None:
    """Stop the local Ray cluster this process started, if any (one it attached to is left alone).

    Not needed at the end of a program: Ray stops a cluster its driver started when the driver exits.
    """
    global _started_here
    if _started_here:
        import ray

        ray.shutdown()
        _started_here = False


def _husky_task(fn: Callable[..., Any], shared: Any, task: Any, blas: int | None) -> Any:
    """The body of every Ray task (its process title reads ``ray::_husky_task`` while it runs)."""
    return _call(fn, shared, task, blas=blas)


@functools.lru_cache(maxsize=4)
def _remote(max_retries: int) -> Any:
    import ray

    return ray.remote(num_cpus=1, max_retries=max_retries)(_husky_task)


def map_tasks(
    fn: Callable[..., Any],
    tasks: Sequence[Any],
    engine: str | None = None,
    workers: int = 1,
    shared: Any = None,
    desc: str = "tasks",
    unit: str = "task",
    sizes: Sequence[int] | None = None,
    initial: int = 0,
    progress: bool = True,
    config: EngineConfig | None = None,
) -> list[Any]:
    """``[fn(task) for task in tasks]`` (or ``fn(shared, task)``) on an engine, results in task order.

    Parameters
    ----------
    fn : callable
        A module-level function (pickled by reference); it must depend on its arguments alone.
    tasks : sequence
        Picklable task arguments (backend names and configs, not live simulators).
    engine : {"local", "ray"}, optional
        Default: :func:`resolve_engine` (``--engine``, else ``$HUSKY_ENGINE``, else ``local``).
    workers : int
        Local: 1 runs serially in this process, more uses a pool of that many processes (the
        platform's default start method). Ray: the CPUs of a local cluster started on demand
        (ignored when attaching to ``RAY_ADDRESS``).
    shared : object, optional
        One argument common to every task (e.g. a planner), sent once to Ray's object store.
    desc, unit, sizes, initial, progress :
        The progress bar: its label, its unit, how many units each task counts (default 1), the
        units already done before this call (a resumed job), and whether to show it at all.
    config : EngineConfig, optional
        Default: the module's :data:`ENGINE` as it is at the call (a benchmark may replace it).
        ``max_retries``: how often Ray re-runs a task whose worker process died;
        ``worker_blas_threads``: numpy's BLAS threads in each worker process.

    Returns
    -------
    list
        One result per task, in the order of ``tasks``, whatever the order they finished in.
    """
    engine, config = resolve_engine(engine), config or ENGINE
    if not is_int(workers) or workers < 1:  # type: ignore[operator]
        raise ValueError(f"workers must be a positive integer, got {workers!r}")
    tasks = list(tasks)
    weights = [1] * len(tasks) if sizes is None else [int(s) for s in sizes]
    if len(weights) != len(tasks):
        raise ValueError(f"sizes has {len(weights)} entries for {len(tasks)} tasks")
    results: list[Any] = [None] * len(tasks)
    bar = tqdm(total=initial + sum(weights), initial=initial, desc=desc, unit=unit, disable=not progress)
    try:
        if engine == "ray":
            ray = _ray(workers)
            remote = _remote(int(config.max_retries))
            ref = None if shared is None else ray.put(shared)  # sent once, not once per task
            blas = config.worker_blas_threads
            pending = {remote.remote(fn, ref, task, blas): i for i, task in enumerate(tasks)}
            waiting = list(pending)
            while waiting:
                ready, waiting = ray.wait(waiting, num_returns=1)
                for done in ready:
                    i = pending.pop(done)
                    results[i] = ray.get(done)
                    bar.update(weights[i])
        elif workers == 1 or len(tasks) <= 1:
            for i, task in enumerate(tasks):
                results[i] = _call(fn, shared, task, worker=False)
                bar.update(weights[i])
        else:
            import multiprocessing as mp

            ctx = mp.get_context()  # the platform's default start method (tasks are picklable)
            jobs = [(i, fn, shared, task, config.worker_blas_threads) for i, task in enumerate(tasks)]
            with ctx.Pool(min(workers, len(jobs))) as pool:
                for i, result in pool.imap_unordered(_pool_job, jobs):
                    results[i] = result
                    bar.update(weights[i])
    finally:
        bar.close()
    return results
