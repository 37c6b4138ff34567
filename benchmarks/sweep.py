"""A 200-trial sweep through the process and the Ray backends: per-trial overhead.

Usage: ``python benchmarks/sweep.py [--trials 200] [--episodes 500]``

Runs supervised CACLA (skew 22.5°) on paper-left with ``--trials`` seeds, once per backend, into
fresh run folders, and prints wall time, time per trial, and the overhead per trial over the
bare compute (the sum of the trials' own times divided by the workers).
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
import time

import numpy as np

from pipefollow.experiments import store
from pipefollow.experiments.config import ExperimentConfig, Phase, load_experiment
from pipefollow.experiments.runner import run_experiment


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--episodes", type=int, default=500)
    ap.add_argument("--backends", default="process,ray")
    args = ap.parse_args(argv)
    base = load_experiment("paper").trial("supervised-cacla-skew22.5")
    trial = dataclasses.replace(base, phases=(Phase("paper-left", args.episodes),))
    exp = ExperimentConfig(name="sweep", repeats=args.trials, seed=1, trials=(trial,))
    print(f"{args.trials} trials of {trial.title}, {args.episodes} episodes each")
    header = f"{'backend':<9}{'workers':>8}{'wall':>9}{'per trial':>11}{'compute/trial':>15}"
    print(header + f"{'overhead/trial':>16}")
    tables = {}
    for backend in args.backends.split(","):
        with tempfile.TemporaryDirectory() as out:
            t = time.perf_counter()
            summary = run_experiment(exp, out, backend=backend, show_progress=False)
            wall = time.perf_counter() - t
            compute = [store.load_trial(out, trial.name, s).wall_seconds for s in exp.seeds()]
            with open(summary.tables[0]) as f:
                tables[backend] = f.read()
        per = wall / args.trials
        comp = float(np.sum(compute)) / args.trials
        over = (wall - np.sum(compute) / summary.workers) / args.trials
        print(
            f"{backend:<9}{summary.workers:>8}{wall:>8.2f}s{per * 1e3:>9.1f}ms{comp * 1e3:>13.1f}ms"
            f"{over * 1e3:>14.1f}ms"
        )
    if len(tables) > 1:
        same = len(set(tables.values())) == 1
        print("identical results.csv on every backend:", same)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
