"""The experiment runner: backends agree, runs resume, interruptions lose only unfinished trials."""

from __future__ import annotations

import json
import multiprocessing
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from pipefollow.experiments import store
from pipefollow.experiments.backends import longest_first
from pipefollow.experiments.config import load_experiment, with_overrides
from pipefollow.experiments.runner import RunInterrupted, run_experiment
from pipefollow.experiments.schema import ConfigError, ExperimentConfig
from pipefollow.experiments.tables import write_tables
from pipefollow.experiments.trial import run_trial

# Two of the paper's trials (SARSA; supervised CACLA with skew, two phases and a validation run),
# 2 seeds × 5 episodes per phase.
TINY = with_overrides(load_experiment("paper"), repeats=2, episodes=5, trials=["sarsa", "validation"])
PAIRS = [(t.name, s) for t in TINY.trials for s in TINY.seeds()]


class Counting:
    """run_trial, counting its calls."""

    def __init__(self, fail_on_call: int | None = None, exc: type[BaseException] = KeyboardInterrupt):
        self.calls: list[tuple[str, int]] = []
        self.fail_on_call, self.exc = fail_on_call, exc

    def __call__(self, config, seed):
        self.calls.append((config.name, seed))
        if len(self.calls) == self.fail_on_call:
            raise self.exc()
        return run_trial(config, seed)


def tables(run_dir: Path) -> tuple[str, str]:
    return (run_dir / "results.csv").read_text(), (run_dir / "evaluation.csv").read_text()


def stamps(run_dir: Path) -> dict[str, tuple[int, int]]:
    """(inode, mtime) of every trial and policy file: a recomputed file gets a new inode."""
    return {
        p.relative_to(run_dir).as_posix(): (p.stat().st_ino, p.stat().st_mtime_ns)
        for p in [*run_dir.glob("trials/*/*.npz"), *run_dir.glob("policies/*.npz")]
    }


def assert_same_trials(a: Path, b: Path, exp: ExperimentConfig = TINY) -> None:
    for t in exp.trials:
        for seed in exp.seeds():
            ra, rb = store.load_trial(a, t.name, seed), store.load_trial(b, t.name, seed)
            for name in ("stats", "phase", "sigma", "weights"):
                np.testing.assert_array_equal(getattr(ra, name), getattr(rb, name), err_msg=name)
            assert ra.evaluation == rb.evaluation
            for c in ra.poses:
                np.testing.assert_array_equal(ra.poses[c], rb.poses[c])
    assert tables(a) == tables(b)


@pytest.fixture(scope="module")
def serial_run(tmp_path_factory) -> Path:
    """The tiny experiment, run once serially: the reference of the other backends."""
    run = tmp_path_factory.mktemp("serial")
    summary = run_experiment(TINY, run, backend="serial", show_progress=False)
    assert (summary.trials_computed, summary.trials_reused, summary.trials_total) == (4, 0, 4)
    return run


def test_serial_run_fills_the_run_folder(serial_run):
    assert store.finished(serial_run, TINY) == set(PAIRS)
    assert store.read_config(serial_run) == TINY
    files = {p.relative_to(serial_run).as_posix() for p in serial_run.rglob("*") if p.is_file()}
    assert files == {
        "config.json",  # and no .lock: a finished run folder holds results only
        "results.csv",
        "evaluation.csv",
        *(f"trials/{t}/seed-{s}.npz" for t, s in PAIRS),
        *(f"policies/{t}-seed{s}.npz" for t, s in PAIRS),
    }
    results, evaluation = tables(serial_run)
    assert len(results.splitlines()) == 1 + 2 * 5 + 2 * 10
    assert len(evaluation.splitlines()) == 1 + 2 * 2 + 2 * 3


def test_process_backend_gives_identical_results(serial_run, tmp_path):
    summary = run_experiment(TINY, tmp_path, backend="process", workers=2, show_progress=False)
    assert (summary.trials_computed, summary.workers) == (4, 2)
    assert_same_trials(serial_run, tmp_path)


