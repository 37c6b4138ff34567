"""The deep-RL-against-the-paper results page: PPO, SAC, CACLA and supervised CACLA at equal budgets.

Sources: ``docs/deep-vs-paper/*.json`` (``examples/deep-vs-paper.py``: one file per learner, budget
and seed with its judgement on ``heldout`` calm and disturbed, and the heuristic's) and
``docs/deep-vs-paper/discount.jsonl`` (PPO and SAC at several discounts).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from pipefollow.experiments.results_pages.markdown import (
    PageError,
    ci,
    count,
    fill,
    num,
    page,
    pct,
    read_json,
    read_text,
    stored_provenance,
    table,
)
from pipefollow.files.machine import PROVENANCE_FILE

TITLE = "Results: deep RL against the paper's learners"
SOURCES = ("deep-vs-paper/*.json", "deep-vs-paper/discount.jsonl")
LEARNERS = {"ppo": "PPO", "sac": "SAC", "cacla": "CACLA", "supervised-cacla": "supervised CACLA"}
DEEP = ("ppo", "sac")

TEXT = """\
Regenerate the stored outputs with `python examples/deep-vs-paper.py --out FOLDER` (needs the extra
`deep`) and copy `FOLDER/runs/*.json` and `FOLDER/provenance.json` to `docs/deep-vs-paper/`; the how-to is
[Deep RL and RL libraries](../guides/deep-rl.md).

## Equal budgets on `heldout`

All four train on a new `random:mixed` pipe every episode, undisturbed, and every policy is
judged on `{suite}` ({pipes} pipes) calm and disturbed (a current and camera noise). Per cell:
the mean over training seeds of the mean return, the 95 % bootstrap interval of the seed whose
interval lies lowest, the seeds' range of success rates (the pipe in view at ≥ 95 % of the
decisions: these outputs were measured before success also asked that the pipe be followed
forward, and their policies are not stored to judge them again), the mean paired difference to the
heuristic, and the training's wall time per seed as stored (on a shared machine: compare orders of
magnitude only):

{table}

At the paper's own budget ({small} steps) PPO and SAC score {deep_small} in calm water (PPO in
{ppo_small_wall} s of training); the paper's learners score {paper_mid} at {mid} steps and
{paper_large} at {large}. At {large} steps CACLA ({cacla_large}) is {gap_lo} to {gap_hi} points
below the deep policies' calm returns ({deep_lo} to {deep_hi}). The disturbed condition costs the
deep policies {deep_cost_lo} to {deep_cost_hi} points and the paper's learners {paper_cost_lo} to
{paper_cost_hi}.

## The discount

PPO and SAC with the project's other defaults at several discounts γ (`discount.jsonl`; {discount_steps}
steps, calm `heldout`; mean over seeds):

{discount}

