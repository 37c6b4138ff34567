"""The report: smoothing, the convergence rule, every claim's verdict, and REPORT.md's numbers.

Run folders are built here from synthetic learning curves whose outcome is known by construction
(which repeats converge, which set-up is better early), written in the store's documented layout.
The numbers REPORT.md states are recomputed independently with pandas and scipy.
"""

import csv
import dataclasses
import json
import math
import re
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from scipy import stats as sps

from pipefollow.experiments import claims, findings, report, summary
from pipefollow.experiments.config import with_overrides
from pipefollow.experiments.figures import learning_curve_figure, sliding_average
from pipefollow.experiments.schema import ExperimentConfig, Phase, TrialConfig, to_dict
from pipefollow.sim.pipeline import builtin

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
EPISODES = 160  # ≥ first-100 + last-50 windows, so they do not overlap
REPEATS = 3
OFFSETS = (-2.0, 0.0, 2.0)  # per-repeat offset of the return: the spread across repeats
RESULTS_COLUMNS = (
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
)
EVALUATION_COLUMNS = (
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
)

# trial → (return at episode 0, return at the end, in view, progress): converges iff in view ≥ 0.95 and
# progress ≥ 4 m. The skew variants: 11.25° and 22.5° start far better than plain CACLA, 45° does not.
SPEC = {
    "sarsa": (-150.0, -120.0, 0.70, 2.5),
    "cacla": (-150.0, -5.0, 0.99, 5.0),
    "supervised-cacla": (-30.0, -5.0, 0.99, 5.5),
    "cacla-skew11.25": (-100.0, -5.0, 0.99, 5.0),
    "cacla-skew22.5": (-90.0, -5.0, 0.99, 5.0),
    "cacla-skew45": (-150.0, -5.0, 0.99, 5.0),
    "supervised-cacla-skew22.5": (-30.0, -5.0, 0.99, 5.5),
    "validation": (-30.0, -5.0, 0.99, 5.5),
}
LEARNED = (-20.0, -22.0, -25.0)  # validation: learned return per repeat on paper-validation
ACTOR = (-24.0, -23.0, -30.0)
HEURISTIC_VALIDATION = -27.86
HEURISTIC_LEFT = -10.0


def _series(trial, repeat, episodes, rng):
    """(return, in view, progress) per episode of one repeat's phase: an exponential learning curve."""
    start, end, in_view, progress = SPEC[trial]
    e = np.arange(episodes)
    ret = end + (start - end) * np.exp(-e / 30.0) + OFFSETS[repeat] + rng.normal(0.0, 0.5, episodes)
    view = np.clip(in_view + rng.normal(0.0, 0.005, episodes), 0.0, 1.0)
    prog = progress + rng.normal(0.0, 0.05, episodes)
    return ret, view, prog


def _write_csv(path, columns, rows):
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(columns)
        w.writerows(rows)


def _poses(pipeline, n=61):
    pipe = builtin(pipeline)
    s = np.linspace(0.0, 0.8 * pipe.length, n)
    xy = np.array([pipe.point_at(v) for v in s])
    d = np.gradient(xy, axis=0)
    psi = np.arctan2(d[:, 1], d[:, 0])
    return np.column_stack([xy, psi])


