"""The reproduction's results page: the paper's claims, Table 1 and the figures of ``pipefollow reproduce``.

Sources: ``docs/reproduction/`` (the default run, 5 repeats: ``REPORT.md`` and ``evaluation.csv``)
and ``docs/repeats/REPORT.md`` (the same claims over 30 repeats). Table 1 and the evaluation
numbers are computed from ``evaluation.csv``; the training statistics and the claims' verdicts
and margins are the tables and claim lines of the generated reports (their run folders'
``results.csv`` is not stored in docs/).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from pipefollow.experiments.claims import PAPER_TABLE1
from pipefollow.experiments.results_pages.markdown import (
    PageError,
    fill,
    fraction_cell,
    mean_sd_cell,
    minus,
    num,
    page,
    read_csv,
    read_text,
    report_provenance,
    report_table,
    row_by,
    table,
)

TITLE = "Results: the reproduction"
SOURCES = ("reproduction/REPORT.md", "reproduction/evaluation.csv", "repeats/REPORT.md")

_PART = re.compile(
    r"^- \((?P<part>[a-z])\) \*(?P<statement>.+?)\* Ours: (?P<ours>.+?) Margin: (?P<margin>.+?) "
    r"\*\*Verdict: (?P<verdict>[^*]+?)\.\*\*$",
    flags=re.MULTILINE,
)
_CLAIM = re.compile(r"^### Claim (?P<n>\d) \((?P<figure>[^)]+)\): (?P<verdict>.+)$", flags=re.MULTILINE)


def claim_parts(report: Path) -> dict[str, dict[str, str]]:
    """The claim parts of a generated reproduction report, by id (``1a``, ...)."""
    text = read_text(report)
    heads = list(_CLAIM.finditer(text))
    out = {}
    for i, h in enumerate(heads):
        end = heads[i + 1].start() if i + 1 < len(heads) else len(text)
        for m in _PART.finditer(text, h.end(), end):
            out[f"{h['n']}{m['part']}"] = {"figure": h["figure"], **m.groupdict()}
    if not out:
        raise PageError(f"{report}: no claim parts found")
    return out


def _ses(text: str) -> list[float]:
    """The '+3.4 SE' distances of a claim line, in order."""
    return [float(x) for x in re.findall(r"Welch SE, ([+-]\d+\.\d) SE\)", text)]


def _table1(rows: list[dict[str, str]]) -> dict[str, np.ndarray]:
    """Per controller, the validation trial's returns on its evaluation pipeline (one per repeat)."""
    val = [r for r in rows if r["trial"] == "validation"]
    if not val:
        raise PageError("evaluation.csv: no rows of the trial 'validation'")
    out: dict[str, list[float]] = {}
    for r in val:
        out.setdefault(r["controller"], []).append(float(r["return"]))
    return {k: np.array(v) for k, v in out.items()}


def _eval_mean(
    rows: list[dict[str, str]], trial: str, controller: str, pipeline: str = "paper-left"
) -> float:
    v = [
        float(r["return"])
        for r in rows
        if (r["trial"], r["controller"], r["pipeline"]) == (trial, controller, pipeline)
    ]
    if not v:
        raise PageError(f"evaluation.csv: no rows of {trial}/{controller} on {pipeline}")
    return float(np.mean(v))


def _sd(x: np.ndarray) -> float:
    return float(x.std(ddof=1)) if x.size > 1 else math.nan


CLAIMS_TEXT = """\
## The paper's claims

The default run ({repeats} repeats, default readings) and the same claims over {repeats30} repeats
(seeds {seeds30}; the first {repeats} are the default run's). A verdict on {repeats} repeats can
rest on one repeat or on a fraction of a standard error, so each part gives its margin from its
rule's threshold; "firm" says whether both runs agree.

{claims_table}

Two of the default run's confirmations do not hold over {repeats30} repeats: plain CACLA converges in
{cacla30} (claim 1b) and supervised CACLA with skew in {sup_skew30} (3a). Skew's early advantage
(2b), which the default run confirms by {margin_2b} standard errors over the rule's 2, is firm: over
{repeats30} repeats the skewed set-up nearest the rule is ahead by {nearest_2b30} standard errors.
"""

TRIALS_TEXT = """\
## Per trial

Mean ± sample standard deviation over the {repeats} repeats (the report's "Results per trial"):
training statistics per phase, then one deterministic episode after training (σ = 0).

{trials_table}

![Fig. 5: SARSA versus CACLA and supervised CACLA](../reproduction/fig5.png){{ width="49%" }}
![Fig. 6: CACLA with varying skew](../reproduction/fig6.png){{ width="49%" }}
![Fig. 7: supervised CACLA with and without skew](../reproduction/fig7.png){{ width="49%" }}
![Validation: learned versus heuristic](../reproduction/validation-trajectories.png){{ width="49%" }}
"""

