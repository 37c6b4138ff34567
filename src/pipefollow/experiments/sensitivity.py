"""How the paper's claims depend on the readings of its open points (the ``readings`` experiment).

An experiment with ``compare_readings`` runs each of its trials under each listed reading:
:func:`expand` turns trial ``cacla`` into ``cacla@default``, ``cacla@skew_step=weights``, … . A
reading that changes only how results are judged (the convergence thresholds) trains nothing
new: it re-judges the trials of the reading that trains the same way. :func:`compute` checks every
claim under every reading with the same rules as the reproduction report
(:func:`pipefollow.experiments.findings.compute_findings`); :func:`write_outputs` writes the tidy
``readings.csv`` (``reading, claim, passed, repeats, verdict``) and ``REPORT.md`` with the
sensitivity table and one line per claim.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path

from pipefollow import readings as rd
from pipefollow.experiments.claims import CONFIRMED, NOT_CONFIRMED, NOT_TESTED
from pipefollow.experiments.config import ConfigError, ExperimentConfig, TrialConfig, from_dict
from pipefollow.experiments.findings import Findings, compute_findings
from pipefollow.experiments.summary import as_training, read_rows, read_training
from pipefollow.files.machine import describe as describe_machine

SEP = "@"  # joins a trial's name and the reading id it was trained under
READINGS_CSV = "readings.csv"
CSV_COLUMNS = ("reading", "claim", "passed", "repeats", "verdict")
HOLDS, FAILS = "holds under every reading", "fails under every reading"


def canonical(rid: str) -> str:
    """The canonical id of a reading id (``default`` for the defaults).

    Raises:
        ConfigError: the id cannot be parsed.
    """
    try:
        return rd.parse(rid).id
    except rd.ReadingError as e:
        raise ConfigError(f"compare_readings: {e}") from None


def training_id(rid: str) -> str:
    """The reading a reading trains under: ``rid`` without its report-only (threshold) readings."""
    return rd.parse(rid).training.id


def compared(exp: ExperimentConfig) -> list[str]:
    """The experiment's compared readings, canonical, in order.

    Raises:
        ConfigError: two entries name the same reading.
    """
    ids = [canonical(r) for r in exp.compare_readings]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    if dup:
        raise ConfigError(f"compare_readings: the same reading appears twice: {', '.join(dup)}")
    return ids


def expand(exp: ExperimentConfig) -> ExperimentConfig:
    """Every trial once per training reading of ``compare_readings`` (unchanged without it)."""
    if not exp.compare_readings:
        return exp
    train = list(dict.fromkeys(training_id(r) for r in compared(exp)))
    trials = tuple(
        dataclasses.replace(t, name=f"{t.name}{SEP}{tid}", readings=(*t.readings, tid))
        for tid in train
        for t in exp.trials
    )
    return dataclasses.replace(exp, trials=trials)


def under(exp: ExperimentConfig, rid: str) -> ExperimentConfig:
    """The expanded experiment's trials of one compared reading, judged under that reading."""
    tid = training_id(rid)
    trials: list[TrialConfig] = [
        dataclasses.replace(t, readings=(*t.readings, rid))
        for t in exp.trials
        if t.name.rsplit(SEP, 1)[-1] == tid
    ]
    return dataclasses.replace(exp, name=f"{exp.name} [{rid}]", compare_readings=(), trials=tuple(trials))


@dataclass(frozen=True)
class Row:
    """One claim part under one reading (a row of ``readings.csv``)."""

    reading: str
    claim: str
    statement: str
    passed: int
    repeats: int
    verdict: str


@dataclass(frozen=True)
class Sensitivity:
    """The claims under every compared reading.

    Attributes:
        config: the expanded experiment.
        readings: the compared readings (canonical ids, in order).
        findings: reading → the findings under it.
        rows: one per (reading, claim part).
    """

    config: ExperimentConfig
    readings: tuple[str, ...]
    findings: dict[str, Findings]
    rows: tuple[Row, ...]

    def claim_ids(self) -> list[str]:
        """Claim parts in report order (``1a`` …)."""
        return list(dict.fromkeys(r.claim for r in self.rows))

    def verdict_line(self, claim: str) -> str:
        """``holds under every reading``, ``fails under every reading`` or ``depends on …``."""
        rows = [r for r in self.rows if r.claim == claim and r.verdict != NOT_TESTED]
        if not rows:
            return "not tested under any reading"
        holds = [r.reading for r in rows if r.verdict == CONFIRMED]
        fails = [r.reading for r in rows if r.verdict == NOT_CONFIRMED]
        if not fails:
            return HOLDS
        if not holds:
            return FAILS
        return f"depends on the reading: holds under {_names(holds)}; fails under {_names(fails)}"


def _names(ids: list[str]) -> str:
    return ", ".join(f"`{i}`" for i in ids)


def compute(config: ExperimentConfig, results, evaluation) -> Sensitivity:
    """The sensitivity of every claim, from an expanded experiment's tables."""
    ids = tuple(compared(config))
    results = as_training(results)
    findings, rows = {}, []
    for rid in ids:
        f = compute_findings(under(config, rid), results, evaluation)
        findings[rid] = f
        for c in f.claims:
            for i, p in enumerate(c.parts):
                claim = f"{c.number}{chr(ord('a') + i)}"
                rows.append(Row(rid, claim, p.statement, p.passed, p.total, p.verdict))
    return Sensitivity(config, ids, findings, tuple(rows))


