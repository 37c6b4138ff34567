"""The sample-efficiency results page: the paper's family and PPO at 10,000-100,000 decisions.

Sources: ``docs/sample-efficiency/summary.json`` (``examples/sample_efficiency.py``: per variant,
budget and condition the mean return with its interval, the paired difference to the heuristic,
the success rate and the training's wall time), ``tuning.json`` and ``continuation.json`` (the
same script on the tuning pipes, and beyond the recipe's 30,000 decisions), ``measured-state.json``,
and ``options.json`` (CACLA+Var and the critic's TD(λ) paired per pipe against the learner without
them: :mod:`~pipefollow.experiments.results_pages.sample_efficiency_options`). A source ``X.json``
computed by a recorded command has its ``X.provenance.json`` beside it.
"""

from __future__ import annotations

from pathlib import Path

from pipefollow.experiments.results_pages import sample_efficiency_options
from pipefollow.experiments.results_pages.markdown import (
    PageError,
    ci,
    count,
    fill,
    num,
    page,
    pct,
    read_json,
    stored_provenance,
    table,
)

TITLE = "Results: sample efficiency"
CONDITIONS = ("calm", "disturbed")
VS_HEADERS = tuple(f"{c}: vs heuristic [95 % CI]" for c in CONDITIONS)
SOURCES = (
    "sample-efficiency/summary.json",
    "sample-efficiency/tuning.json",
    "sample-efficiency/continuation.json",
    "sample-efficiency/measured-state.json",
    sample_efficiency_options.SOURCE,
)

TEXT = """\
Regenerate the stored outputs with `python examples/sample_efficiency.py --out FOLDER --variants ...`
(the how-to and the exact commands: [Sample efficiency](../guides/sample-efficiency.md)) and copy
each folder's `summary.json` to `docs/sample-efficiency/` (`summary.json`, `tuning.json`,
`continuation.json`), its `provenance.json` beside it (`summary.provenance.json`, …); the
options' paired comparisons with `python examples/sample_efficiency_options.py FOLDER --json
docs/sample-efficiency/options.json` over the runs of the variants they compare.

## Every variant at every budget

Trained on a new `random:mixed` pipe every episode, {seeds} seeds, judged on `heldout` calm and
disturbed; per (variant, budget) a pipe's return is the mean over the seeds, intervals are BCa
bootstraps over the pipes. Training wall times as stored (a shared machine: compare orders of
magnitude only). The heuristic scores {h_calm} calm and {h_dist} disturbed.

{table}

![Held-out return against training decisions](../sample-efficiency/learning-curves.png)

## The state the vehicle measures

Supervised CACLA with TD(0.9) observing the paper's state or it with the DVL's sway velocity over
ground (`paper+drift`) and the gyro's yaw rate (`paper+drift+yaw`), {ms_seeds} seeds, judged as
above with the sensors' noise in both conditions (the heuristic, which reads neither sensor, scores
{ms_h_calm} calm and {ms_h_dist} disturbed there); trained calm or in the disturbed condition
(`docs/sample-efficiency/measured-state.json`, `measured-state.md`). Differences to the heuristic:

{ms_table}

## How the recipe was chosen

`python examples/sample_efficiency.py --out FOLDER --judge-on tuning --variants ...` trains as
above and judges on the first {tuning_pipes} pipes of the training family (`mixed`; training draws
its pipe indices from [0, 2⁶²), so it meets none of them), with seeds {tuning_seeds}, which the
table above does not use; `docs/sample-efficiency/tuning.json`. Differences to the heuristic on
those pipes (its return {t_h_calm} calm, {t_h_dist} disturbed):

{tuning_table}

## Beyond 30,000 decisions

The recipe's 333 episodes, then 778 more (99,990 decisions in all) another way, and the recipe's
options changed throughout, each at 100,000 decisions with {c_seeds} seeds on `heldout`
(`docs/sample-efficiency/continuation.json`; `python examples/sample_efficiency.py --out FOLDER
--budgets 100000 --variants ...`), paired per pipe against the heuristic and against PPO:

{cont_table}

**These were chosen on `heldout`**, the suite that judges them: all with seeds 0–2 first, the two
best (CACLA+Var throughout, and CACLA+Var after the recipe's 30,000 decisions) then with 0–4, and
only afterwards on the tuning pipes (`tuning.json`, seeds 5–9); the rows above were completed to
seeds 0–4 after the choice. The
recipe to 100,000 decisions (`examples/recipe-100k.toml`: the recipe's 333 episodes, then 778
with CACLA+Var and σ from 1 again) is {r100_ppo} calm and {r100_dist_ppo} disturbed against PPO
at 100,000 ({r100_vs} and {r100_dist_vs} against the heuristic); on the tuning pipes
{r100_t_ppo} calm and {r100_t_dist_ppo} disturbed.

## What helped and what did not, at equal budgets

* **Supervision is the first large gain**: supervised CACLA against the heuristic in calm water
  {sup_mid_vs} at {mid} decisions and {sup_big_vs} at {big}, where CACLA alone is {cacla_big_vs};
  disturbed, supervised CACLA is {sup_mid_dist_vs} at {mid} and {sup_big_dist_vs} at {big}.
* **Exploration starting at σ = 0.3**: CACLA {s03_big} against {cacla_big} at {big} calm;
  supervised CACLA {ss03_big} against {sup_big}.
* **Training under `mild` randomization**, judged disturbed at {big}: supervised CACLA {smild_big}
  against {sup_big_dist}, CACLA {cmild_big} against {cacla_big_dist}.
* **CACLA+Var**, paired per pipe against the same learner without it: its section below.
* **An eligibility trace on the critic, TD(λ)**, paired per pipe against TD(0): its section below.
  Supervised CACLA with λ = 0.9 is {std9_mid_vs} over the heuristic in calm water at {mid}
  decisions and {std9_mid_dist_vs} disturbed; at {big} it scores {std9_big} calm against PPO's
  {ppo_big}. CACLA with λ = 0.9 is {ctd9_big_vs} over the heuristic at {big} calm.
* **The recipe** (`examples/recipe-30k.toml`: {rec_label}) was chosen on the tuning pipes (the
  first {tuning_pipes} pipes of the training family, seeds {tuning_seeds}; table below) and only
  then judged here, on `heldout` with the table's seeds. Against the heuristic at {mid} decisions it
  is {rec_mid_vs} calm and {rec_mid_dist_vs} disturbed; paired per pipe against PPO it is
  {rec_mid_ppo} calm and {rec_mid_dist_ppo} disturbed at {mid}, {rec_big_ppo} calm and
  {rec_big_dist_ppo} disturbed at {big} (the same options over 1,111 episodes); trained on from
  its {mid} decisions with CACLA+Var instead (`examples/recipe-100k.toml`, "Beyond 30,000
  decisions" above) {r100_ppo} and {r100_dist_ppo}. Without the trace (TD(0), the same step sizes and
  discount) it is {rec0_mid_vs} calm and {rec0_mid_dist_vs} disturbed at {mid}; CACLA without
  the supervisor, with the recipe's options, {crec_mid_vs} and {crec_mid_dist_vs}.
* **The paper's family against PPO**: the best of the family at {big} decisions in calm water is
  {best_name} ({best_big}), {best_gap} below PPO ({ppo_big}); within {mid} decisions the variants
  whose interval of the difference to the heuristic lies above 0 in both conditions: {both_mid}.

## CACLA+Var against CACLA

{var_section}

![CACLA and supervised CACLA with and without the options](../sample-efficiency/options.png)

## The critic's TD(λ) against TD(0)

{td_section}
"""


