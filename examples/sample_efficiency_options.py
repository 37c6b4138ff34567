"""Two learner options against the same learner without them, paired per pipe: CACLA+Var and TD(λ).

    python examples/sample_efficiency.py --out runs/options --variants cacla supervised-cacla \
        cacla-var supervised-cacla-var cacla-td0.5 supervised-cacla-td0.5 cacla-td0.9 \
        supervised-cacla-td0.9 cacla-td1 supervised-cacla-td1
    python examples/sample_efficiency_options.py runs/options --json docs/sample-efficiency/options.json

Reads the run files of ``examples/sample_efficiency.py`` (one per variant, budget and seed, each with
its per-pipe returns on ``heldout``, calm and disturbed) and writes, per option, budget and
condition: the paired difference per pipe (option − the same learner without it; a pipe's return is
the mean over the seeds) with its 95 % bootstrap interval over the pipes (which does not include
the spread between seeds), how many seeds' held-out means are higher with the option (seed against
the same seed), and for CACLA+Var √var, its running variance of δ, after training. Beside the JSON,
``options.provenance.json`` says how it was made; the JSON holds the run folder's own record (the
training's command, date, code and machine). The results page ``docs/results/sample-efficiency.md``
renders it (``pipefollow docs results``).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from pipefollow.evaluation.stats import paired_difference
from pipefollow.files.atomic import write_text_atomic
from pipefollow.files.machine import PROVENANCE_FILE, script_command, write_output_provenance

CONDITIONS = ("calm", "disturbed")
LEARNERS = {"cacla": "CACLA", "supervised-cacla": "supervised CACLA"}
# option → (family, λ or None); its base is the learner it names without the option
OPTIONS = {"var": None, "td0.5": 0.5, "td0.9": 0.9, "td1": 1.0}


def pairs() -> list[tuple[str, str, str, float | None]]:
    """(option variant, base variant, family, λ) for every learner and option."""
    return [
        (f"{base}-{option}", base, "var" if lam is None else "td", lam)
        for option, lam in OPTIONS.items()
        for base in LEARNERS
    ]


def compare(runs: list[dict]) -> list[dict]:
    """One row per (option, budget, condition) whose option and base both have runs."""
    by = {}
    for r in runs:
        by.setdefault((r["variant"], r["budget"]), {})[r["seed"]] = r
    rows = []
    for option, base, family, lam in pairs():
        for budget in sorted({b for v, b in by if v == option}):
            a, b = by.get((option, budget), {}), by.get((base, budget), {})
            seeds = sorted(set(a) & set(b))
            if not seeds:
                continue
            for cond in CONDITIONS:
                ra = np.array([a[s][cond]["returns"] for s in seeds])  # seeds × pipes
                rb = np.array([b[s][cond]["returns"] for s in seeds])
                d = paired_difference(ra.mean(axis=0), rb.mean(axis=0))
                higher = int(np.sum(ra.mean(axis=1) > rb.mean(axis=1)))  # seed against the same seed
                row = {
                    "option": option, "base": base, "learner": LEARNERS[base], "family": family,
                    "lambda": lam, "budget": budget, "steps": a[seeds[0]]["steps"], "condition": cond,
                    "seeds": seeds, "pipes": ra.shape[1], "mean_diff": d["mean_diff"],
                    "ci95_diff": d["ci95_diff"], "seeds_higher": higher,
                }  # fmt: skip
                if family == "var":
                    row["sqrt_td_var"] = [a[s].get("sqrt_td_var") for s in seeds]
                rows.append(row)
    return rows


def main() -> None:
    """Command line: see the module docstring."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", type=Path, help="the --out folder of examples/sample_efficiency.py")
    ap.add_argument("--json", type=Path, default=None, help="write the rows here")
    args = ap.parse_args()
    runs = [json.loads(p.read_text()) for p in sorted((args.runs / "runs").glob("*.json"))]
    rows = compare([r for r in runs if r["variant"] != "heuristic"])
    if not rows:
        raise SystemExit(f"{args.runs}: no option with its base learner among the runs")
    for r in rows:
        lo, hi = r["ci95_diff"]
        print(f"{r['option']:24s} {r['steps']:>7,} {r['condition']:9s} {r['mean_diff']:+6.1f} "
              f"[{lo:+.1f}, {hi:+.1f}]  seeds higher {r['seeds_higher']}/{len(r['seeds'])}")  # fmt: skip
    if args.json:
        own = args.runs / PROVENANCE_FILE  # the training's record, written by examples/sample_efficiency.py
        trained = json.loads(own.read_text()) if own.is_file() else None
        record = {"rows": rows, "trained_by": trained}
        write_text_atomic(args.json, json.dumps(record, indent=1) + "\n")
        write_output_provenance(args.json, script_command())


if __name__ == "__main__":
    main()