def make_run(tmp_path, exp, spec_override=None, learned=LEARNED):
    """A run folder of ``exp`` with synthetic results; returns (run_dir, trial results by (trial, seed))."""
    rng = np.random.default_rng(7)
    run = tmp_path / "run"
    (run / "trials").mkdir(parents=True)
    (run / "config.json").write_text(json.dumps(to_dict(exp)))
    results, evaluation, trials = [], [], {}
    for t in exp.trials:
        spec = (spec_override or {}).get(t.name)
        for repeat, seed in enumerate(exp.seeds()):
            episode, stats, phases = 0, [], []
            for k, ph in enumerate(t.phases):
                ret, view, prog = (
                    spec(repeat, ph.episodes) if spec else _series(t.name, repeat, ph.episodes, rng)
                )
                for i in range(ph.episodes):
                    results.append(
                        (
                            exp.name,
                            t.name,
                            t.title,
                            t.algorithm,
                            t.skew_deg,
                            t.supervised,
                            repeat,
                            seed,
                            k,
                            ph.pipeline,
                            episode,
                            0.5,
                            ret[i],
                            view[i],
                            prog[i],
                            20 * (1 - view[i]),
                        )
                    )
                    stats.append((ret[i], view[i], prog[i], 20 * (1 - view[i])))
                    phases.append(k)
                    episode += 1
            if t.evaluate_on:
                pipe, ev = t.evaluate_on, {"learned": learned[repeat], "heuristic": HEURISTIC_VALIDATION}
                if t.supervised:
                    ev["actor"] = ACTOR[repeat]
            else:
                pipe, ev = t.phases[-1].pipeline, {"learned": -6.0 + repeat, "heuristic": HEURISTIC_LEFT}
            values = {c: (r, 1.0, 10.0, 0.0) for c, r in ev.items()}
            for c, v in values.items():
                evaluation.append((t.name, t.title, repeat, seed, pipe, c, *v))
            trials[(t.name, seed)] = SimpleNamespace(
                trial=t.name,
                seed=seed,
                stats=np.array(stats),
                phase=np.array(phases),
                sigma=np.full(len(stats), 0.5),
                weights=np.zeros(3),
                evaluation=values,
                poses={c: _poses(pipe) for c in values},
                evaluation_pipeline=pipe,
                wall_seconds=12.5,
            )
    _write_csv(run / "results.csv", RESULTS_COLUMNS, results)
    _write_csv(run / "evaluation.csv", EVALUATION_COLUMNS, evaluation)
    return run, trials


def provide_trial_files(run, trials, monkeypatch):
    """Trial files through the store if it imports; else the report's loader reads ``trials``."""
    try:
        from pipefollow.experiments import store
        from pipefollow.experiments.trial import TrialResult
    except ImportError:  # the store's dependencies are not there yet: stand in for its loader

        def load(run_dir, trial, seed):
            if (trial, seed) not in trials:
                raise FileNotFoundError(f"no trial file for {trial} seed {seed}")
            return trials[(trial, seed)]

        monkeypatch.setattr(report, "_load_trial", load)
        return
    for r in trials.values():
        store.save_trial(run, TrialResult(**vars(r)))


def paper_grid():
    """The paper's grid (as in paper.toml), with REPEATS repeats of EPISODES episodes per phase."""
    left, right = Phase("paper-left", EPISODES), Phase("paper-right", EPISODES)
    cacla, supervised = dict(algorithm="cacla"), dict(algorithm="cacla", supervised=True)
    trials = (
        TrialConfig("sarsa", "SARSA", algorithm="sarsa", phases=(left,), figures=("fig5",)),
        TrialConfig("cacla", "CACLA", **cacla, phases=(left,), figures=("fig5", "fig6")),
        TrialConfig(
            "supervised-cacla", "supervised CACLA", **supervised, phases=(left,), figures=("fig5", "fig7")
        ),
        TrialConfig(
            "cacla-skew11.25",
            "CACLA, skew 11.25°",
            **cacla,
            skew_deg=11.25,
            phases=(left,),
            figures=("fig6",),
        ),
        TrialConfig(
            "cacla-skew22.5", "CACLA, skew 22.5°", **cacla, skew_deg=22.5, phases=(left,), figures=("fig6",)
        ),
        TrialConfig(
            "cacla-skew45", "CACLA, skew 45°", **cacla, skew_deg=45.0, phases=(left,), figures=("fig6",)
        ),
        TrialConfig(
            "supervised-cacla-skew22.5",
            "supervised CACLA, skew 22.5°",
            **supervised,
            skew_deg=22.5,
            phases=(left,),
            figures=("fig7",),
        ),
        TrialConfig(
            "validation",
            "supervised CACLA, skew 22.5°, left then right",
            **supervised,
            skew_deg=22.5,
            phases=(left, right),
            evaluate_on="paper-validation",
            evaluate_seconds=60.0,
            figures=("table1",),
        ),
    )
    return ExperimentConfig("paper", repeats=REPEATS, seed=2010, trials=trials)


@pytest.fixture(scope="module")
def paper_short():
    return paper_grid()


@pytest.fixture
def run(tmp_path, paper_short, monkeypatch):
    run, trials = make_run(tmp_path, paper_short)
    provide_trial_files(run, trials, monkeypatch)
    return run


def _findings(run_dir):
    cfg = report.from_dict(json.loads((run_dir / "config.json").read_text()))
    return findings.compute_findings(
        cfg, report.read_rows(run_dir / "results.csv"), report.read_rows(run_dir / "evaluation.csv")
    )


