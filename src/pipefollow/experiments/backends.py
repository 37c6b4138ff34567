"""Where an experiment's trials run: the backends, each an iterator of (config, result) as trials finish.

Every backend yields the trials of its ``work`` — (trial configuration, seed) pairs — as they
finish, and cleans up when it is closed (:func:`pipefollow.experiments.runner.run_experiment`
saves each result the moment it arrives). They differ in where trials run, never in their numbers:

* :func:`serial`: one after the other, in this process;
* :func:`process_pool`: a pool of worker processes on this machine (forked on Linux, so that they
  inherit the compiled numba code instead of each compiling it), the longest trials first
  (:func:`longest_first`);
* :func:`ray_tasks`: Ray tasks, on a local instance or on a cluster.
"""

from __future__ import annotations

import contextlib
import logging
import multiprocessing
import os
import signal
import sys
import warnings
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed

from pipefollow.experiments.config import ConfigError, TrialConfig
from pipefollow.experiments.trial import TrialResult

BACKENDS = ("serial", "process", "ray")

TrialFn = Callable[[TrialConfig, int], TrialResult]
Work = list[tuple[TrialConfig, int]]


def import_ray():
    """The ``ray`` module, or a :class:`ConfigError` saying how to install it."""
    try:
        import ray
    except ImportError:
        raise ConfigError("backend 'ray' needs the optional extra: pip install 'pipefollow[ray]'") from None
    return ray


@contextlib.contextmanager
def forking():
    """Fork without Python ≥ 3.12's warning about forking a multi-threaded process.

    The threads are BLAS's idle pool from importing NumPy; the forked workers run only our
    compiled code, which does not call BLAS, so the deadlock the warning guards against cannot
    occur, and forking lets the workers inherit the compiled code instead of loading it again.
    """
    with warnings.catch_warnings():
        warnings.filterwarnings(
            "ignore", message=r".*use of fork\(\) may lead to deadlocks", category=DeprecationWarning
        )
        yield


def _failed(e: BaseException, config: TrialConfig, seed: int) -> BaseException:
    e.add_note(f"while running trial '{config.name}' with seed {seed}")
    return e


def serial(work: Work, trial_fn: TrialFn) -> Iterator[tuple[TrialConfig, TrialResult]]:
    """The ``serial`` backend: the trials one after the other, in this process."""
    for config, seed in work:
        try:
            result = trial_fn(config, seed)
        except Exception as e:
            raise _failed(e, config, seed) from None
        yield config, result


def _worker_init(parent_pid: int) -> None:
    # Ctrl-C reaches the whole process group: the parent alone decides how to stop.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        # Die with the parent (kill -9 included) instead of computing for nobody.
        try:
            import ctypes

            ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):  # pragma: no cover
            pass
        if os.getppid() != parent_pid:  # the parent died before prctl took effect
            os._exit(1)


def _stop_workers(pool: ProcessPoolExecutor) -> None:
    terminate = getattr(pool, "terminate_workers", None)  # Python ≥ 3.14
    if terminate is not None:
        terminate()
        return
    for p in list((getattr(pool, "_processes", None) or {}).values()):
        if p.is_alive():
            p.terminate()


def longest_first(work: Work) -> Work:
    """``work`` with the trials likely to take longest first (stable among equals).

    Handing the long trials out first keeps a worker from starting one while the others have
    nothing left, so the last trials end together. The estimate: training through a sensor (frame by
    frame, some ten times a compiled loop's episode), the episodes of all phases, then an evaluation
    run after training, SARSA (its update of all actions), skew or supervision.
    """

    def cost(item: tuple[TrialConfig, int]) -> tuple:
        c = item[0]
        episodes = sum(p.episodes for p in c.phases)
        slow = c.train_through_sensor
        return (slow, episodes, bool(c.evaluate_on), c.algorithm == "sarsa", c.skew_deg > 0 or c.supervised)

    return sorted(work, key=cost, reverse=True)


def process_pool(
    work: Work, trial_fn: TrialFn, workers: int, while_waiting: Callable[[], object] | None = None
) -> Iterator[tuple[TrialConfig, TrialResult]]:
    """The ``process`` backend: a pool of ``workers`` processes, forked on Linux, the longest trials first.

    ``while_waiting`` is called once when the pool has every trial. Interrupted or failed, the
    trials not finished are cancelled and the workers stopped.
    """
    work = longest_first(work)
    ctx = multiprocessing.get_context("fork") if sys.platform.startswith("linux") else None
    pool = ProcessPoolExecutor(
        max_workers=workers, mp_context=ctx, initializer=_worker_init, initargs=(os.getpid(),)
    )
    futures = {}
    complete = False
    try:
        with forking():  # the pool forks its workers on the first submissions
            futures = {pool.submit(trial_fn, config, seed): (config, seed) for config, seed in work}
        if while_waiting is not None:
            while_waiting()
        for fut in as_completed(futures):
            config, seed = futures[fut]
            try:
                result = fut.result()
            except Exception as e:
                raise _failed(e, config, seed) from None
            yield config, result
        complete = True
    finally:
        if not complete:  # interrupted or failed: do not wait for trials nobody will save
            for fut in futures:
                fut.cancel()
            _stop_workers(pool)
        pool.shutdown(wait=True, cancel_futures=True)


def ray_tasks(
    work: Work,
    trial_fn: TrialFn,
    workers: int | None,
    address: str | None,
    info: dict,
    while_waiting: Callable[[], object] | None = None,
) -> Iterator[tuple[TrialConfig, TrialResult]]:
    """The ``ray`` backend: one Ray task per trial, on a local instance or the cluster at ``address``.

    ``info["cpus"]`` receives the CPUs of the instance; ``while_waiting`` is called once when the
    tasks are submitted. A Ray session this call started is shut down at the end.
    """
    ray = import_ray()
    connected_here = not ray.is_initialized()  # else: the caller's Ray session, left as it is
    pending = {}
    try:
        # Ray's INFO/WARNING start-up lines would drown the progress bar; errors still show.
        if connected_here and address:
            ray.init(address=address, log_to_driver=False, logging_level=logging.ERROR)
        elif connected_here:
            ray.init(
                num_cpus=workers or os.cpu_count(),
                include_dashboard=False,
                log_to_driver=False,
                logging_level=logging.ERROR,
            )
        info["cpus"] = int(ray.cluster_resources().get("CPU", 0))
        remote = ray.remote(num_cpus=1, max_retries=0)(trial_fn)
        pending = {remote.remote(config, seed): (config, seed) for config, seed in work}
        if while_waiting is not None:
            while_waiting()
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                config, seed = pending.pop(ref)
                try:
                    result = ray.get(ref)
                except Exception as e:
                    raise _failed(e, config, seed) from None
                yield config, result
    finally:
        for ref in pending:
            ray.cancel(ref, force=True)
        if connected_here:
            ray.shutdown()


def check_backend(backend: str, workers: int | None) -> None:
    """Refuse an unknown backend or fewer than one worker; a missing Ray before any work."""
    if backend not in BACKENDS:
        raise ConfigError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    if workers is not None and workers < 1:
        raise ConfigError(f"workers must be at least 1, got {workers}")
    if backend == "ray":
        import_ray()
