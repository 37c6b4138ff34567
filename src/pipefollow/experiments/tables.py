"""A run's tables, regenerated from its stored trials: ``results.csv``, ``evaluation.csv`` and the summary.

The two tables of the run folder (its layout: :mod:`pipefollow.experiments.store`) are written
atomically from the trial files, in the experiment's order, by :func:`write_tables`, so they can
always be made again; :func:`summary` gives per trial the means over its stored seeds.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping
from pathlib import Path

import numpy as np

from pipefollow.experiments.schema import ExperimentConfig, TrialConfig
from pipefollow.experiments.store import stored_results
from pipefollow.experiments.trial import TrialResult
from pipefollow.files.atomic import write_text_atomic
from pipefollow.sim.episode import TRAINING_STAT_NAMES
from pipefollow.training.outputs import csv_text

RESULTS_FILE = "results.csv"
EVALUATION_FILE = "evaluation.csv"

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
    *TRAINING_STAT_NAMES,
)
EVALUATION_COLUMNS = ("trial", "label", "repeat", "seed", "pipeline", "controller", *TRAINING_STAT_NAMES)


def _results_lines(exp: ExperimentConfig, t: TrialConfig, repeat: int, r: TrialResult) -> Iterator[str]:
    """One trial's rows of ``results.csv``, as :func:`csv_text` would write them, ~5x faster.

    The text columns (quoted where the CSV dialect needs it) are formatted once per trial and
    phase, the numbers of each row by ``repr`` of Python floats, as :func:`csv_text` does; a test
    holds the two equal byte for byte.
    """
    head = csv_text(
        (), [(exp.name, t.name, t.title, t.algorithm, float(t.skew_deg), t.supervised, repeat, r.seed)]
    )
    head = head[1:-1]  # csv_text's empty header line and the row's line end
    phases = {ph: csv_text((), [(ph, p.pipeline)])[1:-1] for ph, p in enumerate(t.phases)}
    sigma, stats = r.sigma.tolist(), r.stats.tolist()
    for e, ph in enumerate(r.phase.tolist()):
        numbers = ",".join(map(repr, (sigma[e], *stats[e])))
        yield f"{head},{phases[ph]},{e},{numbers}\n"


def write_tables(
    run_dir: str | os.PathLike,
    exp: ExperimentConfig,
    results: Mapping[tuple[str, int], TrialResult] | None = None,
) -> list[Path]:
    """Regenerate ``results.csv`` and ``evaluation.csv`` from the stored trials of ``exp``.

    Rows follow the order of the trials in ``exp``, then the seeds; trials not (yet) stored are
    left out. ``results`` (:func:`stored_results`) saves reading the trial files again. Returns
    the two paths.
    """
    run_dir = Path(run_dir)
    if results is None:
        results = stored_results(run_dir, exp)
    lines, evaluation = [csv_text(RESULTS_COLUMNS, ())], []
    for t in exp.trials:
        for repeat, seed in enumerate(exp.seeds()):
            r = results.get((t.name, seed))
            if r is None:
                continue
            lines.extend(_results_lines(exp, t, repeat, r))
            for controller, values in r.evaluation.items():
                evaluation.append(
                    (
                        t.name,
                        t.title,
                        repeat,
                        seed,
                        r.evaluation_pipeline,
                        controller,
                        *(float(v) for v in values),
                    )
                )
    paths = [run_dir / RESULTS_FILE, run_dir / EVALUATION_FILE]
    write_text_atomic(paths[0], "".join(lines))
    write_text_atomic(paths[1], csv_text(EVALUATION_COLUMNS, evaluation))
    return paths


def summary(
    run_dir: str | os.PathLike,
    exp: ExperimentConfig,
    last: int = 50,
    results: Mapping[tuple[str, int], TrialResult] | None = None,
) -> dict[str, dict]:
    """Per trial of ``exp``, means over its stored seeds.

    Of the last ``last`` training episodes: return and pipe in view; of the evaluation episodes:
    each controller's return. ``results`` (:func:`stored_results`) saves reading the trial files.
    """
    if results is None:
        results = stored_results(run_dir, exp)
    out = {}
    for t in exp.trials:
        results_of = [results[t.name, s] for s in exp.seeds() if (t.name, s) in results]
        if not results_of:
            continue
        final = [r.stats[-last:].mean(axis=0) for r in results_of]
        row = {
            "label": t.title,
            "seeds": [r.seed for r in results_of],
            f"mean_return_last{last}": float(np.mean([f[0] for f in final])),
            # sample standard deviation, as in the report
            f"std_return_last{last}": float(np.std([f[0] for f in final], ddof=1)) if len(final) > 1 else 0.0,
            f"mean_pipe_in_view_last{last}": float(np.mean([f[1] for f in final])),
            "evaluation_pipeline": results_of[0].evaluation_pipeline,
            "evaluation_mean_return": {
                c: float(np.mean([r.evaluation[c][0] for r in results_of])) for c in results_of[0].evaluation
            },
        }
        out[t.name] = row
    return out
