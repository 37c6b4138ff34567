"""Judge the policies of a `generalize` run on the held-out suite, with and without disturbances.

    pipefollow reproduce --experiment examples/generalize.toml --out generalize
    python examples/generalize_table.py generalize --csv docs/generalize/heldout.csv

Every policy of the run folder, the heuristic and the line-of-sight controller run one
deterministic 60-s episode per held-out pipe (`pipefollow.evaluation.benchmark`) in three scenarios: calm
water, a 0.1 m/s current flowing east (across the pipes' first leg, which runs north), and that
current with camera noise of 0.05 m (s.d. on each detected end point). The noise of pipe i is the
same for every controller (common random numbers). Prints a markdown table (per learner: the range
over training seeds, and the worst seed's confidence intervals) and writes one CSV row per
controller × seed × scenario.
"""

from __future__ import annotations

import argparse
import csv
import json
import re
from pathlib import Path

from pipefollow.evaluation.benchmark import benchmark, load_controller
from pipefollow.files.machine import script_command, write_provenance
from pipefollow.sim.decision import PAPER_SIM
from pipefollow.sim.disturbance import make_disturbance
from pipefollow.sim.suites import get_suite

SCENARIOS = {
    "calm": make_disturbance(0.0, 0.0),
    "current 0.1 m/s": make_disturbance(0.1, 90.0),
    "current 0.1 m/s + camera noise 0.05 m": make_disturbance(0.1, 90.0, camera_noise=0.05),
}
COLUMNS = (
    "scenario", "controller", "seed", "mean_return", "ci95_low", "ci95_high", "success_rate",
    "mean_diff", "ci95_diff_low", "ci95_diff_high", "win_rate",
)  # fmt: skip


def rows(run_dir: Path, suite_name: str, seconds: float, seed: int):
    """One row per scenario × controller (× training seed)."""
    suite = get_suite(suite_name)
    labels = {
        t["name"]: t["label"] or t["name"]
        for t in json.loads((run_dir / "config.json").read_text())["trials"]
    }
    policies = sorted((run_dir / "policies").glob("*.npz"))
    controllers = [("heuristic", "", "heuristic"), ("LOS (Δ = 1.5 m)", "", "los")]
    for p in policies:
        trial, s = re.fullmatch(r"(.+)-seed(\d+)", p.stem).groups()
        controllers.append((labels.get(trial, trial), s, str(p)))
    for scenario, d in SCENARIOS.items():
        params = PAPER_SIM._replace(disturbance=d)
        for name, s, spec in controllers:
            agent = load_controller(spec)
            run = benchmark(
                agent, suite, controller=name, seconds=seconds, params=params, seed=seed, noise_seed=seed
            )
            r = run.summary
            v = r.get("vs_heuristic", {"mean_diff": 0.0, "ci95_diff": [0.0, 0.0], "win_rate": 0.0})
            yield {
                "scenario": scenario,
                "controller": name,
                "seed": s,
                "mean_return": r["mean_return"],
                "ci95_low": r["ci95_mean"][0],
                "ci95_high": r["ci95_mean"][1],
                "success_rate": r["success_rate"],
                "mean_diff": v["mean_diff"],
                "ci95_diff_low": v["ci95_diff"][0],
                "ci95_diff_high": v["ci95_diff"][1],
                "win_rate": v["win_rate"],
            }


def _span(values, fmt: str) -> str:
    lo, hi = min(values), max(values)
    return format(lo, fmt) if lo == hi else f"{format(lo, fmt)} to {format(hi, fmt)}"


def markdown(table: list[dict]) -> str:
    """Per scenario and controller: ranges over training seeds, the worst seed's intervals."""
    out = [
        "| scenario | controller | mean return, per seed | 95 % CI, worst seed | success rate, per seed "
        "| vs heuristic: mean difference, per seed | its 95 % CI, worst seed |",
        "|---|---|---|---|---|---|---|",
    ]
    for scenario in SCENARIOS:
        names = list(dict.fromkeys(r["controller"] for r in table if r["scenario"] == scenario))
        for name in names:
            rs = [r for r in table if r["scenario"] == scenario and r["controller"] == name]
            worst = min(rs, key=lambda r: r["mean_return"])
            worst_diff = min(rs, key=lambda r: r["ci95_diff_low"])
            diff = "—" if name == "heuristic" else f"{_span([r['mean_diff'] for r in rs], '+.1f')}"
            diff_ci = (
                "—"
                if name == "heuristic"
                else f"[{worst_diff['ci95_diff_low']:+.1f}, {worst_diff['ci95_diff_high']:+.1f}]"
            )
            out.append(
                f"| {scenario} | {name} | {_span([r['mean_return'] for r in rs], '.1f')} "
                f"| [{worst['ci95_low']:.1f}, {worst['ci95_high']:.1f}] "
                f"| {_span([r['success_rate'] * 100 for r in rs], '.0f')} % | {diff} | {diff_ci} |"
            )
    return "\n".join(out)


def main() -> None:
    """Benchmark, write the CSV, print the table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run_dir", type=Path)
    ap.add_argument("--suite", default="heldout")
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--seed", type=int, default=0, help="seed of the bootstrap and of the camera noise")
    ap.add_argument("--csv", type=Path, help="write the rows here")
    args = ap.parse_args()
    table = list(rows(args.run_dir, args.suite, args.seconds, args.seed))
    if args.csv:
        args.csv.parent.mkdir(parents=True, exist_ok=True)
        with args.csv.open("w", newline="") as f:
            w = csv.DictWriter(f, COLUMNS, lineterminator="\n")
            w.writeheader()
            for r in table:
                w.writerow({k: (f"{v:.4f}" if isinstance(v, float) else v) for k, v in r.items()})
        # beside the CSV: the command, the date, the code and the machine (the results page cites it)
        write_provenance(args.csv.parent, script_command())
    print(markdown(table))


if __name__ == "__main__":
    main()
