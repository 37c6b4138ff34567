"""Two sections of the sample-efficiency page: CACLA+Var and the critic's TD(λ), each against TD(0)/once.

Source: ``docs/sample-efficiency/options.json`` (``examples/sample_efficiency_options.py`` over the
runs of ``examples/sample_efficiency.py``): per option, budget and condition the paired difference
per pipe to the same learner without the option with its interval, how many seeds' held-out means
are higher with it, and CACLA+Var's √var after training per seed. The file holds the training's
own provenance record (``trained_by``).
"""

from __future__ import annotations

from pathlib import Path

from pipefollow.experiments.results_pages.markdown import (
    NOT_RECORDED,
    PageError,
    ci,
    count,
    fill,
    num,
    read_json,
    table,
)
from pipefollow.sim.reward import LOST_REWARD

SOURCE = "sample-efficiency/options.json"
CONDITIONS = ("calm", "disturbed")

VAR_TEXT = """\
CACLA+Var (Van Hasselt & Wiering 2007; `actor_repeats = "var"`, var₀ = 1): on δ > 0 the actor makes
⌈δ/√var⌉ updates instead of one, var a running variance of δ. Each pipe's return is the mean over
the seeds ({seeds}); the difference is paired per pipe (CACLA+Var − CACLA) with a 95 % bootstrap
interval over the {pipes} pipes (it does not include the spread between seeds); "seeds higher":
the seeds whose held-out mean is higher with the option than the same seed without it. The
runs of both options' sections and of their baselines: {trained}.

{table}

The running variance of δ is dominated by the lost-pipe punishment ({lost} per decision,
accumulated over the semi-Markov transitions while the pipe is out of view): √var after training
lies between {var_lo} and {var_hi} over both learners, the budgets and the seeds, so only a δ
larger than that makes a second actor update (how rarely, counted once on `paper-left`:
docs/decisions.md, "CACLA+Var, a sample-efficiency option beyond the paper"). {verdict}"""

TD_TEXT = """\
`critic_lambda = λ` (beyond the paper, whose critic is TD(0), eqs. 5–6): the critic steps along an
accumulating eligibility trace, `e ← γ_d^n λ e + φ(s)`, `w_V += α_V δ e`, zero at each episode's
start (n the decisions of a semi-Markov transition). The actor, σ and step sizes are the paper's.
Paired per pipe (TD(λ) − TD(0)), as above; "seeds higher" counts the (seed, budget, condition)
cells whose held-out mean is higher with the trace.

{table}"""


def trained_by(docs: Path) -> str:
    """Where the runs the options were paired over were trained: the run folder's own record."""
    from pipefollow.files.machine import describe_provenance

    record = read_json(docs / SOURCE).get("trained_by")
    return NOT_RECORDED if not record else describe_provenance(record)


def _rows(docs: Path, family: str) -> list[dict]:
    record = read_json(docs / SOURCE)
    rows = [r for r in record.get("rows", []) if r.get("family") == family]
    if not rows:
        raise PageError(f"{docs / SOURCE}: no rows of the option family {family!r}")
    return rows


def _cell(rows: list[dict], option: str, budget: int, condition: str) -> dict:
    for r in rows:
        if (r["option"], r["budget"], r["condition"]) == (option, budget, condition):
            return r
    raise PageError(f"{SOURCE}: no row for {option} at {budget} ({condition})")


def _diff(r: dict) -> str:
    return f"{num(r['mean_diff'], 1, True)} {ci(*r['ci95_diff'], sign=True)}"


def var_section(docs: Path) -> str:
    """CACLA+Var against CACLA, per learner and budget, calm and disturbed."""
    rows = _rows(docs, "var")
    out = []
    for option, budget in dict.fromkeys((r["option"], r["budget"]) for r in rows):
        c, d = (_cell(rows, option, budget, k) for k in CONDITIONS)
        out.append(
            (
                c["learner"],
                count(c["steps"]),
                _diff(c),
                _diff(d),
                f"{c['seeds_higher']}/{len(c['seeds'])}, {d['seeds_higher']}/{len(d['seeds'])}",
                f"{min(c['sqrt_td_var']):.1f}–{max(c['sqrt_td_var']):.1f}",
            )
        )
    roots = [v for r in rows for v in r["sqrt_td_var"]]
    signs = {r["learner"]: set() for r in rows}
    for r in rows:
        signs[r["learner"]].add(r["mean_diff"] > 0)
    mixed = all(len(s) == 2 for s in signs.values())
    return fill(
        VAR_TEXT,
        seeds=", ".join(map(str, rows[0]["seeds"])),
        pipes=rows[0]["pipes"],
        trained=trained_by(docs),
        table=table(
            (
                "learner",
                "decisions",
                "calm: Var − once [95 % CI]",
                "disturbed: Var − once [95 % CI]",
                "seeds higher (calm, disturbed)",
                "√var after training (over the seeds)",
            ),
            out,
        ),
        lost=num(LOST_REWARD, 0),
        var_lo=f"{min(roots):.1f}",
        var_hi=f"{max(roots):.1f}",
        verdict=(
            "The differences change sign from budget to budget for both learners: no consistent gain."
            if mixed
            else "For at least one learner every difference has the same sign."
        ),
    )


def td_section(docs: Path) -> str:
    """The critic's TD(λ) against TD(0), per learner and λ, at every budget, calm and disturbed."""
    rows = _rows(docs, "td")
    budgets = sorted({r["budget"] for r in rows})
    steps = {r["budget"]: r["steps"] for r in rows}
    headers = ["learner", "λ"] + [f"{k} {count(steps[b])}" for b in budgets for k in CONDITIONS]
    out = []
    for option in dict.fromkeys(r["option"] for r in rows):
        own = [r for r in rows if r["option"] == option]
        cells = [_diff(_cell(rows, option, b, k)) for b in budgets for k in CONDITIONS]
        higher = sum(r["seeds_higher"] for r in own)
        total = sum(len(r["seeds"]) for r in own)
        out.append((own[0]["learner"], f"{own[0]['lambda']:g}", *cells, f"{higher}/{total}"))
    return fill(TD_TEXT, table=table((*headers, "seeds higher"), out))