def _parts(found, number):
    return next(c for c in found.claims if c.number == number).parts


# ---------------------------------------------------------------------------------------------
# sliding average and the figure


def test_sliding_average_by_hand():
    x = [1.0, 2.0, 3.0, 4.0, 5.0]
    # trailing window of 3; the first two points average what exists: 1, (1+2)/2
    np.testing.assert_allclose(sliding_average(x, 3), [1.0, 1.5, 2.0, 3.0, 4.0])
    np.testing.assert_allclose(sliding_average(x, 1), x)
    np.testing.assert_allclose(sliding_average(x, 10), [1.0, 1.5, 2.0, 2.5, 3.0])  # window > length
    two = np.array([x, [0.0, 0.0, 3.0, 3.0, 6.0]])
    np.testing.assert_allclose(
        sliding_average(two, 2), [[1.0, 1.5, 2.5, 3.5, 4.5], [0.0, 0.0, 1.5, 3.0, 4.5]]
    )


def test_sliding_average_default_window_is_ten_episodes():
    x = np.arange(30.0)
    y = sliding_average(x)
    assert y[9] == pytest.approx(np.mean(x[:10]))
    assert y[25] == pytest.approx(np.mean(x[16:26]))
    with pytest.raises(ValueError, match="window"):
        sliding_average(x, 0)


def test_learning_curve_figure_draws_the_smoothed_mean_and_saves_a_png(tmp_path):
    rng = np.random.default_rng(1)
    curves = {"a": rng.normal(size=(3, 40)), "b": rng.normal(size=(2, 40))}
    path = tmp_path / "fig.png"
    fig = learning_curve_figure(curves, path, "title", reference=-1.5)
    line = fig.axes[0].lines[0]
    np.testing.assert_allclose(line.get_ydata(), sliding_average(curves["a"], 10).mean(axis=0))
    assert fig.axes[0].lines[-1].get_ydata()[0] == -1.5  # the heuristic's dashed line
    assert path.read_bytes()[:8] == PNG_MAGIC
    assert not list(tmp_path.glob("*.tmp*"))


# ---------------------------------------------------------------------------------------------
# convergence rule and statistics


def test_convergence_rule_thresholds_and_window():
    n = 120
    good_view = np.full(n, summary.CONVERGE_MIN_IN_VIEW)
    good_prog = np.full(n, summary.CONVERGE_MIN_PROGRESS_M)
    assert summary.repeat_stats(0, np.zeros(n), good_view, good_prog).converged  # thresholds inclusive
    assert not summary.repeat_stats(0, np.zeros(n), good_view - 0.001, good_prog).converged
    assert not summary.repeat_stats(0, np.zeros(n), good_view, good_prog - 0.01).converged
    # only the last 50 episodes count: a bad start does not matter, a bad end does
    view = np.where(np.arange(n) < n - summary.CONVERGE_EPISODES, 0.0, 1.0)
    assert summary.repeat_stats(0, np.zeros(n), view, good_prog).converged
    assert not summary.repeat_stats(0, np.zeros(n), view[::-1], good_prog).converged


def test_repeat_stats_windows():
    ret = np.arange(200.0)
    r = summary.repeat_stats(5, ret, np.ones(200), np.full(200, 5.0))
    assert r.first_return == pytest.approx(np.mean(ret[:100]))
    assert r.last_return == pytest.approx(np.mean(ret[150:]))
    assert (r.seed, r.episodes) == (5, 200)


def test_welch_matches_scipy():
    a, b = [1.0, 2.5, 3.0, 7.0], [0.5, 0.0, 1.0]
    diff, se = summary.welch(a, b)
    assert diff == pytest.approx(np.mean(a) - np.mean(b))
    assert diff / se == pytest.approx(sps.ttest_ind(a, b, equal_var=False).statistic)
    assert math.isnan(summary.welch([1.0], b)[1])


# ---------------------------------------------------------------------------------------------
# verdicts on synthetic tables


