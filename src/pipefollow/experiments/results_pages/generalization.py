"""The generalization results page: the paper's learners trained on random pipes, judged on ``heldout``.

Source: ``docs/generalize/heldout.csv`` (``examples/generalize_table.py``: per scenario, controller
and training seed the mean return with its 95 % interval, the success rate and the paired
difference to the heuristic).
"""

from __future__ import annotations

from pathlib import Path

from pipefollow.experiments.results_pages.markdown import (
    ci,
    fill,
    num,
    page,
    pct,
    read_csv,
    stored_provenance,
    table,
)

TITLE = "Results: training that generalizes"
SOURCES = ("generalize/heldout.csv",)

TEXT = """\
Regenerate the stored output with `pipefollow reproduce --experiment examples/generalize.toml --out FOLDER`,
then `python examples/generalize_table.py` on it (the how-to:
[Training and comparing](../guides/training-and-comparing.md#training-that-generalizes)).

## On `heldout`, calm and disturbed

{policies} policies ({learners} learners × {seeds} training seeds) and two fixed controllers on
`heldout` in {scenarios} scenarios. Per cell the range over the training seeds, and for the
return's interval the seed with the lowest mean return, for the difference's the seed whose
interval lies lowest:

{table}

In every scenario {beat} of the {policies} policies beat the heuristic with a confidence interval
of the paired difference above 0, and {succ} have a success rate above the heuristic's; the
line-of-sight controller is worse than the heuristic in {los_worse} of the {scenarios} scenarios.
The lowest interval of a paired difference of any learned policy starts at {lowest_diff}.
"""


def _range(values: list[float], digits: int = 1, sign: bool = False) -> str:
    lo, hi = min(values), max(values)
    return num(lo, digits, sign) if lo == hi else f"{num(lo, digits, sign)} to {num(hi, digits, sign)}"


def _pct_range(values: list[float]) -> str:
    lo, hi = min(values), max(values)
    return pct(lo) if lo == hi else f"{100 * lo:.0f} to {pct(hi)}"


def render(docs: Path) -> str:
    """The page's Markdown from the stored outputs under ``docs``."""
    rows = read_csv(docs / "generalize" / "heldout.csv")
    groups: dict[tuple[str, str], list[dict[str, str]]] = {}
    for r in rows:
        groups.setdefault((r["scenario"], r["controller"]), []).append(r)
    scenarios = list(dict.fromkeys(r["scenario"] for r in rows))
    out = []
    for (scenario, controller), rs in groups.items():
        f = {
            k: [float(r[k]) for r in rs]
            for k in (
                "mean_return",
                "ci95_low",
                "ci95_high",
                "success_rate",
                "mean_diff",
                "ci95_diff_low",
                "ci95_diff_high",
            )
        }
        worst = min(range(len(rs)), key=lambda i: f["mean_return"][i])
        heuristic = controller == "heuristic"
        worst_d = min(range(len(rs)), key=lambda i: f["ci95_diff_low"][i])
        out.append(
            (
                scenario,
                controller,
                _range(f["mean_return"]),
                ci(f["ci95_low"][worst], f["ci95_high"][worst]),
                _pct_range(f["success_rate"]),
                "—" if heuristic else _range(f["mean_diff"], sign=True),
                "—"
                if heuristic
                else ci(f["ci95_diff_low"][worst_d], f["ci95_diff_high"][worst_d], sign=True),
            )
        )
    learned = [r for r in rows if r["seed"]]
    heur = {r["scenario"]: r for r in rows if r["controller"] == "heuristic"}
    per_scenario = {s: [r for r in learned if r["scenario"] == s] for s in scenarios}
    beat = min(sum(float(r["ci95_diff_low"]) > 0 for r in rs) for rs in per_scenario.values())
    succ = min(
        sum(float(r["success_rate"]) > float(heur[s]["success_rate"]) for r in rs)
        for s, rs in per_scenario.items()
    )
    los = [r for r in rows if r["controller"].startswith("LOS")]
    body = fill(
        TEXT,
        policies=len(per_scenario[scenarios[0]]),
        learners=len({r["controller"] for r in learned}),
        seeds=len({r["seed"] for r in learned}),
        scenarios=len(scenarios),
        table=table(
            (
                "scenario",
                "controller",
                "mean return, per seed",
                "95 % CI, worst seed",
                "success rate, per seed",
                "vs heuristic: mean difference, per seed",
                "its 95 % CI, worst seed",
            ),
            out,
        ),
        beat=beat,
        succ=succ,
        los_worse=sum(float(r["mean_diff"]) < 0 for r in los),
        lowest_diff=num(min(float(r["ci95_diff_low"]) for r in learned), 1, sign=True),
    )
    provenance = [("generalize/heldout.csv", stored_provenance(docs / "generalize"))]
    return page(TITLE, __name__, SOURCES, provenance, body)
