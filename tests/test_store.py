"""The run folder: atomic trial files, policies, resumption bookkeeping and the tidy tables."""

from __future__ import annotations

import json
import os

import numpy as np
import pandas as pd
import pytest
from llvmlite import binding as llvm

import pipefollow
from pipefollow.experiments import folder, store, tables
from pipefollow.experiments.schema import ConfigError, ExperimentConfig, Phase, TrialConfig, to_dict
from pipefollow.experiments.trial import TrialResult, build_agent
from pipefollow.files.sources import source_hash
from pipefollow.training.policy_files import load_policy

TRIALS = (
    TrialConfig(name="sarsa", label="SARSA", algorithm="sarsa", phases=(Phase("paper-left", 4),)),
    TrialConfig(
        name="sup-skew",
        label="supervised CACLA, skew 22.5°",
        algorithm="cacla",
        skew_deg=22.5,
        supervised=True,
        phases=(Phase("paper-left", 3), Phase("paper-right", 2)),
        evaluate_on="paper-validation",
    ),
)
EXP = ExperimentConfig(name="unit", repeats=2, seed=40, trials=TRIALS)


def fake_result(config: TrialConfig, seed: int) -> TrialResult:
    """A TrialResult with the shapes run_trial gives, filled with seeded random numbers."""
    rng = np.random.default_rng(seed)
    n = config.episodes
    phase = np.concatenate([np.full(p.episodes, i) for i, p in enumerate(config.phases)])
    controllers = ["learned", "heuristic"] + (["actor"] if config.supervised else [])
    return TrialResult(
        trial=config.name,
        seed=seed,
        stats=rng.normal(size=(n, 4)),
        phase=phase,
        sigma=np.linspace(1.0, 0.01, n),
        weights=rng.normal(size=build_agent(config).weights.shape),
        evaluation={c: tuple(float(v) for v in rng.normal(size=4)) for c in controllers},
        poses={c: rng.normal(size=(21 + k, 3)) for k, c in enumerate(controllers)},
        evaluation_pipeline=config.evaluate_on or config.phases[-1].pipeline,
        wall_seconds=1.25,
    )