TABLE1_TEXT = """\
## Table 1: the unseen validation pipe

Trained on `paper-left` then `paper-right`, evaluated for {seconds} s with σ = 0 on the unseen
`{pipeline}`; mean ± sd over {n} repeats (computed from `evaluation.csv`):

{table1}

The learned policy beats the heuristic in {wins} of {n} repeats.
"""

SEEN_TEXT = """\
## What the numbers say

* **CACLA beats SARSA**, as in the paper (last-50 training return {cacla_last50} against
  {sarsa_last50}), and both CACLA variants end slightly better than the heuristic on the training
  pipe (deterministic return {cacla_eval} and {sup_eval} against {heur_eval}).
* **Skew-normal exploration speeds up the early episodes**, as the paper says (first-100-episode
  return {skew_first100} against {cacla_first100} without skew), and the skewed learners end
  with better returns than plain CACLA (last-50 return {skew_last50} against {cacla_last50}). In
  the paper's form the sample keeps A(s) as the location, so the exploration's mean moves by
  σ·δ·√(2/π), up to {max_shift}σ at the largest skew; the skewed policies settle a little slower
  along the pipe, which is why some fall short of the {progress} m convergence rule (closest:
  {closest_2a} m; over {repeats30} repeats {skew_conv30} converge).
* **The validation pipe is hard for the learned policies**: {learned} against the heuristic's
  {heuristic} ({relative} % relative to the heuristic, the paper {paper_relative} %).
"""