def test_resume_recomputes_nothing(serial_run, tmp_path):
    run = tmp_path / "run"
    first = Counting()
    run_experiment(TINY, run, backend="serial", show_progress=False, trial_fn=first)
    assert sorted(first.calls) == sorted(PAIRS)
    before = stamps(run)

    again = Counting()
    summary = run_experiment(TINY, run, backend="serial", show_progress=False, trial_fn=again)
    assert again.calls == []
    assert (summary.trials_computed, summary.trials_reused) == (0, 4)
    assert stamps(run) == before
    assert tables(run) == tables(serial_run)

    store.trial_path(run, "validation", 2011).unlink()
    (store.trial_path(run, "sarsa", 2010)).write_bytes(b"damaged")
    third = Counting()
    summary = run_experiment(TINY, run, backend="process", show_progress=False, trial_fn=third)
    assert (summary.trials_computed, summary.trials_reused) == (2, 2)
    assert tables(run) == tables(serial_run)


def test_ctrl_c_keeps_what_is_saved_and_resumes(serial_run, tmp_path):
    interrupted = Counting(fail_on_call=3)
    with pytest.raises(RunInterrupted) as e:
        run_experiment(TINY, tmp_path, backend="serial", show_progress=False, trial_fn=interrupted)
    assert isinstance(e.value, KeyboardInterrupt)
    assert (e.value.saved, e.value.total) == (2, 4)
    assert e.value.message == (
        f"interrupted: 2 of 4 trials are saved in '{tmp_path}'; run the same command again to resume"
    )
    assert store.finished(tmp_path, TINY) == set(PAIRS[:2])
    assert not (tmp_path / "results.csv").exists()  # no partial tables that look complete

    resumed = Counting()
    run_experiment(TINY, tmp_path, backend="serial", show_progress=False, trial_fn=resumed)
    assert resumed.calls == PAIRS[2:]
    assert_same_trials(serial_run, tmp_path)


def test_a_failing_trial_keeps_the_others_and_says_where(tmp_path):
    failing = Counting(fail_on_call=2, exc=ZeroDivisionError)
    with pytest.raises(ZeroDivisionError) as e:
        run_experiment(TINY, tmp_path, backend="serial", show_progress=False, trial_fn=failing)
    notes = "\n".join(e.value.__notes__)
    assert "while running trial 'sarsa' with seed 2011" in notes
    assert f"1 of 4 trials are saved in '{tmp_path}'; running again resumes" in notes
    assert store.finished(tmp_path, TINY) == {("sarsa", 2010)}


# The process backend hands out the longest trials first (backends.longest_first).
FIRST = next((c.name, s) for c, s in longest_first([(t, s) for t in TINY.trials for s in TINY.seeds()]))


def _interrupting_trial(config, seed):
    """A worker's trial: the first one runs; the next one presses Ctrl-C (once) and then hangs."""
    run_dir = Path(os.environ["PIPEFOLLOW_TEST_RUN"])
    if (config.name, seed) == FIRST:
        return run_trial(config, seed)
    while not store.trial_path(run_dir, *FIRST).exists():
        time.sleep(0.01)
    try:
        os.close(os.open(run_dir / "ctrl-c", os.O_CREAT | os.O_EXCL))
        os.kill(os.getppid(), signal.SIGINT)
    except FileExistsError:
        pass
    time.sleep(120)
    raise AssertionError("a hung worker was not stopped")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the test's trial function needs fork")
