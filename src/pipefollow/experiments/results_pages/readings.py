"""The readings' results page: under which readings of the paper's open points each claim holds.

Sources: ``docs/readings/readings.csv`` (``pipefollow reproduce --experiment readings``: per reading
and claim part the cases that held and the verdict), ``docs/readings/REPORT.md`` (its provenance)
and ``docs/skew-centred/REPORT.md`` (``pipefollow reproduce --experiment examples/skew-centred.toml``).
"""

from __future__ import annotations

import re
from pathlib import Path

from pipefollow.experiments.results_pages.markdown import (
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

TITLE = "Results: the readings"
SOURCES = ("readings/readings.csv", "readings/REPORT.md", "skew-centred/REPORT.md")

READINGS_TEXT = """\
## How the verdicts depend on the readings

The {setups} set-ups under the default and under each of {others} single-point readings, {repeats}
repeats each; per claim part the cases in which its statement held and the verdict (✓ confirmed,
✗ not confirmed; the full report with the per-set-up table is
[readings/REPORT.md](../readings/REPORT.md)):

{verdicts}

* **Claims that fail under every reading**: {fail_all}. **Claims that hold under every reading**:
  {hold_all}.
* Under the default reading: {default_held} of {parts} parts hold ({default_list}).
* Supervised CACLA converges in every repeat (1c) under every reading except {not_1c}; plain CACLA
  (1b) fails under {not_1b}.
* Skew's early advantage (2b) fails under {not_2b}; claim 3a holds under {yes_3a}, and 4b under
  {yes_4b}.
"""

CENTRED_TEXT = """\
## Beyond the paper: centred skew-normal exploration

The skewed set-ups with the exploration re-centred on the actor (`--reading skew_sample=centred`;
[report](../skew-centred/REPORT.md)), {repeats} repeats:

{centred}

Centred, skew no longer helps early (first-100 return {c_first} against {cacla_first} for plain
CACLA and {p_first} in the paper's form), and the skewed set-ups converge about as often as the
paper's form ({c_conv} against {p_conv}; with {repeats} repeats a difference of one repeat says
nothing). Centred or not, the policies trained on the short training pipes do not beat the
heuristic on the validation pipe (centred: {c_val} on average over {repeats} repeats against the
heuristic's {h_val}).
"""


def _verdict_cell(r: dict[str, str]) -> str:
    mark = "✓" if r["verdict"] == "confirmed" else "✗"
    return f"{r['passed']}/{r['repeats']} {mark}"


def _names(items: list[str]) -> str:
    return ", ".join(f"`{x}`" for x in items) if items else "none"


def render(docs: Path) -> str:
    """The page's Markdown from the stored outputs under ``docs``."""
    rows = read_csv(docs / "readings" / "readings.csv")
    readings = list(dict.fromkeys(r["reading"] for r in rows))
    parts = list(dict.fromkeys(r["claim"] for r in rows))
    cell = {(r["reading"], r["claim"]): r for r in rows}
    verdicts = table(
        ("reading", *parts),
        (
            (
                f"`{rd}`",
                *(_verdict_cell(cell[rd, p]) if (rd, p) in cell else "–" for p in parts),
            )
            for rd in readings
        ),
    )

    def holds(rd: str, p: str) -> bool:
        return cell.get((rd, p), {}).get("verdict") == "confirmed"

    report = docs / "readings" / "REPORT.md"
    m = re.search(
        r"the paper's (\d+) trials under each of (\d+) readings, (\d+) repeats each", read_text(report)
    )
    setups, n_readings, repeats = (int(x) for x in m.groups()) if m else (0, len(readings), 0)
    default_held = [p for p in parts if holds("default", p)]
    body = fill(
        READINGS_TEXT,
        setups=setups,
        others=len(readings) - 1,
        repeats=repeats,
        verdicts=verdicts,
        fail_all=", ".join(p for p in parts if not any(holds(rd, p) for rd in readings)) or "none",
        hold_all=", ".join(p for p in parts if all(holds(rd, p) for rd in readings)) or "none",
        default_held=len(default_held),
        parts=len(parts),
        default_list=", ".join(default_held),
        not_1c=_names([rd for rd in readings if not holds(rd, "1c")]),
        not_1b=_names([rd for rd in readings if not holds(rd, "1b")]),
        not_2b=_names([rd for rd in readings if not holds(rd, "2b")]),
        yes_3a=_names([rd for rd in readings if holds(rd, "3a")]),
        yes_4b=_names([rd for rd in readings if holds(rd, "4b")]),
    )

    centred_report = docs / "skew-centred" / "REPORT.md"
    trials = report_table(centred_report, "Results per trial")
    first = [r for r in trials if r["phase"].startswith("1:") and "left then right" not in r["trial"]]
    centred = table(
        ("set-up", "converged", "last-50 return", "first-100 return"),
        (
            (r["trial"], r["converged"], minus(r["return, last 50"]), minus(r["return, first 100"]))
            for r in first
        ),
    )
    n = fraction_cell(first[0]["converged"])[1]

    def first100(label: str) -> str:
        return num(mean_sd_cell(row_by(trials, "trial", label)["return, first 100"])[0], 1)

    def conv(labels) -> str:
        return " and ".join(row_by(trials, "trial", lab)["converged"] for lab in labels)

    val = next(r for r in trials if r["phase"].startswith("2:"))
    body += "\n" + fill(
        CENTRED_TEXT,
        repeats=n,
        centred=centred,
        c_first=first100("CACLA, skew 22.5° centred"),
        cacla_first=first100("CACLA"),
        p_first=first100("CACLA, skew 22.5°"),
        c_conv=conv(("CACLA, skew 22.5° centred", "CACLA, skew 45° centred")),
        p_conv=conv(("CACLA, skew 22.5°", "supervised CACLA, skew 22.5°")),
        c_val=num(mean_sd_cell(val["eval. return, learned"])[0], 1),
        h_val=num(mean_sd_cell(val["eval. return, heuristic"])[0], 1),
    )
    provenance = [
        ("readings/readings.csv", "not recorded (the run of readings/REPORT.md)"),
        ("readings/REPORT.md", report_provenance(report) + "; code stamp and date not recorded"),
        ("skew-centred/REPORT.md", report_provenance(centred_report) + "; code stamp and date not recorded"),
    ]
    lead = (
        "Regenerate the stored outputs with `pipefollow reproduce --experiment readings --out FOLDER` "
        "(`docs/readings/`) and `pipefollow reproduce --experiment examples/skew-centred.toml --out FOLDER` "
        "(`docs/skew-centred/`)."
    )
    return page(TITLE, __name__, SOURCES, provenance, lead + "\n\n" + body)