def render(docs: Path) -> str:
    """The page's Markdown from the stored outputs under ``docs``."""
    from pipefollow.readings import DEFAULT

    report = docs / "reproduction" / "REPORT.md"
    repeats_report = docs / "repeats" / "REPORT.md"
    rows = read_csv(docs / "reproduction" / "evaluation.csv")
    trials = report_table(report, "Results per trial")
    parts5 = claim_parts(report)
    parts30 = claim_parts(repeats_report)
    firm = {r["claim"].split()[0]: r for r in report_table(repeats_report, "How firm the verdicts are")}
    repeats = len({r["seed"] for r in rows})
    seeds30 = sorted({int(s) for s in re.findall(r"seeds (\d+)–(\d+)", read_text(repeats_report))[0]})

    def conv(label: str, phase: str = "1: `paper-left`", table_rows=trials) -> str:
        return next(r["converged"] for r in table_rows if r["trial"] == label and r["phase"] == phase)

    def ret(label: str, column: str) -> str:
        return num(mean_sd_cell(row_by(trials, "trial", label)[column])[0], 1)

    claims_rows = []
    for pid, p in parts5.items():
        p30 = parts30.get(pid)
        claims_rows.append(
            (
                f"{pid} ({p['figure']})",
                p["statement"],
                p["ours"],
                p["verdict"],
                p30["ours"] if p30 else "—",
                p30["verdict"] if p30 else "—",
                firm[pid]["firm"] if pid in firm else "—",
            )
        )
    claims_table = table(
        (
            "claim",
            "statement",
            f"ours, {repeats} repeats",
            "verdict",
            f"ours, {seeds30[-1] - seeds30[0] + 1} repeats",
            "verdict",
            "firm",
        ),
        claims_rows,
    )
    repeats30 = seeds30[-1] - seeds30[0] + 1
    trials30 = report_table(repeats_report, "Results per trial")
    skew_labels = ("CACLA, skew 11.25°", "CACLA, skew 22.5°", "CACLA, skew 45°")
    claims = fill(
        CLAIMS_TEXT,
        repeats=repeats,
        repeats30=repeats30,
        seeds30=f"{seeds30[0]}–{seeds30[-1]}",
        claims_table=minus(claims_table),
        cacla30=conv("CACLA", table_rows=trials30).replace("/", " of "),
        sup_skew30=conv("supervised CACLA, skew 22.5°", table_rows=trials30).replace("/", " of "),
        margin_2b=num(min(_ses(parts5["2b"]["ours"])) - 2.0, 1),
        nearest_2b30=num(min(_ses(parts30["2b"]["ours"])), 1),
    )

    trials_table = table(
        list(trials[0]),
        ([minus(c) for c in r.values()] for r in trials),
    )
    per_trial = fill(TRIALS_TEXT, repeats=repeats, trials_table=trials_table)

    t1 = _table1(rows)
    run = row_by(report_table(report, "What was run"), "trial", "`validation`")
    validation_label = run["label"].removesuffix(", left then right")
    val = next(r for r in rows if r["trial"] == "validation" and r["controller"] == "heuristic")
    n = t1["learned"].size
    learned, heur = t1["learned"], t1["heuristic"]
    relative = (learned.mean() - heur.mean()) / abs(heur.mean()) * 100.0
    paper_relative = (
        (PAPER_TABLE1["learned"] - PAPER_TABLE1["heuristic"]) / abs(PAPER_TABLE1["heuristic"]) * 100.0
    )
    t1_rows = [
        (
            f"learned ({validation_label}, as executed)",
            f"{num(learned.mean(), 2)} ± {num(_sd(learned), 2)}",
            num(PAPER_TABLE1["learned"], 4),
        ),
    ]
    if "actor" in t1:
        t1_rows.append(("its pure actor", f"{num(t1['actor'].mean(), 2)} ± {num(_sd(t1['actor']), 2)}", "—"))
    t1_rows += [
        ("heuristic", num(heur.mean(), 2), num(PAPER_TABLE1["heuristic"], 4)),
        (
            "learned relative to heuristic",
            f"{num(relative, 1, sign=True)} %",
            f"{num(paper_relative, 1, sign=True)} %",
        ),
    ]
    seconds = float(_seconds(report))
    table1 = fill(
        TABLE1_TEXT,
        seconds=f"{seconds:g}",
        pipeline=val["pipeline"],
        n=n,
        table1=table(("controller", "ours: accumulated reward", "paper"), t1_rows),
        wins=int((learned > heur).sum()),
    )

    gmax = DEFAULT.gamma_max
    delta = gmax / math.sqrt(1.0 + gmax**2)
    skew_conv30 = ", ".join(conv(lab, table_rows=trials30) for lab in skew_labels)
    m2a = re.search(r"progress (\d+\.\d+) m", parts5["2a"]["margin"])
    seen = fill(
        SEEN_TEXT,
        cacla_last50=ret("CACLA", "return, last 50"),
        sarsa_last50=ret("SARSA", "return, last 50"),
        cacla_eval=num(_eval_mean(rows, "cacla", "learned"), 1),
        sup_eval=num(_eval_mean(rows, "supervised-cacla", "learned"), 1),
        heur_eval=num(_eval_mean(rows, "cacla", "heuristic"), 1),
        skew_first100=", ".join(ret(lab, "return, first 100") for lab in skew_labels),
        cacla_first100=ret("CACLA", "return, first 100"),
        skew_last50=", ".join(ret(lab, "return, last 50") for lab in skew_labels),
        max_shift=f"{delta * math.sqrt(2.0 / math.pi):.2f}",
        progress=f"{DEFAULT.converge_progress_m:g}",
        closest_2a=m2a.group(1) if m2a else "—",
        repeats30=repeats30,
        skew_conv30=skew_conv30.replace("/", " of "),
        learned=f"{num(learned.mean(), 1)} ± {num(_sd(learned), 1)}",
        heuristic=num(heur.mean(), 1),
        relative=num(relative, 1, sign=True),
        paper_relative=num(paper_relative, 1, sign=True),
    )

    provenance = [
        ("reproduction/REPORT.md", report_provenance(report) + "; code stamp and date not recorded"),
        ("reproduction/evaluation.csv", "not recorded (the run of REPORT.md)"),
        ("repeats/REPORT.md", report_provenance(repeats_report) + "; code stamp and date not recorded"),
    ]
    body = "\n".join(
        (
            "Regenerate the stored outputs with `pipefollow reproduce --out FOLDER` (then copy "
            "`REPORT.md`, `evaluation.csv` and the figures to `docs/reproduction/`) and "
            "`pipefollow reproduce --experiment repeats --out FOLDER` (`docs/repeats/`); the full reports "
            "are [reproduction/REPORT.md](../reproduction/REPORT.md) and "
            "[repeats/REPORT.md](../repeats/REPORT.md).",
            "",
            claims,
            per_trial,
            table1,
            seen,
        )
    )
    return page(TITLE, __name__, SOURCES, provenance, body)


def _seconds(report: Path) -> str:
    m = re.search(r"for (\d+(?:\.\d+)?) s, σ = 0", read_text(report))
    if not m:
        raise PageError(f"{report}: the validation's episode length is not stated")
    return m.group(1)


__all__ = ["TITLE", "SOURCES", "render", "claim_parts", "fraction_cell"]