def _ci(lo_hi, sign=False) -> str:
    return ci(lo_hi[0], lo_hi[1], sign=sign)


def vs_of(row: dict) -> str:
    """A row's paired difference to the heuristic with its interval."""
    return f"{num(row['vs_heuristic'], 1, True)} {_ci(row['vs_heuristic_ci95'], True)}"


def vs_ppo(row: dict) -> str:
    """A row's paired difference to PPO at the same budget with its interval."""
    if "vs_ppo" not in row:
        raise PageError(f"summary.json: {row['variant']} at {row['budget']} has no paired difference to PPO")
    return f"{num(row['vs_ppo'], 1, True)} {_ci(row['vs_ppo_ci95'], True)}"


FULL_HEADERS = (
    "variant",
    "decisions",
    "seeds",
    "calm: mean return [95 % CI]",
    "vs heuristic [95 % CI]",
    "success",
    "disturbed: mean return [95 % CI]",
    "vs heuristic [95 % CI]",
    "success",
    "train wall time per seed",
)


def full_rows(rows: list[dict]) -> list[tuple]:
    """One row of :data:`FULL_HEADERS` per (variant, budget) of stored rows, in their order.

    ``rows``: what ``examples/sample_efficiency.py`` stores, one per variant, budget and condition.
    """
    cell = {(r["variant"], r["budget"], r["condition"]): r for r in rows}
    budgets = sorted({r["budget"] for r in rows})
    out = []
    for v, b in ((v, b) for v in dict.fromkeys(r["variant"] for r in rows) for b in budgets):
        if (v, b, "calm") not in cell:
            continue
        if (v, b, "disturbed") not in cell:
            raise PageError(f"no row for {v} at {b} (disturbed)")
        c, d = (cell[v, b, k] for k in CONDITIONS)
        if not c.get("label"):
            raise PageError(f"the rows of {v} have no label")
        out.append(
            (
                c["label"],
                count(c["steps"]),
                c["seeds"],
                f"{num(c['mean_return'])} {_ci(c['ci95'])}",
                vs_of(c),
                pct(c["success_rate"]),
                f"{num(d['mean_return'])} {_ci(d['ci95'])}",
                vs_of(d),
                pct(d["success_rate"]),
                f"{c['wall_s']:.1f} s",
            )
        )
    return out