def test_verdicts_on_the_designed_run(run):
    f = _findings(run)
    fig5 = _parts(f, 1)
    assert [p.verdict for p in fig5] == [claims.CONFIRMED] * 3  # SARSA none, both CACLAs all
    assert "SARSA: 0/3 repeats converged" in fig5[0].ours
    converge6, helps6 = _parts(f, 2)
    assert converge6.verdict == claims.CONFIRMED
    assert helps6.verdict == claims.NOT_CONFIRMED  # skew 45° starts like plain CACLA
    assert "mixed: 2 of 3 variants" in helps6.ours
    assert [p.verdict for p in _parts(f, 3)] == [claims.CONFIRMED, claims.CONFIRMED]
    beats, right = _parts(f, 4)
    assert beats.verdict == right.verdict == claims.CONFIRMED
    assert "3/3 repeats" in beats.ours
    assert [c.verdict for c in f.claims] == [
        claims.CONFIRMED,
        claims.NOT_CONFIRMED,
        claims.CONFIRMED,
        claims.CONFIRMED,
    ]


def test_every_skew_variant_clearly_better_confirms_claim_2(tmp_path, paper_short):
    exp = with_overrides(paper_short, trials=["cacla", "cacla-skew11.25", "cacla-skew22.5"])
    run, _ = make_run(tmp_path, exp)
    converge, helps = _parts(_findings(run), 2)
    assert converge.verdict == helps.verdict == claims.CONFIRMED
    assert "all 2 variants better" in helps.ours


def _not_converging_repeat(repeat, episodes):
    ret = np.full(episodes, -50.0 + repeat)
    view = np.full(episodes, 0.99 if repeat != 1 else 0.5)  # repeat 1 keeps losing the pipe
    return ret, view, np.full(episodes, 5.0)


def test_a_failed_repeat_is_not_confirmed_and_listed_as_a_difference(tmp_path, paper_short):
    exp = with_overrides(paper_short, trials=["sarsa", "cacla", "supervised-cacla"])
    run, _ = make_run(tmp_path, exp, spec_override={"cacla": _not_converging_repeat})
    f = _findings(run)
    sarsa, cacla, supervised = _parts(f, 1)
    assert cacla.verdict == claims.NOT_CONFIRMED and "2/3 repeats converged" in cacla.ours
    assert sarsa.verdict == supervised.verdict == claims.CONFIRMED
    text = report.render_markdown(f)
    differ = text.split("## Where we differ from the paper")[1]
    assert "Not confirmed — claim 1 (Fig. 5): CACLA converges in every repeat." in differ
    assert "Not tested in this run — claim 2" in differ  # no fig6 skew trials here


def test_sarsa_converging_is_not_confirmed(tmp_path, paper_short):
    exp = with_overrides(paper_short, trials=["sarsa"])
    run, _ = make_run(
        tmp_path, exp, spec_override={"sarsa": lambda r, n: (np.zeros(n), np.ones(n), np.full(n, 6.0))}
    )
    (sarsa,) = _parts(_findings(run), 1)
    assert sarsa.verdict == claims.NOT_CONFIRMED


def test_skew_advantage_in_supervised_cacla_is_not_confirmed(tmp_path, paper_short):
    exp = with_overrides(paper_short, trials=["supervised-cacla", "supervised-cacla-skew22.5"])
    better = {"supervised-cacla-skew22.5": lambda r, n: (np.full(n, 10.0 + r), np.ones(n), np.full(n, 5.0))}
    run, _ = make_run(tmp_path, exp, spec_override=better)
    converge, same = _parts(_findings(run), 3)
    assert converge.verdict == claims.CONFIRMED
    assert same.verdict == claims.NOT_CONFIRMED


def test_learned_worse_than_heuristic_is_not_confirmed(tmp_path, paper_short):
    exp = with_overrides(paper_short, trials=["validation"])
    run, _ = make_run(tmp_path, exp, learned=(-30.0, -26.0, -31.0))
    f = _findings(run)
    beats = _parts(f, 4)[0]
    assert beats.verdict == claims.NOT_CONFIRMED
    assert "1/3 repeats" in beats.ours
    assert f.table1.median_seed == f.config.seed  # returns -30, -26, -31: the median is the first repeat


def test_single_repeat_gives_no_standard_error_and_no_confirmation(tmp_path, paper_short):
    exp = with_overrides(paper_short, repeats=1, trials=["cacla", "cacla-skew22.5"])
    run, _ = make_run(tmp_path, exp)
    helps = _parts(_findings(run), 2)[1]
    assert helps.verdict == claims.NOT_CONFIRMED
    assert "standard error undefined" in helps.ours