def render_markdown(s: Sensitivity, wall_seconds: float | None = None, machine: dict | None = None) -> str:
    """The sensitivity report (REPORT.md of a ``compare_readings`` experiment), ``machine`` where it ran."""
    cfg = s.config
    base = [t for t in cfg.trials if t.name.endswith(f"{SEP}{training_id(s.readings[0])}")]
    seeds = cfg.seeds()
    n_train = len({training_id(r) for r in s.readings})
    lines = [
        "# How the paper's claims depend on its open points",
        "",
        f"Fjerdingen, Kyrkjebø & Transeth (2010), experiment `{cfg.name}`: the paper's {len(base)} trials "
        f"under each of {len(s.readings)} readings, {cfg.repeats} repeats each "
        f"(seeds {seeds[0]}–{seeds[-1]}); "
        f"{n_train} readings train, the others re-judge the same runs with other convergence thresholds. "
        "Generated by `pipefollow.experiments.sensitivity` from this run folder's `results.csv` and "
        "`evaluation.csv`; the counts are also in `readings.csv`.",
        "",
        "Each reading changes one open point from the default (`default` changes none). The claims and "
        "their rules are those of the reproduction report: a claim part holds when its rule is met; "
        "*passed* counts the cases in which the statement held — converged repeats (summed over the "
        "set-ups of the part; for SARSA, repeats that did *not* converge), repeats in which the learned "
        "policy beat the heuristic (4a), and for the skew comparisons the (variant, repeat) pairs of the "
        "same seed in which skew was better early (2b) or not better at the end (3b). The verdicts of 2b "
        "and 3b follow the report's rule on means (2 standard errors), not these counts.",
        "",
    ]
    if wall_seconds is not None:
        lines += [f"The trials took {wall_seconds:.1f} s of compute in total.", ""]
    if machine:
        lines += [f"Started on {describe_machine(machine)}.", ""]
    lines += ["## Per claim", ""]
    statements = {r.claim: r.statement for r in s.rows if r.reading == s.readings[0]}
    for claim in s.claim_ids():
        lines.append(f"- **{claim}** — *{statements.get(claim, '')}*: {s.verdict_line(claim)}.")
    lines += ["", "## Counts", "", "Cells: passed/cases, ✓ the part holds, ✗ it does not, – not tested.", ""]
    claims = s.claim_ids()
    lines.append("| reading | " + " | ".join(claims) + " |")
    lines.append("|---|" + "---|" * len(claims))
    mark = {CONFIRMED: "✓", NOT_CONFIRMED: "✗", NOT_TESTED: "–"}
    for rid in s.readings:
        cells = {r.claim: f"{r.passed}/{r.repeats} {mark[r.verdict]}" for r in s.rows if r.reading == rid}
        lines.append(f"| `{rid}` | " + " | ".join(cells.get(c, "") for c in claims) + " |")
    lines += _setup_lines(s)
    lines += ["", "## The open points", "", rd.table_markdown(), ""]
    return "\n".join(lines).rstrip() + "\n"


def _setup_lines(s: Sensitivity) -> list[str]:
    """Converged repeats and last-50 mean return of every set-up (and phase) under every reading."""
    first = s.findings[s.readings[0]].config.trials
    columns = [(t.name.rsplit(SEP, 1)[0], t.title, k) for t in first for k in range(len(t.phases))]
    lines = [
        "",
        "## Per set-up",
        "",
        "Converged repeats and the mean return of the last 50 training episodes, per set-up and "
        "training phase (the validation set-up's second phase trains on `paper-right`).",
        "",
        "| reading | "
        + " | ".join(f"{title}{f' (phase {k + 1})' if k else ''}" for _, title, k in columns)
        + " |",
        "|---|" + "---|" * len(columns),
    ]
    for rid in s.readings:
        f = s.findings[rid]
        by_base = {t.name.rsplit(SEP, 1)[0]: t.name for t in f.config.trials}
        cells = []
        for base, _, k in columns:
            phases = f.summaries.get(by_base.get(base, ""), [])
            if k < len(phases):
                p = phases[k]
                cells.append(f"{p.n_converged}/{p.n}, {p.values('last_return').mean():.1f}")
            else:
                cells.append("—")
        lines.append(f"| `{rid}` | " + " | ".join(cells) + " |")
    return lines


def csv_text(s: Sensitivity) -> str:
    """``readings.csv``: one row per reading × claim part."""
    import csv
    import io

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(CSV_COLUMNS)
    for r in s.rows:
        w.writerow((r.reading, r.claim, r.passed, r.repeats, r.verdict))
    return buf.getvalue()


def read_csv(path: str | Path) -> Sensitivity:
    """The verdicts of a written ``readings.csv`` (no findings, no statements)."""
    rows = tuple(
        Row(r["reading"], r["claim"], "", int(r["passed"]), int(r["repeats"]), r["verdict"])
        for r in read_rows(path)
    )
    return Sensitivity(None, tuple(dict.fromkeys(r.reading for r in rows)), {}, rows)


def load(run_dir: str | Path) -> Sensitivity:
    """The sensitivity study of a run folder, computed from its tables."""
    run_dir = Path(run_dir)
    config = from_dict(json.loads((run_dir / "config.json").read_text()))
    return compute(config, read_training(run_dir / "results.csv"), read_rows(run_dir / "evaluation.csv"))


def write_outputs(run_dir: str | Path, wall_seconds: float | None = None) -> list[Path]:
    """Write ``readings.csv`` and ``REPORT.md`` into the run folder of a sensitivity study."""
    from pipefollow.files.atomic import write_text_atomic

    run_dir = Path(run_dir)
    s = load(run_dir)
    table = run_dir / READINGS_CSV
    write_text_atomic(table, csv_text(s))
    report = run_dir / "REPORT.md"
    machine = json.loads((run_dir / "config.json").read_text()).get("machine")
    write_text_atomic(report, render_markdown(s, wall_seconds, machine))
    return [table, report]