def assert_same_result(a: TrialResult, b: TrialResult) -> None:
    assert (a.trial, a.seed, a.evaluation_pipeline, a.wall_seconds) == (
        b.trial,
        b.seed,
        b.evaluation_pipeline,
        b.wall_seconds,
    )
    for name in ("stats", "phase", "sigma", "weights"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert list(a.evaluation) == list(b.evaluation)
    assert a.evaluation == b.evaluation
    assert list(a.poses) == list(b.poses)
    for c in a.poses:
        np.testing.assert_array_equal(a.poses[c], b.poses[c])


def fill(run_dir, exp: ExperimentConfig = EXP) -> dict[tuple[str, int], TrialResult]:
    store.prepare(run_dir, exp)
    out = {}
    for t in exp.trials:
        for seed in exp.seeds():
            out[t.name, seed] = r = fake_result(t, seed)
            store.save_trial(run_dir, r, t)
    return out


def all_files(root):
    return sorted(p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file())


@pytest.mark.parametrize("trial", TRIALS, ids=lambda t: t.name)
def test_trial_round_trip(tmp_path, trial):
    r = fake_result(trial, 41)
    path = store.save_trial(tmp_path, r)
    assert path == tmp_path / "trials" / trial.name / "seed-41.npz"
    assert_same_result(store.load_trial(tmp_path, trial.name, 41), r)
    # plain arrays only: readable without pickle by anyone with numpy
    with np.load(path, allow_pickle=False) as z:
        assert list(z["evaluation_controllers"]) == list(r.evaluation)
        assert z["evaluation_values"].shape == (len(r.evaluation), 4)
    assert all_files(tmp_path) == [f"trials/{trial.name}/seed-41.npz"]  # no temporary file left


def test_policy_file_works_with_the_policy_loader(tmp_path):
    t = TRIALS[1]
    r = fake_result(t, 40)
    store.save_trial(tmp_path, r, t)
    agent = load_policy(store.policy_path(tmp_path, t.name, 40))
    np.testing.assert_array_equal(agent.weights, r.weights)
    assert agent.params.supervised and agent.params.skew == 0.5


def test_failed_write_leaves_neither_file_nor_temporary(tmp_path, monkeypatch):
    r = fake_result(TRIALS[0], 40)

    def broken_savez(f, **arrays):
        f.write(b"PK\x03\x04 half a zip")
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez", broken_savez)
    with pytest.raises(OSError, match="disk full"):
        store.save_trial(tmp_path, r)
    assert all_files(tmp_path) == []


@pytest.mark.parametrize(
    "damage",
    [
        lambda p: p.write_bytes(p.read_bytes()[: len(p.read_bytes()) // 2]),  # cut short
        lambda p: p.write_bytes(b""),  # empty
        lambda p: p.write_text("not a zip"),
        lambda p: np.savez(p, format=np.array("something-else")),  # a foreign .npz
    ],
    ids=["truncated", "empty", "garbage", "foreign"],
)
def test_corrupt_trial_file_counts_as_unfinished(tmp_path, damage):
    fill(tmp_path)
    victim = store.trial_path(tmp_path, "sup-skew", 41)
    damage(victim)
    with pytest.raises(store.StoreError, match=r"trial file '.*seed-41.npz'"):
        store.load_trial(tmp_path, "sup-skew", 41)
    assert store.finished(tmp_path, EXP) == {("sarsa", 40), ("sarsa", 41), ("sup-skew", 40)}
    assert not victim.exists()  # removed, so that the rerun writes it afresh


def test_trial_file_of_another_shape_counts_as_unfinished(tmp_path):
    fill(tmp_path)
    longer = ExperimentConfig(
        name="unit",
        repeats=2,
        seed=40,
        trials=(
            TrialConfig(name="sarsa", label="SARSA", algorithm="sarsa", phases=(Phase("paper-left", 5),)),
        ),
    )
    assert store.finished(tmp_path, longer) == set()


def test_finished_ignores_seeds_and_trials_outside_the_experiment(tmp_path):
    fill(tmp_path)
    fewer = ExperimentConfig(name="unit", repeats=1, seed=41, trials=TRIALS[:1])
    assert store.finished(tmp_path, fewer) == {("sarsa", 41)}
    assert store.finished(tmp_path / "nothing-here", EXP) == set()


def test_tables_read_back_with_pandas(tmp_path):
    results = fill(tmp_path)
    paths = tables.write_tables(tmp_path, EXP)
    assert paths == [tmp_path / "results.csv", tmp_path / "evaluation.csv"]
    df = pd.read_csv(tmp_path / "results.csv")
    assert list(df.columns) == [
        "experiment",
        "trial",
        "label",
        "algorithm",
        "skew_deg",
        "supervised",
        "repeat",
        "seed",
        "phase",
        "pipeline",
        "episode",
        "sigma",
        "return",
        "pipe_in_view",
        "progress_m",
        "time_lost_s",
    ]
    assert len(df) == sum(t.episodes for t in TRIALS) * EXP.repeats  # trials × seeds × episodes
    assert df["supervised"].dtype == bool and df["episode"].dtype == np.int64
    assert df.groupby(["trial", "seed"]).size().to_dict() == {
        ("sarsa", 40): 4,
        ("sarsa", 41): 4,
        ("sup-skew", 40): 5,
        ("sup-skew", 41): 5,
    }
    one = df[(df.trial == "sup-skew") & (df.seed == 41)]
    r = results["sup-skew", 41]
    assert one["episode"].tolist() == list(range(5))  # 0-based over the whole trial
    assert one["phase"].tolist() == [0, 0, 0, 1, 1]
    assert one["pipeline"].tolist() == ["paper-left"] * 3 + ["paper-right"] * 2
    assert set(one["repeat"]) == {1} and set(one["label"]) == {"supervised CACLA, skew 22.5°"}
    # full precision: the numbers read back are the numbers stored
    np.testing.assert_array_equal(
        one[["return", "pipe_in_view", "progress_m", "time_lost_s"]].to_numpy(), r.stats
    )
    np.testing.assert_array_equal(one["sigma"].to_numpy(), r.sigma)

    ev = pd.read_csv(tmp_path / "evaluation.csv")
    assert list(ev.columns) == [
        "trial",
        "label",
        "repeat",
        "seed",
        "pipeline",
        "controller",
        "return",
        "pipe_in_view",
        "progress_m",
        "time_lost_s",
    ]
    assert len(ev) == EXP.repeats * (2 + 3)  # sarsa: learned, heuristic; supervised: + actor
    row = ev[(ev.trial == "sup-skew") & (ev.seed == 40) & (ev.controller == "actor")].iloc[0]
    assert row["pipeline"] == "paper-validation"
    stat_names = ["return", "pipe_in_view", "progress_m", "time_lost_s"]
    assert tuple(row[stat_names]) == results["sup-skew", 40].evaluation["actor"]


def test_tables_leave_out_missing_trials(tmp_path):
    fill(tmp_path)
    store.trial_path(tmp_path, "sarsa", 40).unlink()
    tables.write_tables(tmp_path, EXP)
    df = pd.read_csv(tmp_path / "results.csv")
    assert len(df) == 4 + 5 + 5


def test_prepare_writes_the_resolved_config_and_accepts_the_same_again(tmp_path):
    run = tmp_path / "run"
    store.prepare(run, EXP)
    stored = json.loads((run / "config.json").read_text())
    code = stored.pop("code")
    machine = stored.pop("machine")
    assert stored == json.loads(json.dumps(to_dict(EXP)))
    assert code["version"] == pipefollow.__version__
    assert code["sources"] == source_hash(store.result_modules())
    assert code["numpy"] == np.__version__
    assert machine["packages"]["numpy"] == np.__version__
    assert machine["numba_cpu_target"] == (os.environ.get("NUMBA_CPU_NAME") or llvm.get_host_cpu_name())
    assert store.read_config(run) == EXP
    store.prepare(run, EXP)  # same configuration: resume


def test_a_run_started_on_one_cpu_target_resumes_on_another(tmp_path):
    # results do not depend on the CPU, so the machine record does not guard resumption
    run = tmp_path / "run"
    store.prepare(run, EXP)
    data = json.loads((run / "config.json").read_text())
    data["machine"]["numba_cpu_target"] = "some-other-cpu"
    (run / "config.json").write_text(json.dumps(data))
    store.prepare(run, EXP)
    assert json.loads((run / "config.json").read_text())["machine"]["numba_cpu_target"] == "some-other-cpu"


def test_prepare_accepts_a_folder_written_before_a_config_field_existed(tmp_path):
    run = tmp_path / "run"
    store.prepare(run, EXP)
    stored = json.loads((run / "config.json").read_text())
    for t in stored["trials"]:
        del t["readings"]  # as written by a version without that field
    (run / "config.json").write_text(json.dumps(stored))
    store.prepare(run, EXP)


def test_prepare_refuses_to_mix_results_of_other_code(tmp_path):
    run = tmp_path / "run"
    store.prepare(run, EXP)
    stored = json.loads((run / "config.json").read_text())
    stored["code"]["sources"] = "0123456789abcdef"
    (run / "config.json").write_text(json.dumps(stored))
    with pytest.raises(ConfigError, match="computed by other code .*use another --out"):
        store.prepare(run, EXP)


@pytest.mark.parametrize(
    ("changed", "what"),
    [
        (ExperimentConfig(name="unit", repeats=3, seed=40, trials=TRIALS), "repeats 2 there, 3 now"),
        (
            ExperimentConfig(name="unit", repeats=2, seed=40, trials=TRIALS[:1]),
            "trials sarsa, sup-skew there; sarsa now",
        ),
        (
            ExperimentConfig(
                name="unit",
                repeats=2,
                seed=40,
                trials=(
                    TRIALS[0],
                    TrialConfig(**{**to_dict(TRIALS[1]), "phases": TRIALS[1].phases, "alpha_v": 0.3}),
                ),
            ),
            "trial 'sup-skew': alpha_v 0.4 there, 0.3 now",
        ),
    ],
    ids=["repeats", "trials", "field"],
)
def test_prepare_refuses_a_different_config(tmp_path, changed, what):
    store.prepare(tmp_path, EXP)
    with pytest.raises(ConfigError) as e:
        store.prepare(tmp_path, changed)
    assert str(e.value) == (
        f"run folder '{tmp_path}' holds a different configuration ({what}); "
        "use another --out or the same options"
    )


def test_prepare_removes_temporary_files_of_an_interrupted_run(tmp_path):
    fill(tmp_path)
    stale = [tmp_path / "trials" / "sarsa" / ".seed-40.npz.abc123.tmp", tmp_path / ".results.csv.x.tmp"]
    for p in stale:
        p.write_bytes(b"half")
    store.prepare(tmp_path, EXP)
    assert not any(p.exists() for p in stale)
    assert store.finished(tmp_path, EXP) == {(t.name, s) for t in TRIALS for s in EXP.seeds()}


def test_not_a_run_folder(tmp_path):
    with pytest.raises(store.StoreError, match="is not a run folder"):
        store.read_config(tmp_path)
    with pytest.raises(store.StoreError, match="no such folder"):
        store.read_config(tmp_path / "missing")
    (tmp_path / "config.json").write_text("{")
    with pytest.raises(store.StoreError, match="unreadable config.json"):
        store.read_config(tmp_path)


def test_lock_keeps_a_second_run_out(tmp_path):
    with folder.locked(tmp_path / "run"):
        with pytest.raises(ConfigError, match="is in use by another pipefollow run"):
            with folder.locked(tmp_path / "run"):
                pass
    with folder.locked(tmp_path / "run"):  # released
        pass


def test_missing_policies_are_rewritten(tmp_path):
    results = fill(tmp_path)
    path = store.policy_path(tmp_path, "sarsa", 41)
    path.unlink()
    assert store.ensure_policies(tmp_path, EXP) == 1
    np.testing.assert_array_equal(load_policy(path).weights, results["sarsa", 41].weights)
    assert store.ensure_policies(tmp_path, EXP) == 0


def test_summary(tmp_path):
    results = fill(tmp_path)
    s = tables.summary(tmp_path, EXP, last=2)
    assert list(s) == ["sarsa", "sup-skew"]
    expected = np.mean([results["sarsa", seed].stats[-2:, 0].mean() for seed in (40, 41)])
    assert s["sarsa"]["mean_return_last2"] == pytest.approx(expected)
    assert set(s["sup-skew"]["evaluation_mean_return"]) == {"learned", "heuristic", "actor"}


@pytest.mark.slow  # a trial in a fresh interpreter (≈ 4 s)
def test_the_code_stamp_covers_every_module_a_trial_imports():
    # A trial run in a fresh interpreter: every pipefollow module it loads must be in the stamp.
    import subprocess
    import sys

    code = (
        "import sys\n"
        "from pipefollow.experiments.schema import Phase, TrialConfig\n"
        "from pipefollow.experiments.trial import run_trial\n"
        "for algorithm in ('cacla', 'sarsa'):\n"
        "    run_trial(TrialConfig(name='t', algorithm=algorithm, phases=(Phase('random:easy', 2),), "
        "skew_deg=22.5 if algorithm == 'cacla' else 0.0, supervised=algorithm == 'cacla', "
        "evaluate_on='paper-validation', evaluate_seconds=5.0, "
        "disturbance={'current_speed': 0.1, 'camera_noise': 0.02}), 3)\n"
        "print('\\n'.join(m for m in sys.modules if m.startswith('pipefollow')))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    loaded = set(out.split())
    covered = set(store.result_modules())
    assert loaded - covered == set()
    assert {"pipefollow.sim.decision", "pipefollow.learners.cacla", "pipefollow.training.compiled"} <= covered
    assert not any(m.startswith(("pipefollow.cli", "pipefollow.experiments.report")) for m in covered)


def test_the_lock_file_goes_when_the_run_ends(tmp_path):
    with folder.locked(tmp_path / "run") as run_dir:
        assert (run_dir / folder.LOCK_FILE).exists()
        with pytest.raises(ConfigError, match="in use by another pipefollow run"):
            with folder.locked(run_dir):
                pass
        assert (run_dir / folder.LOCK_FILE).exists()  # the refused second run leaves the lock alone
    assert not (run_dir / folder.LOCK_FILE).exists()
    with folder.locked(run_dir):  # and the folder can be locked again
        pass


def _csv_rows_of(exp: ExperimentConfig, results) -> str:
    """results.csv as the csv module writes the rows (the independent answer)."""
    from pipefollow.training.outputs import csv_text

    rows = []
    for t in exp.trials:
        for repeat, seed in enumerate(exp.seeds()):
            r = results[t.name, seed]
            for e in range(len(r.stats)):
                ph = int(r.phase[e])
                rows.append(
                    (exp.name, t.name, t.title, t.algorithm, float(t.skew_deg), t.supervised, repeat, seed)
                    + (ph, t.phases[ph].pipeline, e, float(r.sigma[e]), *(float(v) for v in r.stats[e]))
                )
    return csv_text(tables.RESULTS_COLUMNS, rows)


def test_results_table_equals_the_csv_modules_text_byte_for_byte(tmp_path):
    # a label and a pipeline name that need quoting, and awkward floats
    trials = (
        TrialConfig(
            name="odd",
            label='CACLA, "quoted", skew 11.25°',
            algorithm="cacla",
            skew_deg=11.25,
            phases=(Phase("paper-left", 3), Phase("paper-right", 2)),
        ),
        TRIALS[0],
    )
    exp = ExperimentConfig(name="unit, odd", repeats=2, seed=40, trials=trials)
    results = fill(tmp_path, exp)
    results["odd", 40].stats[0, :] = [1e-300, -0.0, 1 / 3, 12345678901234567.0]
    store.save_trial(tmp_path, results["odd", 40], trials[0])
    tables.write_tables(tmp_path, exp)  # from the trial files
    assert (tmp_path / "results.csv").read_text(encoding="utf-8") == _csv_rows_of(exp, results)
    tables.write_tables(tmp_path, exp, results)  # from memory
    assert (tmp_path / "results.csv").read_text(encoding="utf-8") == _csv_rows_of(exp, results)


def test_stored_results_take_known_results_and_read_the_others(tmp_path):
    results = fill(tmp_path)
    store.trial_path(tmp_path, "sarsa", 41).unlink()
    known = {("sarsa", 40): results["sarsa", 40]}
    got = store.stored_results(tmp_path, EXP, known)
    assert list(got) == [("sarsa", 40), ("sup-skew", 40), ("sup-skew", 41)]
    assert got["sarsa", 40] is known["sarsa", 40]
    assert_same_result(got["sup-skew", 41], results["sup-skew", 41])
    assert tables.summary(tmp_path, EXP, last=2) == tables.summary(tmp_path, EXP, last=2, results=got)


def test_the_report_from_memory_equals_the_report_from_the_files(tmp_path):
    from pipefollow.experiments import report
    from pipefollow.experiments.summary import read_training

    results = fill(tmp_path)
    tables.write_tables(tmp_path, EXP)
    from_files = read_training(tmp_path / "results.csv")
    from_memory = report.training_of(EXP, results)
    assert list(from_memory) == list(from_files)
    for trial, by_seed in from_files.items():
        assert list(from_memory[trial]) == list(by_seed)
        for seed, phases in by_seed.items():
            assert len(from_memory[trial][seed]) == len(phases)
            for a, b in zip(from_memory[trial][seed], phases, strict=True):
                assert a.pipeline == b.pipeline
                for name in ("returns", "in_view", "progress_m"):
                    np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    report.write_outputs(tmp_path)
    text = (tmp_path / "REPORT.md").read_text(encoding="utf-8")
    (tmp_path / "REPORT.md").unlink()
    report.write_outputs(tmp_path, results)
    assert (tmp_path / "REPORT.md").read_text(encoding="utf-8") == text


def test_finished_hands_over_the_results_it_read_and_only_those(tmp_path):
    results = fill(tmp_path)
    store.trial_path(tmp_path, "sarsa", 41).write_bytes(b"damaged")  # removed, not handed over
    loaded = {}
    done = store.finished(tmp_path, EXP, loaded)
    assert done == {("sarsa", 40), ("sup-skew", 40), ("sup-skew", 41)}
    assert set(loaded) == done
    for key, r in loaded.items():
        assert_same_result(r, results[key])