# ---------------------------------------------------------------------------------------------
# REPORT.md against an independent computation


def _fmt(values, digits=2):
    v = pd.Series(values, dtype=float)
    return f"{v.mean():.{digits}f} ± {v.std(ddof=1):.{digits}f}"


def test_write_outputs_writes_pngs_and_report(run):
    written = report.write_outputs(run)
    names = [p.name for p in written]
    assert names == ["fig5.png", "fig6.png", "fig7.png", "validation-trajectories.png", "REPORT.md"]
    for p in written[:-1]:
        data = p.read_bytes()
        assert data[:8] == PNG_MAGIC and len(data) > 5000
    text = (run / "REPORT.md").read_text()
    for name in names[:-1]:
        assert f"]({name})" in text
    assert not [p for p in run.iterdir() if "tmp" in p.name]


@pytest.mark.slow  # a whole report computed twice (≈ 2 s)
def test_report_numbers_equal_an_independent_computation(run, paper_short):
    report.write_outputs(run)
    text = (run / "REPORT.md").read_text()
    res = pd.read_csv(run / "results.csv")
    ev = pd.read_csv(run / "evaluation.csv")
    first = res[res.phase == 0].sort_values(["trial", "seed", "episode"])
    per_seed = first.groupby(["trial", "seed"])
    last50 = per_seed.tail(50).groupby(["trial", "seed"]).mean(numeric_only=True)
    first100 = per_seed.head(100).groupby(["trial", "seed"]).mean(numeric_only=True)
    for t in paper_short.trials:
        l50, f100 = last50.loc[t.name], first100.loc[t.name]
        conv = int(((l50.pipe_in_view >= 0.95) & (l50.progress_m >= 4.0)).sum())
        evs = ev[ev.trial == t.name].set_index("controller")["return"]
        row = (
            f"| {t.title} | 1: `{t.phases[0].pipeline}` | {conv}/{REPEATS} | {_fmt(l50['return'])} "
            f"| {_fmt(f100['return'])} | {_fmt(100 * l50.pipe_in_view, 1)} | {_fmt(l50.progress_m)} |"
        )
        assert row in text, row
        if len(t.phases) == 1:
            assert f"`{t.phases[0].pipeline}` | {_fmt(evs['learned'])} | {_fmt(evs['heuristic'])} |" in text
    # claim 2: difference of first-100 means and its Welch SE, as a multiple of the SE (scipy's t)
    base = first100.loc["cacla"]["return"]
    for name in ("cacla-skew11.25", "cacla-skew22.5", "cacla-skew45"):
        var = first100.loc[name]["return"]
        t_stat = sps.ttest_ind(var, base, equal_var=False).statistic
        se = math.sqrt(var.var() / len(var) + base.var() / len(base))
        assert f"difference {var.mean() - base.mean():+.2f} ± {se:.2f} (Welch SE, {t_stat:+.1f} SE)" in text
    # claim 4 / Table 1
    val = ev[ev.trial == "validation"].pivot(index="seed", columns="controller", values="return")
    gain = (val.learned.mean() - val.heuristic.mean()) / abs(val.heuristic.mean()) * 100
    assert f"| learned (supervised CACLA, as executed) | {_fmt(val.learned)} | -23.2349 |" in text
    assert f"| its pure actor | {_fmt(val.actor)} | — |" in text
    assert f"| learned relative to heuristic | {gain:+.1f} % | +16.6 % |" in text
    assert (
        f"| repeats where learned beats heuristic | {int((val.learned > val.heuristic).sum())}/3 | — |"
        in text
    )
    median_seed = val.learned.sort_values().index[1]
    assert f"(seed {median_seed})" in text
    # the rule's thresholds come from the constants; the run time from the trial files
    assert (
        "at least 95 % of the decisions" in text
        and "at least 4 m" in text
        and "turns at 2 m and 4.5 m" in text
    )
    assert f"took {len(paper_short.trials) * REPEATS * 12.5:.1f} s of compute in total" in text
    assert "Summary: claim 1 confirmed, claim 2 not confirmed, claim 3 confirmed, claim 4 confirmed." in text
    assert re.search(r"Not confirmed — claim 2 \(Fig. 6\): skew helps early", text)


