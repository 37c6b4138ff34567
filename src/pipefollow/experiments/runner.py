"""Run an experiment: map the pure ``run_trial(config, seed)`` over its trials and seeds.

The parent process owns the run folder (:mod:`pipefollow.experiments.store`): it saves every
finished trial the moment its result arrives, so an interruption (Ctrl-C, ``kill``, a crash)
loses only the trials still running, and starting again in the same folder computes only what
is missing. The backend — ``serial``, ``process`` or ``ray`` (:mod:`pipefollow.experiments.backends`)
— decides where trials run, never their numbers; before any trial, :func:`warm_up` compiles (or
loads) the compiled code every kind of trial uses, once.
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import os
import sys
import time
from collections.abc import Callable, Mapping
from contextlib import closing
from dataclasses import dataclass, field
from pathlib import Path

from pipefollow.experiments import backends, folder, store, tables
from pipefollow.experiments.backends import TrialFn, Work
from pipefollow.experiments.config import ExperimentConfig, TrialConfig
from pipefollow.experiments.trial import TrialResult, run_trial
from pipefollow.files.output_paths import first_missing, remove_empty_folders
from pipefollow.files.progress import progress


@dataclass(frozen=True)
class RunSummary:
    """What :func:`run_experiment` did.

    Attributes:
        run_dir: the run folder.
        backend: the backend used.
        workers: trials run at the same time (1 for ``serial`` or without work; Ray's CPUs for ``ray``).
        trials_total: trials × seeds of the experiment.
        trials_computed: those computed by this call.
        trials_reused: those found finished in the run folder.
        wall_seconds: time this call took.
        tables: the regenerated ``results.csv`` and ``evaluation.csv`` (none if ``read_only``).
        read_only: the run folder was complete and not writable (read-only media): it was only read.
        results: every stored trial by (trial, seed), as the tables were written from them (none
            if ``read_only``): the report and summaries need not read the trial files again.
    """

    run_dir: Path
    backend: str
    workers: int
    trials_total: int
    trials_computed: int
    trials_reused: int
    wall_seconds: float
    tables: tuple[Path, ...] = ()
    read_only: bool = False
    results: Mapping[tuple[str, int], TrialResult] = field(default_factory=dict, repr=False, compare=False)


class RunInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped a run; what was saved stays, and running the same command again resumes."""

    def __init__(self, run_dir: Path, saved: int, total: int) -> None:
        self.run_dir, self.saved, self.total = run_dir, saved, total
        super().__init__(self.message)

    @property
    def message(self) -> str:
        """One line for the user."""
        return (
            f"interrupted: {self.saved} of {self.total} trials are saved in '{self.run_dir}'; "
            "run the same command again to resume"
        )


def check_inputs(exp: ExperimentConfig) -> None:
    """Fail before any work on what the trials would fail on late: unreadable pipelines."""
    from pipefollow.sim.pipe_names import resolve_fixed, resolve_training

    for name in dict.fromkeys(p.pipeline for t in exp.trials for p in t.phases):
        resolve_training(name)
    for t in exp.trials:
        if t.evaluate_on:
            resolve_fixed(t.evaluate_on)


def _compile_quietly(config: TrialConfig) -> None:
    """In a forked helper: compile (and cache) one kind of trial, then leave without a trace.

    ``os._exit`` skips the inherited stdout buffers and exit handlers; any failure is left for the
    parent, which runs the same tiny trial itself afterwards.
    """
    code = 0
    try:
        run_trial(config, 0)
    except BaseException:  # noqa: BLE001 - the parent reports it
        code = 1
    os._exit(code)


def compile_cache_filled() -> bool:
    """Whether numba's cache folder holds compiled functions already (any index file)."""
    import numba

    folder = numba.config.CACHE_DIR
    return bool(folder) and next(Path(folder).rglob("*.nbi"), None) is not None


def warm_up(configs: list[TrialConfig], parallel: bool = False) -> None:
    """Run a one-episode version of each distinct kind of learner once, in this process.

    This compiles (or loads from numba's cache) every compiled path the trials use, so that
    forked workers inherit the code and spawned ones find it cached instead of all compiling it
    at the same time. With ``parallel`` (and ``fork``) and an empty cache, the SARSA and CACLA
    paths are first compiled side by side in a child process and this one, which saves seconds;
    with a filled cache the child would only load what this process loads again afterwards
    (0.6 s more wall time, measured).
    """
    kinds: dict[tuple, TrialConfig] = {}
    for c in configs:
        # a trial trained through a sensor compiles no training loop: one that does warms the kind
        kinds.setdefault((c.algorithm, c.skew_deg > 0, c.supervised, c.train_through_sensor), c)
    tiny = [
        dataclasses.replace(c, phases=(dataclasses.replace(c.phases[0], episodes=1),), evaluate_on="")
        for c in kinds.values()
    ]
    helper = None
    algorithms = list(dict.fromkeys(c.algorithm for c in tiny))
    if parallel and len(algorithms) > 1 and sys.platform.startswith("linux") and not compile_cache_filled():
        other = [c for c in tiny if c.algorithm != algorithms[0]][0]
        helper = multiprocessing.get_context("fork").Process(
            target=_compile_quietly, args=(other,), daemon=True
        )
        with backends.forking():
            helper.start()
        first = [c for c in tiny if c.algorithm == algorithms[0]]
        for c in first:
            run_trial(c, 0)
        helper.join()
        tiny = [c for c in tiny if c not in first]  # the rest now loads from the cache
    for c in tiny:
        run_trial(c, 0)


def _compile_phase(name: str, configs: list[TrialConfig], parallel: bool, hidden: bool) -> None:
    """Warm up (:func:`warm_up`) with a line of its own on stderr when progress is shown."""
    if hidden:
        warm_up(configs, parallel=parallel)
        return
    print(f"{name}: compiling (cached after the first run) ...", file=sys.stderr, end="", flush=True)
    t0 = time.perf_counter()
    warm_up(configs, parallel=parallel)
    print(f" {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)


@dataclass(frozen=True)
class _How:
    """How :func:`run_experiment` runs its work: the backend and its settings, the progress shown."""

    backend: str
    workers: int | None
    ray_address: str | None
    trial_fn: TrialFn
    while_waiting: Callable[[], object] | None
    hidden: bool
    bar: Callable | None


def _prepare(run_dir: Path, exp: ExperimentConfig, created: bool) -> None:
    """Write (or check) the run folder's configuration; a folder this run created goes if that fails."""
    try:
        store.prepare(run_dir, exp)
    except Exception:
        if created:  # a folder holding another run (or none) is left as it is
            folder.discard_unfinished(run_dir, exp, created)
        raise


def _results(work: Work, n_workers: int, how: _How, ray_info: dict):
    """The backend's iterator of (config, result) over ``work``."""
    if how.backend == "serial" or not work:
        return backends.serial(work, how.trial_fn)
    if how.backend == "process":
        return backends.process_pool(work, how.trial_fn, n_workers, how.while_waiting)
    return backends.ray_tasks(work, how.trial_fn, how.workers, how.ray_address, ray_info, how.while_waiting)


def _run_work(run_dir: Path, exp: ExperimentConfig, done: set, in_hand: dict, created: bool, how: _How):
    """Compute the trials of ``exp`` not in ``done``, saving each as it arrives into ``in_hand`` too.

    Returns:
        The workers used and the trials computed.
    """
    work = [(t, seed) for t in exp.trials for seed in exp.seeds() if (t.name, seed) not in done]
    total = len(exp.trials) * exp.repeats
    n_workers = 1
    if how.backend == "process":
        n_workers = max(1, min(how.workers or os.cpu_count() or 1, len(work)))
    ray_info = {"cpus": 0}
    computed = 0
    try:
        if work and (how.backend != "serial" or how.trial_fn is run_trial):
            # Compiling (or loading the compiled code) is a phase of its own: inside the
            # trials' progress bar it made the first time estimate many times too long.
            _compile_phase(exp.name, [c for c, _ in work], n_workers > 1, how.hidden)
        label = f"{exp.name}: trials"
        with progress(total, label, hidden=how.hidden, unit="trials", bar=how.bar) as bar:
            bar.update(len(done))
            with closing(_results(work, n_workers, how, ray_info)) as results:
                for config, result in results:
                    store.save_trial(run_dir, result, config)
                    in_hand[config.name, result.seed] = result
                    computed += 1
                    bar.update(1)
    except KeyboardInterrupt:
        raise RunInterrupted(run_dir, len(done) + computed, total) from None
    except Exception as e:
        # nothing half-made stays: a policy without its trial, empty folders, a config alone
        folder.discard_unfinished(run_dir, exp, created)
        saved = len(done) + computed
        if saved:
            e.add_note(f"{saved} of {total} trials are saved in '{run_dir}'; running again resumes")
        raise
    if how.backend == "ray":
        n_workers = ray_info["cpus"] or 1
    return n_workers, computed


def run_experiment(
    exp: ExperimentConfig,
    out_dir: str | os.PathLike,
    backend: str = "process",
    workers: int | None = None,
    ray_address: str | None = None,
    show_progress: bool = True,
    trial_fn: TrialFn = run_trial,
    while_waiting: Callable[[], object] | None = None,
    progress_bar: Callable | None = None,
) -> RunSummary:
    """Run every (trial, seed) of ``exp`` not yet finished in the run folder ``out_dir``.

    Args:
        exp: the experiment; its seeds are ``exp.seeds()``.
        out_dir: the run folder (created; an existing one must hold the same configuration).
        backend: ``serial``, ``process`` or ``ray``.
        workers: trials at the same time (default: all cores; for Ray, the CPUs of a local instance).
        ray_address: address of a running Ray cluster (default: start a local instance).
        show_progress: progress on stderr: a bar on a terminal (``progress_bar``), else lines.
        trial_fn: the unit of work, ``run_trial`` or a function with its signature (picklable
            for the ``process`` backend on platforms without ``fork``).
        while_waiting: called once in this process when the trials have been handed to the
            ``process`` or ``ray`` workers, before their results are awaited: work for what
            follows the run (the command imports Matplotlib there, instead of after the trials).
        progress_bar: the bar drawn on a terminal (see :func:`pipefollow.files.progress.progress`).

    Returns:
        A :class:`RunSummary`; the results are in the run folder.

    Raises:
        ConfigError: unknown backend, ``workers`` < 1, missing Ray, a folder holding another
            configuration or in use by another run.
        RunInterrupted: on Ctrl-C, after stopping the workers; finished trials stay saved.
    """
    t0 = time.perf_counter()
    backends.check_backend(backend, workers)
    check_inputs(exp)
    total = len(exp.trials) * exp.repeats
    run_dir = Path(out_dir)
    if run_dir.is_dir() and not folder.writable(run_dir) and folder.is_complete(run_dir, exp):
        # A finished run on read-only media (a DVD, a read-only share): nothing to compute or write.
        return RunSummary(run_dir, backend, 1, total, 0, total, time.perf_counter() - t0, read_only=True)
    created = not (run_dir / store.CONFIG_FILE).exists()
    made = first_missing(run_dir)
    how = _How(backend, workers, ray_address, trial_fn, while_waiting, not show_progress, progress_bar)
    try:
        with folder.locked(out_dir) as run_dir:
            _prepare(run_dir, exp, created)
            in_hand: dict[tuple[str, int], TrialResult] = {}  # every result read or computed
            done = store.finished(run_dir, exp, in_hand)
            n_workers, computed = _run_work(run_dir, exp, done, in_hand, created, how)
            store.ensure_policies(run_dir, exp)
            results = store.stored_results(run_dir, exp, in_hand)
            written = tables.write_tables(run_dir, exp, results)
    except Exception:
        remove_empty_folders(run_dir, made)  # the lock file is gone now; so go empty folders made here
        raise
    return RunSummary(
        run_dir=Path(run_dir),
        backend=backend,
        workers=n_workers,
        trials_total=total,
        trials_computed=computed,
        trials_reused=len(done),
        wall_seconds=time.perf_counter() - t0,
        tables=tuple(written),
        results=results,
    )