def heuristic_of(row: dict) -> float:
    """The heuristic's mean return: a row's mean return minus its paired difference to it."""
    return row["mean_return"] - row["vs_heuristic"]


def seed_list(seeds) -> str:
    """``[5, 6, 7, 8, 9]`` → ``5–9`` (a run of consecutive seeds), else the list."""
    seeds = sorted(seeds)
    if seeds == list(range(seeds[0], seeds[-1] + 1)) and len(seeds) > 2:
        return f"{seeds[0]}–{seeds[-1]}"
    return ", ".join(map(str, seeds))


def render(docs: Path) -> str:
    """The page's Markdown from the stored outputs under ``docs``."""
    folder = docs / "sample-efficiency"
    rows = read_json(folder / "summary.json")
    cell = {(r["variant"], r["budget"], r["condition"]): r for r in rows}
    variants = list(dict.fromkeys(r["variant"] for r in rows))
    budgets = sorted({r["budget"] for r in rows})
    small, mid, big = budgets[0], budgets[len(budgets) // 2], budgets[-1]

    def get(v: str, b: int, c: str) -> dict:
        try:
            return cell[v, b, c]
        except KeyError:
            raise PageError(f"summary.json: no row for {v} at {b} ({c})") from None

    # the heuristic's return: mean return minus the paired difference (the same on every row)
    heur = {c: heuristic_of(get("cacla", small, c)) for c in CONDITIONS}

    labels = {r["variant"]: r.get("label") for r in rows}

    def name_of(v: str) -> str:  # the label examples/sample_efficiency.py stored with the row
        if not labels.get(v):
            raise PageError(f"summary.json: the rows of {v} have no label")
        return labels[v]

    for v in variants:
        name_of(v)  # every variant labelled
    out = full_rows(rows)

    def vs(v, b, c="calm"):
        r = get(v, b, c)
        return f"{num(r['vs_heuristic'], 1, True)} {_ci(r['vs_heuristic_ci95'], True)}"

    def ret(v, b, c="calm"):
        return num(get(v, b, c)["mean_return"])

    family = [v for v in variants if not v.startswith("ppo")]
    best = max(family, key=lambda v: get(v, big, "calm")["mean_return"])
    both = [
        name_of(v)
        for v in family
        if (v, mid, "calm") in cell
        and all(get(v, mid, c)["vs_heuristic_ci95"][0] > 0 for c in ("calm", "disturbed"))
    ]

    tuning = read_json(folder / "tuning.json")
    t_cell = {(r["variant"], r["budget"], r["condition"]): r for r in tuning}
    t_rows = [
        (
            t_cell[v, b, "calm"]["label"],
            count(t_cell[v, b, "calm"]["steps"]),
            t_cell[v, b, "calm"]["seeds"],
            *(vs_of(t_cell[v, b, c]) for c in ("calm", "disturbed")),
        )
        for v, b in dict.fromkeys((r["variant"], r["budget"]) for r in tuning)
    ]
    t_heur = {c: tuning[0 if c == "calm" else 1] for c in ("calm", "disturbed")}
    rec = "supervised-cacla-recipe"
    measured = read_json(folder / "measured-state.json")
    m_cell = {(r["variant"], r["budget"], r["condition"]): r for r in measured}
    m_rows = [
        (
            m_cell[v, b, "calm"]["label"],
            count(m_cell[v, b, "calm"]["steps"]),
            *(vs_of(m_cell[v, b, c]) for c in CONDITIONS),
        )
        for v, b in dict.fromkeys((r["variant"], r["budget"]) for r in measured)
    ]

    cont = read_json(folder / "continuation.json")
    c_cell = {(r["variant"], r["budget"], r["condition"]): r for r in cont}
    c_rows = [
        (
            c_cell[v, b, "calm"]["label"],
            *(vs_of(c_cell[v, b, c]) for c in CONDITIONS),
            *(vs_ppo(c_cell[v, b, c]) for c in CONDITIONS),
        )
        for v, b in dict.fromkeys((r["variant"], r["budget"]) for r in cont if r["variant"] != "ppo")
    ]
    rec100 = rec + "-100k"
    t_ppo = {c: t_cell.get((rec100, big, c)) for c in CONDITIONS}
    if any(r is None for r in t_ppo.values()):
        raise PageError(f"tuning.json: no row for {rec100} at {big}")

    body = fill(
        TEXT,
        seeds=get("cacla", small, "calm")["seeds"],
        h_calm=num(heur["calm"]),
        h_dist=num(heur["disturbed"]),
        table=table(FULL_HEADERS, out),
        mid=count(mid),
        big=count(big),
        sup_mid_vs=vs("supervised-cacla", mid),
        sup_big_vs=vs("supervised-cacla", big),
        cacla_big_vs=vs("cacla", big),
        sup_mid_dist_vs=vs("supervised-cacla", mid, "disturbed"),
        sup_big_dist_vs=vs("supervised-cacla", big, "disturbed"),
        s03_big=ret("cacla-sigma0.3", big),
        cacla_big=ret("cacla", big),
        ss03_big=ret("supervised-cacla-sigma0.3", big),
        sup_big=ret("supervised-cacla", big),
        smild_big=ret("supervised-cacla-mild", big, "disturbed"),
        sup_big_dist=ret("supervised-cacla", big, "disturbed"),
        cmild_big=ret("cacla-mild", big, "disturbed"),
        cacla_big_dist=ret("cacla", big, "disturbed"),
        var_section=sample_efficiency_options.var_section(docs),
        td_section=sample_efficiency_options.td_section(docs),
        std9_mid_vs=vs("supervised-cacla-td0.9", mid),
        std9_mid_dist_vs=vs("supervised-cacla-td0.9", mid, "disturbed"),
        std9_big=ret("supervised-cacla-td0.9", big),
        ppo_big=ret("ppo", big),
        ctd9_big_vs=vs("cacla-td0.9", big),
        best_name=name_of(best),
        best_big=ret(best, big),
        best_gap=num(get("ppo", big, "calm")["mean_return"] - get(best, big, "calm")["mean_return"]),
        both_mid="; ".join(both) or "none",
        rec_label=get(rec, mid, "calm")["label"],
        ms_seeds=measured[0]["seeds"],
        ms_h_calm=num(heuristic_of(measured[0])),
        ms_h_dist=num(heuristic_of(measured[1])),
        ms_table=table(("variant", "decisions", *VS_HEADERS), m_rows),
        tuning_pipes=tuning[0]["pipes"],
        tuning_seeds=seed_list(tuning[0]["seed_list"]),
        rec_mid_vs=vs(rec, mid),
        rec_mid_dist_vs=vs(rec, mid, "disturbed"),
        rec_mid_ppo=vs_ppo(get(rec, mid, "calm")),
        rec_mid_dist_ppo=vs_ppo(get(rec, mid, "disturbed")),
        rec_big_ppo=vs_ppo(get(rec, big, "calm")),
        rec_big_dist_ppo=vs_ppo(get(rec, big, "disturbed")),
        rec0_mid_vs=vs(rec + "-td0", mid),
        rec0_mid_dist_vs=vs(rec + "-td0", mid, "disturbed"),
        crec_mid_vs=vs("cacla-recipe", mid),
        crec_mid_dist_vs=vs("cacla-recipe", mid, "disturbed"),
        t_h_calm=num(heuristic_of(t_heur["calm"])),
        t_h_dist=num(heuristic_of(t_heur["disturbed"])),
        c_seeds=cont[0]["seeds"],
        cont_table=table(
            ("variant", *VS_HEADERS, *(f"{c}: vs PPO [95 % CI]" for c in CONDITIONS)),
            c_rows,
        ),
        r100_ppo=vs_ppo(get(rec100, big, "calm")),
        r100_dist_ppo=vs_ppo(get(rec100, big, "disturbed")),
        r100_vs=vs(rec100, big),
        r100_dist_vs=vs(rec100, big, "disturbed"),
        r100_t_ppo=vs_ppo(t_ppo["calm"]),
        r100_t_dist_ppo=vs_ppo(t_ppo["disturbed"]),
        tuning_table=table(
            ("variant", "decisions", "seeds", *VS_HEADERS),
            t_rows,
        ),
    )
    provenance = [(s, stored_provenance(docs / s)) for s in SOURCES]
    return page(TITLE, __name__, SOURCES, provenance, body)