The best mean return is PPO's at γ = {best_ppo} and SAC's at γ = {best_sac}.
"""


def _runs(folder: Path) -> list[dict]:
    # the run files; a provenance record copied beside them (provenance.json) is not a run
    runs = [read_json(p) for p in sorted(folder.glob("*.json")) if not p.name.endswith(PROVENANCE_FILE)]
    if not runs:
        raise PageError(f"{folder}: no run files (*.json)")
    return runs


def _ci(summary: dict) -> list[float]:
    return summary["ci95_mean"] if "ci95_mean" in summary else summary["ci95_return"]


def render(docs: Path) -> str:
    """The page's Markdown from the stored outputs under ``docs``."""
    folder = docs / "deep-vs-paper"
    runs = _runs(folder)
    h = next(r for r in runs if r["learner"] == "heuristic")
    rows = [
        (
            "heuristic",
            "—",
            "—",
            f"{num(h['calm']['mean_return'])} {ci(*_ci(h['calm']))}",
            pct(h["calm"]["success_rate"]),
            f"{num(h['disturbed']['mean_return'])} {ci(*_ci(h['disturbed']))}",
            pct(h["disturbed"]["success_rate"]),
            "—",
            "—",
        )
    ]
    cells: dict[tuple[str, int], dict] = {}
    budgets = sorted({r["budget"] for r in runs if "budget" in r})
    for budget in budgets:
        for learner, label in LEARNERS.items():
            rs = [r for r in runs if r.get("learner") == learner and r.get("budget") == budget]
            if not rs:
                continue
            c = {}
            for cond in ("calm", "disturbed"):
                worst = min((_ci(r[cond]) for r in rs), key=lambda x: x[0])
                succ = [r[cond]["success_rate"] for r in rs]
                c[cond] = float(np.mean([r[cond]["mean_return"] for r in rs]))
                c[cond + "_cell"] = f"{num(c[cond])} {ci(*worst)}"
                c[cond + "_succ"] = (
                    pct(min(succ)) if min(succ) == max(succ) else f"{pct(min(succ))}–{pct(max(succ))}"
                )
                c[cond + "_diff"] = float(np.mean([r[cond]["vs_heuristic"]["mean_diff"] for r in rs]))
            cells[learner, budget] = c
            rows.append(
                (
                    label,
                    count(rs[0]["steps"]),
                    len(rs),
                    c["calm_cell"],
                    c["calm_succ"],
                    c["disturbed_cell"],
                    c["disturbed_succ"],
                    f"{num(c['calm_diff'], 1, True)} / {num(c['disturbed_diff'], 1, True)}",
                    f"{np.mean([r['wall_s'] for r in rs]):.1f} s",
                )
            )
    small, mid, large = budgets[0], budgets[1], budgets[-1]
    deep_large = [cells[k]["calm"] for k in cells if k[0] in DEEP]
    cacla_large = cells["cacla", large]["calm"]
    cost = {k: cells[k]["calm"] - cells[k]["disturbed"] for k in cells}
    deep_cost = [v for k, v in cost.items() if k[0] in DEEP]
    paper_cost = [v for k, v in cost.items() if k[0] not in DEEP]
    ppo_small = [r for r in runs if r.get("learner") == "ppo" and r.get("budget") == small]

    disc = [json.loads(line) for line in read_text(folder / "discount.jsonl").splitlines() if line.strip()]
    by: dict[tuple[str, float], list[dict]] = {}
    for d in disc:
        by.setdefault((d["alg"], d["gamma"]), []).append(d)
    drows = [
        (
            alg.upper(),
            f"{g:g}",
            len(ds),
            num(np.mean([d["mean_return"] for d in ds])),
            pct(float(np.mean([d["success_rate"] for d in ds]))),
            num(np.mean([d["vs"]["mean_diff"] for d in ds]), 1, True),
        )
        for (alg, g), ds in sorted(by.items())
    ]

    def best(alg: str) -> str:
        cand = {g: np.mean([d["mean_return"] for d in ds]) for (a, g), ds in by.items() if a == alg}
        return f"{max(cand, key=cand.get):g}" if cand else "—"

    body = fill(
        TEXT,
        table=table(
            (
                "learner",
                "budget (steps)",
                "seeds",
                "mean return, calm: mean of seeds [worst seed's 95 % CI]",
                "success, calm",
                "mean return, disturbed [worst CI]",
                "success, disturbed",
                "vs heuristic, calm / disturbed (mean diff.)",
                "train wall time per seed",
            ),
            rows,
        ),
        suite=h["calm"]["suite"],
        pipes=h["calm"]["n_episodes"],
        small=count(small),
        mid=count(mid),
        large=count(large),
        deep_small=" and ".join(num(cells[k, small]["calm"]) for k in DEEP if (k, small) in cells),
        ppo_small_wall=f"{np.mean([r['wall_s'] for r in ppo_small]):.1f}",
        paper_mid=" and ".join(
            num(cells[k, mid]["calm"]) for k in LEARNERS if k not in DEEP and (k, mid) in cells
        ),
        paper_large=" and ".join(
            num(cells[k, large]["calm"]) for k in LEARNERS if k not in DEEP and (k, large) in cells
        ),
        cacla_large=num(cacla_large),
        gap_lo=num(min(deep_large) - cacla_large),
        gap_hi=num(max(deep_large) - cacla_large),
        deep_lo=num(min(deep_large)),
        deep_hi=num(max(deep_large)),
        deep_cost_lo=num(min(deep_cost)),
        deep_cost_hi=num(max(deep_cost)),
        paper_cost_lo=num(min(paper_cost)),
        paper_cost_hi=num(max(paper_cost)),
        discount_steps=" / ".join(sorted({count(d["steps"]) for d in disc})),
        discount=table(("learner", "γ", "seeds", "mean return", "success", "vs heuristic"), drows),
        best_ppo=best("ppo"),
        best_sac=best("sac"),
    )
    # the runs: the folder's record (examples/deep-vs-paper.py); discount.jsonl, another command's: its own
    provenance = [
        (SOURCES[0], stored_provenance(docs / "deep-vs-paper")),
        (SOURCES[1], stored_provenance(docs / SOURCES[1], folder=False)),
    ]
    return page(TITLE, __name__, SOURCES, provenance, body)