def test_missing_figure_group_is_skipped(tmp_path, paper_short, monkeypatch):
    exp = with_overrides(paper_short, trials=["sarsa", "cacla"])  # no fig7 trial, no table1 trial
    run, trials = make_run(tmp_path, exp)
    provide_trial_files(run, trials, monkeypatch)
    written = report.write_outputs(run)
    assert [p.name for p in written] == ["fig5.png", "fig6.png", "REPORT.md"]
    assert not (run / "fig7.png").exists()
    text = (run / "REPORT.md").read_text()
    assert "### Claim 3 (Fig. 7): not tested" in text and "### Claim 4 (Table 1): not tested" in text
    assert "## Table 1" not in text


def test_trials_without_results_are_skipped(tmp_path, paper_short, monkeypatch):
    run, trials = make_run(tmp_path, with_overrides(paper_short, trials=["sarsa", "cacla"]))
    # the configuration lists the whole paper grid, the tables only two trials: as after an interruption
    (run / "config.json").write_text(json.dumps(to_dict(paper_short)))
    provide_trial_files(run, trials, monkeypatch)
    written = report.write_outputs(run)
    assert [p.name for p in written] == ["fig5.png", "fig6.png", "REPORT.md"]
    text = (run / "REPORT.md").read_text()
    assert "No training results for: `supervised-cacla`" in text
    assert "took" not in text  # some trial files are missing: no run time


def test_unreadable_trial_files_skip_the_trajectories_with_a_note(tmp_path, paper_short, monkeypatch):
    exp = with_overrides(paper_short, trials=["validation"])
    run, _ = make_run(tmp_path, exp)

    def missing(run_dir, trial, seed):
        raise FileNotFoundError(f"no trial file for {trial} seed {seed}")

    monkeypatch.setattr(report, "_load_trial", missing)
    written = report.write_outputs(run)
    assert [p.name for p in written] == ["REPORT.md"]
    text = (run / "REPORT.md").read_text()
    assert "The validation trajectories were not drawn: no trial file for validation" in text
    assert "## Table 1" in text


def test_findings_are_frozen(run):
    f = _findings(run)
    with pytest.raises(dataclasses.FrozenInstanceError):
        f.table1 = None


# ---------------------------------------------------------------------------------------------
# margins, and a run of more repeats judged on the paper's five as well


def _sixth_repeat_fails(repeat, episodes):
    view = 0.99 if repeat < 5 else 0.5  # repeats 0-4 keep the pipe in view, repeat 5 does not
    return np.full(episodes, -5.0), np.full(episodes, view), np.full(episodes, 4.5 + 0.1 * repeat)


def test_margin_names_the_repeat_nearest_the_rule(tmp_path, paper_short):
    exp = dataclasses.replace(with_overrides(paper_short, trials=["cacla"]), repeats=5)
    run, _ = make_run(tmp_path, exp, spec_override={"cacla": _sixth_repeat_fails})
    (part,) = _parts(_findings(run), 1)
    # every repeat in view at 99 %; the least progress is repeat 0's 4.5 m (seed 2010): 12.5 % past 4 m,
    # while 99 % is 4.2 % past 95 %, so each repeat's margin is its in-view one and all tie: the first wins
    assert part.verdict == claims.CONFIRMED
    assert part.margin.startswith("closest to failing: CACLA seed 2010, in view 99.0 %")
    assert "progress 4.50 m (rule ≥ 4 m)" in part.margin


def test_a_run_of_more_repeats_is_judged_on_the_first_five_too(tmp_path, paper_short):
    exp = dataclasses.replace(with_overrides(paper_short, trials=["cacla"]), repeats=6)
    run, _ = make_run(tmp_path, exp, spec_override={"cacla": _sixth_repeat_fails})
    f = _findings(run)
    (few,) = next(c for c in f.first_repeats if c.number == 1).parts
    (full,) = _parts(f, 1)
    assert few.verdict == claims.CONFIRMED and (few.passed, few.total) == (5, 5)
    assert full.verdict == claims.NOT_CONFIRMED and (full.passed, full.total) == (5, 6)
    assert "seed 2015, in view 50.0 %" in full.margin
    text = report.render_markdown(f)
    row = next(line for line in text.splitlines() if line.startswith("| 1a"))
    assert "| confirmed (5/5)" in row and "| not confirmed (5/6)" in row and row.endswith("| **no** |")


def test_a_run_of_five_repeats_has_no_second_judgement(run):
    assert _findings(run).first_repeats is None
