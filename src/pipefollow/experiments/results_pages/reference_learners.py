"""The reference learners' results page: what eq. 7's sign and max terms buy.

Source: ``docs/reference-learners/REPORT.md`` (``pipefollow reproduce --experiment
reference-learners``), its table "Results per trial"; the differences between set-ups are computed
from that table's means and sample standard deviations (Welch's standard error, ±1.96 SE).
"""

from __future__ import annotations

import math
from pathlib import Path

from pipefollow.experiments.results_pages.markdown import (
    fill,
    fraction_cell,
    mean_sd_cell,
    minus,
    num,
    page,
    report_provenance,
    report_table,
    row_by,
    table,
)

TITLE = "Results: the paper's reference learners"
SOURCES = ("reference-learners/REPORT.md",)

TEXT = """\
Regenerate the stored output with `pipefollow reproduce --experiment reference-learners --out FOLDER`
and copy its `REPORT.md` to `docs/reference-learners/` (the full report:
[reference-learners/REPORT.md](../reference-learners/REPORT.md); the how-to:
[The reproduction]({guide})).

## Per set-up

{n} repeats × {episodes} episodes on `paper-left`; mean ± sample standard deviation over repeats:

{table}

## What the terms buy

Differences of the last-50 training return between set-ups, ± 1.96 Welch standard errors (from the
table's rounded means and standard deviations):

{diffs}

With eq. 7's terms both CACLAs converge in {cacla_conv} repeats, without them the actor-critics in
{ac_conv}. The max term alone converges in {max_conv}; the sign term alone in {sign_conv}. Over the
first 100 episodes the δ-weighted actor (eq. 9) is {early} against CACLA.
"""

PAIRS = (
    ("CACLA (eq. 7)", "actor-critic (eq. 9)", "eq. 7 against eq. 9"),
    ("supervised CACLA (eq. 12)", "supervised actor-critic (eq. 11)", "supervised: eq. 12 against eq. 11"),
    ("actor-critic, max(δ, 0)", "actor-critic (eq. 9)", "max term alone against eq. 9"),
    (
        "supervised actor-critic, max(δ, 0)",
        "supervised actor-critic (eq. 11)",
        "supervised: max term alone against eq. 11",
    ),
    ("CACLA (eq. 7)", "actor-critic, max(δ, 0)", "adding the sign term to the max term (CACLA)"),
    ("supervised CACLA (eq. 12)", "supervised actor-critic, max(δ, 0)", "supervised: adding the sign term"),
    ("actor-critic, sgn(δ)", "actor-critic (eq. 9)", "sign term alone against eq. 9"),
    (
        "supervised actor-critic, sgn(δ)",
        "supervised actor-critic (eq. 11)",
        "supervised: sign term alone against eq. 11",
    ),
)


def _diff(rows, a: str, b: str, column: str, n: int) -> str:
    (ma, sa), (mb, sb) = (mean_sd_cell(row_by(rows, "trial", x)[column]) for x in (a, b))
    se = math.sqrt(sa**2 / n + sb**2 / n)
    return f"{num(ma - mb, 1, True)} ± {num(1.96 * se, 1)}"


def render(docs: Path) -> str:
    """The page's Markdown from the stored outputs under ``docs``."""
    report = docs / "reference-learners" / "REPORT.md"
    rows = report_table(report, "Results per trial")
    n = fraction_cell(rows[0]["converged"])[1]
    episodes = (
        report_table(report, "What was run")[0]["training phases (pipeline × episodes)"]
        .split("×")[-1]
        .strip()
    )
    cols = (
        "trial",
        "converged",
        "return, last 50",
        "return, first 100",
        "pipe in view, last 50 (%)",
        "progress, last 50 (m)",
        "eval. return, learned",
    )
    t = table(("set-up", *cols[1:]), ((minus(r[c]) for c in cols) for r in rows))
    diffs = table(
        ("comparison", "last-50 return, difference"),
        ((label, _diff(rows, a, b, "return, last 50", n)) for a, b, label in PAIRS),
    )

    def conv(*labels) -> str:
        return " and ".join(row_by(rows, "trial", x)["converged"] for x in labels)

    body = fill(
        TEXT,
        guide="../guides/reproduction.md#the-papers-reference-learners-what-eq-7s-sign-and-max-terms-buy",
        n=n,
        episodes=episodes,
        table=t,
        diffs=diffs,
        cacla_conv=conv("CACLA (eq. 7)", "supervised CACLA (eq. 12)"),
        ac_conv=conv("actor-critic (eq. 9)", "supervised actor-critic (eq. 11)"),
        max_conv=conv("actor-critic, max(δ, 0)", "supervised actor-critic, max(δ, 0)"),
        sign_conv=conv("actor-critic, sgn(δ)", "supervised actor-critic, sgn(δ)"),
        early=_diff(rows, "actor-critic (eq. 9)", "CACLA (eq. 7)", "return, first 100", n),
    )
    provenance = [
        ("reference-learners/REPORT.md", report_provenance(report) + "; code stamp and date not recorded")
    ]
    return page(TITLE, __name__, SOURCES, provenance, body)