def test_ctrl_c_stops_the_process_pool_without_waiting(tmp_path, monkeypatch):
    monkeypatch.setenv("PIPEFOLLOW_TEST_RUN", str(tmp_path))
    # Python's Ctrl-C handler, also where the test runner was started with SIGINT ignored (nohup, &)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    t0 = time.perf_counter()
    try:
        with pytest.raises(RunInterrupted) as e:
            run_experiment(
                TINY,
                tmp_path,
                backend="process",
                workers=2,
                show_progress=False,
                trial_fn=_interrupting_trial,
            )
    finally:
        signal.signal(signal.SIGINT, previous)
    assert time.perf_counter() - t0 < 60  # the hung workers were stopped, not waited for
    assert e.value.saved == 1
    assert multiprocessing.active_children() == []
    assert store.finished(tmp_path, TINY) == {FIRST}


def test_bad_backend_and_workers_are_config_errors(tmp_path):
    with pytest.raises(ConfigError, match="backend must be one of serial, process, ray, got 'dask'"):
        run_experiment(TINY, tmp_path / "a", backend="dask")
    with pytest.raises(ConfigError, match="workers must be at least 1"):
        run_experiment(TINY, tmp_path / "b", backend="process", workers=0)
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_missing_ray_is_a_config_error(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # makes `import ray` fail
    with pytest.raises(
        ConfigError, match=r"backend 'ray' needs the optional extra: pip install 'pipefollow\[ray\]'"
    ):
        run_experiment(TINY, tmp_path, backend="ray")


def test_a_different_config_in_the_same_folder_is_refused(serial_run):
    more = with_overrides(TINY, repeats=3)
    with pytest.raises(ConfigError, match=r"holds a different configuration \(repeats 2 there, 3 now\)"):
        run_experiment(more, serial_run, backend="serial")


@pytest.mark.ray
@pytest.mark.slow  # starts a local Ray instance (≈ 16 s)
def test_ray_backend_gives_identical_results(serial_run, tmp_path):
    pytest.importorskip("ray")
    summary = run_experiment(TINY, tmp_path, backend="ray", workers=2, show_progress=False)
    assert (summary.trials_computed, summary.backend) == (4, "ray")
    assert_same_trials(serial_run, tmp_path)


# ---------------------------------------------------------------------------------------------
# The command line


def reproduce_cmd(out: Path, *extra: str) -> list[str]:
    return [
        sys.executable,
        "-m",
        "pipefollow.cli",
        "reproduce",
        "--out",
        str(out),
        "--backend",
        "serial",
        "--no-figures",
        "--json",
        *extra,
    ]


# Big enough that a trial takes a good fraction of a second, so the kill lands mid-run.
KILL_RUN = ("--trial", "sarsa", "--trial", "cacla", "--repeats", "2", "--episodes", "1500")


@pytest.mark.slow  # a real run of 4 × 1,500 episodes killed midway and resumed (≈ 12 s)
def test_sigkill_midway_loses_only_unfinished_trials(tmp_path):
    killed = tmp_path / "killed"
    proc = subprocess.Popen(reproduce_cmd(killed, *KILL_RUN), stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120
        while not list(killed.glob("trials/*/seed-*.npz")):
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "no trial finished in time"
            time.sleep(0.005)
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.communicate()
    assert proc.returncode == -signal.SIGKILL, "the run finished before it could be killed"

    exp = store.read_config(killed)
    saved = store.finished(killed, exp)
    assert 1 <= len(saved) < 4
    # Every file is complete: trial files and policies load, and the only other files are the
    # configuration, the lock and temporary files, whose names cannot be taken for results.
    for p in killed.rglob("*"):
        if p.is_dir():
            continue
        rel = p.relative_to(killed).as_posix()
        if p.name.startswith(".") and p.name.endswith(".tmp"):
            continue
        if rel.startswith("trials/"):
            store.load_trial(killed, p.parent.name, int(p.stem.removeprefix("seed-")))
        elif rel.startswith("policies/"):
            from pipefollow.training.policy_files import load_policy

            load_policy(p)
        else:
            assert rel in ("config.json", ".lock"), rel
    # A saved trial has its policy (written just before the trial file; a policy without its
    # trial file, if the kill fell between the two, is rewritten by the rerun).
    before = {
        k: v
        for k, v in stamps(killed).items()
        if any(k in (f"trials/{t}/seed-{s}.npz", f"policies/{t}-seed{s}.npz") for t, s in saved)
    }
    assert len(before) == 2 * len(saved)

    done = subprocess.run(reproduce_cmd(killed, *KILL_RUN), capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert (report["trials_reused"], report["trials_computed"]) == (len(saved), 4 - len(saved))
    after = stamps(killed)
    assert {k: after[k] for k in before} == before  # the saved trials were not recomputed
    assert not [p for p in killed.rglob("*.tmp")]

    clean = tmp_path / "clean"
    run_experiment(exp, clean, backend="serial", show_progress=False)
    assert tables(killed) == tables(clean)


def test_cli_reproduce_json_and_errors(tmp_path):
    from click.testing import CliRunner

    from pipefollow.cli import main

    runner = CliRunner()
    out = tmp_path / "run"
    args = [
        "reproduce",
        "--out",
        str(out),
        "--backend",
        "serial",
        "--no-figures",
        "--json",
        "--trial",
        "sarsa",
        "--repeats",
        "1",
        "--episodes",
        "3",
    ]
    result = runner.invoke(main, args)
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert report["run_dir"] == str(out)
    assert (report["trials_computed"], report["trials_reused"]) == (1, 0)
    assert report["outputs"] == [str(out / "results.csv"), str(out / "evaluation.csv")]
    assert set(report["trials"]) == {"sarsa"}
    assert isinstance(report["trials"]["sarsa"]["mean_return_last50"], float)

    again = runner.invoke(main, args)
    assert json.loads(again.stdout)["trials_reused"] == 1

    for bad, message in [
        (["--backend", "dask"], "backend must be one of serial, process, ray, got 'dask'"),
        (["--repeats", "2"], "holds a different configuration (repeats 1 there, 2 now)"),
        (["--trial", "ppo"], "--trial: unknown trial 'ppo'; allowed: sarsa, cacla"),
        (["--experiment", str(tmp_path / "none.toml")], "none.toml': no such file"),
    ]:
        result = runner.invoke(main, [*args, *bad])
        assert result.exit_code == 2, result.output
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("pipefollow: error: ") and message in lines[0], lines

    result = runner.invoke(main, ["plot", str(out), "--json"])
    assert result.exit_code == 0, result.output
    drawn = json.loads(result.stdout)["outputs"]
    assert str(out / "REPORT.md") in drawn and all(Path(p).exists() for p in drawn)

    result = runner.invoke(main, ["plot", str(tmp_path)])
    assert result.exit_code == 2
    assert (
        result.stderr.strip() == f"pipefollow: error: '{tmp_path}' is not a run folder "
        "(no config.json; 'pipefollow reproduce' writes one)"
    )


def _no_space(*args, **kwargs):
    import errno

    raise OSError(errno.ENOSPC, "No space left on device")  # as a full disk reports it: no file name


def test_a_full_disk_before_any_trial_is_saved_leaves_no_run_folder(tmp_path, monkeypatch):
    out = tmp_path / "runs" / "run"
    monkeypatch.setattr(store, "_write_npz_atomic", _no_space)  # the trial file, after its policy
    with pytest.raises(OSError, match="No space left"):
        run_experiment(TINY, out, backend="serial", show_progress=False)
    assert list(tmp_path.iterdir()) == []  # nor the folder made for it


def test_a_full_disk_later_keeps_finished_trials_only(tmp_path, monkeypatch):
    out = tmp_path / "run"
    real = store._write_npz_atomic
    calls = []

    def second_fails(path, arrays):
        calls.append(path)
        if len(calls) == 2:
            _no_space()
        real(path, arrays)

    monkeypatch.setattr(store, "_write_npz_atomic", second_fails)
    with pytest.raises(OSError) as e:
        run_experiment(TINY, out, backend="serial", show_progress=False)
    assert f"1 of 4 trials are saved in '{out}'; running again resumes" in "\n".join(e.value.__notes__)
    files = {p.relative_to(out).as_posix() for p in out.rglob("*")}
    # no policy of the failed trial, no .lock
    assert files == {
        "config.json",
        "trials",
        "trials/sarsa",
        "trials/sarsa/seed-2010.npz",
        "policies",
        "policies/sarsa-seed2010.npz",
    }
    monkeypatch.setattr(store, "_write_npz_atomic", real)
    assert run_experiment(TINY, out, backend="serial", show_progress=False).trials_reused == 1


def test_a_full_disk_names_the_file_it_could_not_write(tmp_path, monkeypatch):
    import pipefollow.files.atomic

    monkeypatch.setattr(pipefollow.files.atomic.os, "fsync", _no_space)
    with pytest.raises(OSError) as e:
        write_tables(tmp_path, TINY)
    assert e.value.filename == str(tmp_path / "results.csv")
    assert list(tmp_path.iterdir()) == []  # and no temporary file stays


def test_compilation_is_its_own_phase_before_the_trials_progress_bar(tmp_path, monkeypatch, capsys):
    import click

    from pipefollow.experiments import runner

    events = []
    monkeypatch.setattr(runner, "warm_up", lambda configs, parallel=False: events.append("compile"))
    monkeypatch.setattr(runner.sys.stderr, "isatty", lambda: True)
    run_experiment(
        with_overrides(TINY, trials=["sarsa"]), tmp_path, backend="serial",
        progress_bar=lambda **k: (events.append("trials bar"), click.progressbar(**k))[1],
    )  # fmt: skip
    # the bar's time estimate starts after compiling: its first estimate is per trial, not per build
    assert events == ["compile", "trials bar"]
    assert "compiling" in capsys.readouterr().err


def _read_only(monkeypatch, folder: Path) -> None:
    """Make creating or writing any file under ``folder`` fail as on read-only media (even as root)."""
    import errno

    real_open = os.open
    writing = os.O_CREAT | os.O_WRONLY | os.O_RDWR | os.O_TRUNC

    def guarded(path, flags, *args, **kwargs):
        if flags & writing and Path(os.fsdecode(path)).resolve().is_relative_to(folder.resolve()):
            raise OSError(errno.EROFS, "Read-only file system", os.fsdecode(path))
        return real_open(path, flags, *args, **kwargs)

    monkeypatch.setattr(os, "open", guarded)


def test_a_complete_run_on_read_only_media_is_summarised(serial_run, tmp_path, monkeypatch):
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(serial_run, copy)
    before = stamps(copy)
    _read_only(monkeypatch, copy)
    summary = run_experiment(TINY, copy, backend="serial", show_progress=False)
    assert summary.read_only and (summary.trials_computed, summary.trials_reused) == (0, 4)
    assert stamps(copy) == before
    assert not (copy / ".lock").exists()
    # an incomplete one cannot be resumed there: the error names the folder
    (copy / "trials" / "sarsa" / "seed-2011.npz").unlink()
    with pytest.raises(OSError) as e:
        run_experiment(TINY, copy, backend="serial", show_progress=False)
    assert str(copy) in e.value.filename


def test_cli_summarises_a_complete_run_on_read_only_media(tmp_path, monkeypatch):
    from click.testing import CliRunner

    from pipefollow.cli import main

    out = tmp_path / "run"
    args = ["reproduce", "--out", str(out), "--backend", "serial", "--trial", "sarsa", "--repeats", "1"]
    args += ["--episodes", "3"]
    runner = CliRunner()
    first = runner.invoke(main, args)
    assert first.exit_code == 0, first.output
    _read_only(monkeypatch, out)
    res = runner.invoke(main, args)
    assert res.exit_code == 0, res.output
    assert f"note: '{out}' is complete and read-only: summarised, nothing written" in res.stderr
    assert "1 trials (0 computed, 1 reused)" in res.stdout and "wrote" not in res.stdout
    summary_rows = [line for line in first.stdout.splitlines() if line.startswith("SARSA")]
    assert summary_rows and summary_rows[0] in res.stdout  # the same summary as when it ran
    redraw = runner.invoke(main, ["plot", str(out)])  # redrawing needs to write: a clear refusal
    assert redraw.exit_code == 2
    lines = redraw.stderr.strip().splitlines()
    assert len(lines) == 1 and str(out) in lines[0] and "Read-only file system" in lines[0], lines


def test_a_refused_folder_is_left_as_it_is(serial_run, tmp_path):
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(serial_run, copy)
    (copy / "trials" / "sarsa" / "seed-2011.npz").unlink()  # its policy now has no trial file
    before = sorted(p.relative_to(copy).as_posix() for p in copy.rglob("*"))
    with pytest.raises(ConfigError, match="different configuration"):
        run_experiment(with_overrides(TINY, repeats=3), copy, backend="serial", show_progress=False)
    assert sorted(p.relative_to(copy).as_posix() for p in copy.rglob("*")) == before


def test_process_backend_hands_out_the_longest_trials_first():
    exp = load_experiment("paper")
    work = [(t, s) for t in exp.trials for s in exp.seeds()]
    ordered = longest_first(work)
    assert sorted(ordered, key=work.index) == work  # the same work, reordered
    names = [c.name for c, _ in ordered]
    assert names[: exp.repeats] == ["validation"] * exp.repeats  # two phases and an evaluation
    assert names[exp.repeats : 2 * exp.repeats] == ["sarsa"] * exp.repeats
    assert names[-exp.repeats :] == ["cacla"] * exp.repeats  # plain CACLA, one phase: the shortest
    assert [s for c, s in ordered if c.name == "cacla"] == list(exp.seeds())  # stable among equals


def test_the_side_compilation_runs_only_on_an_empty_compile_cache(tmp_path, monkeypatch):
    import numba

    from pipefollow.experiments import runner

    started = []
    monkeypatch.setattr(runner, "run_trial", lambda config, seed: None)
    monkeypatch.setattr(
        runner.multiprocessing.context.ForkProcess, "start", lambda self: started.append(self), raising=True
    )
    monkeypatch.setattr(runner.multiprocessing.context.ForkProcess, "join", lambda self, timeout=None: None)
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    configs = [t for t in TINY.trials]  # SARSA and CACLA: two compiled paths
    assert not runner.compile_cache_filled()
    runner.warm_up(configs, parallel=True)
    assert len(started) == 1
    (tmp_path / "pipefollow" / "sim").mkdir(parents=True)
    (tmp_path / "pipefollow" / "sim" / "decision.decide-10.py311.nbi").write_bytes(b"")
    assert runner.compile_cache_filled()
    runner.warm_up(configs, parallel=True)
    assert len(started) == 1  # a filled cache: everything loads here, no child


def test_while_waiting_runs_once_after_the_pool_has_the_trials_and_not_serially(tmp_path, monkeypatch):
    events = []
    real_save = store.save_trial
    monkeypatch.setattr(store, "save_trial", lambda *a, **k: (events.append("save"), real_save(*a, **k))[1])
    exp = with_overrides(TINY, trials=["sarsa"])
    run_experiment(
        exp, tmp_path / "p", backend="process", workers=2, while_waiting=lambda: events.append("wait")
    )
    assert events == ["wait", "save", "save"]  # before the first result is saved, and once
    events.clear()
    run_experiment(exp, tmp_path / "s", backend="serial", while_waiting=lambda: events.append("wait"))
    assert events == ["save", "save"]  # nothing runs beside a serial run
