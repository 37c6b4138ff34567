"""Deep RL against the paper's learners on pipes none of them has seen.

PPO and SAC (Stable-Baselines3, extra 'deep') and CACLA and supervised CACLA (the paper's) train
in the generalizing regime of examples/generalize.toml — a new `random:mixed` pipe every 90-s
episode — with the same budgets in environment steps (decisions): 10,000 (the paper's 500 × 20)
and 100,000. Every policy is then judged on the `heldout` suite (100 pipes × 60 s, one
deterministic episode each, beside the heuristic) without disturbances and with a 0.1 m/s current
(towards 45°) and 0.05 m camera noise. Training itself is undisturbed.

    python examples/deep-vs-paper.py --out runs/deep-vs-paper            # everything (≈1 h here)
    python examples/deep-vs-paper.py --out runs/deep-vs-paper --learners sac --budgets 100000 --seeds 0
    python examples/deep-vs-paper.py --out runs/deep-vs-paper --learners ppo cacla supervised-cacla \
        --budgets 450000                                                # generalize.toml's budget
    python examples/deep-vs-paper.py --out runs/deep-vs-paper --table   # the table of what is done

Each (learner, budget, seed) writes one JSON file under OUT/runs/ (resumable: done runs are
skipped) and its policy under OUT/policies/; `--table` prints the Markdown table of all of them.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from pipefollow.evaluation.benchmark import benchmark
from pipefollow.files.atomic import write_text_atomic
from pipefollow.files.machine import script_command, write_provenance
from pipefollow.learners.heuristic import Heuristic
from pipefollow.sim.decision import PAPER_SIM
from pipefollow.sim.disturbance import make_disturbance
from pipefollow.sim.suites import get_suite
from pipefollow.training.agents import make_agent
from pipefollow.training.policy_files import save_policy
from pipefollow.training.random_pipes import train_random_compiled

LEARNERS = ("ppo", "sac", "cacla", "supervised-cacla")
TRAIN_PIPES, EPISODE_S, TEST_SUITE, TEST_S = "random:mixed", 90.0, "heldout", 60.0
CONDITIONS = {
    "calm": PAPER_SIM,
    "disturbed": PAPER_SIM._replace(disturbance=make_disturbance(0.1, 45.0, camera_noise=0.05)),
}
LABELS = {"ppo": "PPO", "sac": "SAC", "cacla": "CACLA", "supervised-cacla": "supervised CACLA"}


def train(learner: str, budget: int, seed: int):
    """(policy, steps, wall_s) of one training run."""
    if learner in ("ppo", "sac"):
        from pipefollow.training.deep import train_deep

        run = train_deep(learner, TRAIN_PIPES, steps=budget, seconds=EPISODE_S, seed=seed)
        return run.policy, run.steps, run.wall_s
    episodes = budget // int(EPISODE_S)
    rng = np.random.default_rng(seed)
    agent = make_agent("cacla", supervised=learner == "supervised-cacla", rng=rng)
    t0 = time.perf_counter()
    train_random_compiled(
        agent, get_suite("mixed"), episodes, pipe_rng=rng.spawn(1)[0], episode_seconds=EPISODE_S
    )
    return agent, episodes * int(EPISODE_S), time.perf_counter() - t0


def judge(agent, label: str) -> dict:
    """Benchmark summaries on the held-out suite, per condition."""
    out = {}
    for name, params in CONDITIONS.items():
        s = benchmark(agent, get_suite(TEST_SUITE), controller=label, seconds=TEST_S, params=params).summary
        s.pop("episodes")
        out[name] = s
    return out


def run_all(out: Path, learners, budgets, seeds) -> None:
    """Train and judge every missing (learner, budget, seed); one JSON file each."""
    (out / "runs").mkdir(parents=True, exist_ok=True)
    (out / "policies").mkdir(exist_ok=True)
    # compile the paper's training loop before timing it
    train_random_compiled(make_agent("cacla"), get_suite("mixed"), 2, pipe_rng=np.random.default_rng(0))
    heuristic = out / "runs" / "heuristic.json"
    if not heuristic.exists():
        write_text_atomic(heuristic, json.dumps({"learner": "heuristic", **judge(Heuristic(), "heuristic")}))
    for budget in budgets:
        for learner in learners:
            for seed in seeds:
                path = out / "runs" / f"{learner}-{budget}-{seed}.json"
                if path.exists():
                    continue
                agent, steps, wall = train(learner, budget, seed)
                save_policy(agent, out / "policies" / f"{learner}-{budget}-{seed}.npz", seed=seed)
                result = {"learner": learner, "budget": budget, "seed": seed, "steps": steps, "wall_s": wall}
                result |= judge(agent, f"{learner}-{budget}-{seed}")
                write_text_atomic(path, json.dumps(result))
                write_provenance(out, script_command())  # OUT/provenance.json
                calm, dist = result["calm"], result["disturbed"]
                print(
                    f"{learner:17s} {budget:>7} seed {seed}: {wall:7.1f} s, "
                    f"heldout {calm['mean_return']:7.2f} (success {calm['success_rate']:.0%}), "
                    f"disturbed {dist['mean_return']:7.2f}",
                    flush=True,
                )


def ci95_mean(summary: dict) -> list[float]:
    """The interval of the mean return; the runs stored in docs/deep-vs-paper name it ``ci95_return``."""
    return summary["ci95_mean"] if "ci95_mean" in summary else summary["ci95_return"]


def table(out: Path) -> str:
    """The Markdown table of all finished runs: per cell the mean over seeds and the seeds' range."""
    runs = [json.loads(p.read_text()) for p in sorted((out / "runs").glob("*.json"))]
    h = next(r for r in runs if r["learner"] == "heuristic")
    lines = [
        "| learner | budget (steps) | seeds | mean return, calm: mean of seeds [worst seed's 95 % CI] "
        "| success, calm | mean return, disturbed [worst CI] | success, disturbed "
        "| vs heuristic, calm / disturbed (mean diff.) | train wall time per seed |",
        "|---|---|---|---|---|---|---|---|---|",
    ]

    def cell(rs, cond):
        m = [r[cond]["mean_return"] for r in rs]
        worst = min((ci95_mean(r[cond]) for r in rs), key=lambda ci: ci[0])
        lo, hi = min(r[cond]["success_rate"] for r in rs), max(r[cond]["success_rate"] for r in rs)
        succ = f"{lo:.0%}" if lo == hi else f"{lo:.0%}–{hi:.0%}"
        return f"{np.mean(m):.1f} [{worst[0]:.1f}, {worst[1]:.1f}]", succ

    hc, hd = h["calm"], h["disturbed"]
    c_lo, c_hi = ci95_mean(hc)
    d_lo, d_hi = ci95_mean(hd)
    lines.append(
        f"| heuristic | — | — | {hc['mean_return']:.1f} [{c_lo:.1f}, {c_hi:.1f}] | {hc['success_rate']:.0%} "
        f"| {hd['mean_return']:.1f} [{d_lo:.1f}, {d_hi:.1f}] | {hd['success_rate']:.0%} | — | — |"
    )
    for budget in sorted({r["budget"] for r in runs if "budget" in r}):
        for learner in LEARNERS:
            rs = [r for r in runs if r.get("learner") == learner and r.get("budget") == budget]
            if not rs:
                continue
            c_ret, c_succ = cell(rs, "calm")
            d_ret, d_succ = cell(rs, "disturbed")
            diff = [np.mean([r[c]["vs_heuristic"]["mean_diff"] for r in rs]) for c in ("calm", "disturbed")]
            walls = [r["wall_s"] for r in rs]
            steps = rs[0]["steps"]
            lines.append(
                f"| {LABELS[learner]} | {steps:,} | {len(rs)} | {c_ret} | {c_succ} | {d_ret} | {d_succ} "
                f"| {diff[0]:+.1f} / {diff[1]:+.1f} | {np.mean(walls):.1f} s |"
            )
    return "\n".join(lines)


def main() -> None:
    """Command line: see the module docstring."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--learners", nargs="+", default=list(LEARNERS), choices=LEARNERS)
    ap.add_argument("--budgets", nargs="+", type=int, default=[10_000, 100_000])
    ap.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    ap.add_argument("--table", action="store_true", help="print the table of the finished runs and stop")
    args = ap.parse_args()
    if not args.table:
        run_all(args.out, args.learners, args.budgets, args.seeds)
    print(table(args.out))


if __name__ == "__main__":
    main()
