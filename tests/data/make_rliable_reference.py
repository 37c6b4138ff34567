"""Reference values of rliable 1.2 for tests/test_compare.py (run in an environment with rliable).

Command that made tests/data/rliable_reference.json:

    python -m venv /work/venv-rliable
    /work/venv-rliable/bin/pip install "rliable==1.2.0" "arch==7.2.0" "pandas<3"
    /work/venv-rliable/bin/python tests/data/make_rliable_reference.py > tests/data/rliable_reference.json

The score matrices are drawn here from a seeded generator and stored with the values: returns
per pipe spread widely (a pipe effect), runs differ less (a seed effect), a few returns are tied
and a few are −200 (a lost pipe), as in pipefollow's benchmarks. rliable draws its bootstrap from
NumPy's global generator; the intervals are computed under three global seeds so that the test
knows their Monte-Carlo spread.
"""

from __future__ import annotations

import json
import sys

import numpy as np
import rliable
from rliable import library as rly
from rliable import metrics

RUNS, PIPES = 5, 16
GLOBAL_SEEDS = [0, 1, 2]
REPS, POI_REPS, PROFILE_REPS = 10_000, 500, 2_000  # rliable's Python loop: 50,000 would take hours


def matrices() -> dict[str, np.ndarray]:
    rng = np.random.default_rng(20261201)
    pipe_effect = rng.normal(0.0, 20.0, PIPES)
    out = {}
    for label, shift, spread in (("A", 0.0, 6.0), ("B", 4.0, 6.0), ("C", -3.0, 12.0)):
        m = pipe_effect + shift + rng.normal(0.0, spread, (RUNS, PIPES))
        m[rng.random((RUNS, PIPES)) < 0.05] = -200.0  # lost pipes
        out[label] = np.round(m, 1)  # rounding makes some ties
    out["B"][:, 3] = out["A"][:, 3]  # one pipe where B equals A run for run
    return out


def main() -> None:
    scores = matrices()
    taus = np.linspace(-60.0, 60.0, 7)
    ref = {
        "rliable": rliable.__version__ if hasattr(rliable, "__version__") else "1.2.0",
        "numpy": np.__version__,
        "scores": {k: v.tolist() for k, v in scores.items()},
        "taus": taus.tolist(),
        "iqm": {k: float(metrics.aggregate_iqm(v)) for k, v in scores.items()},
        "mean": {k: float(metrics.aggregate_mean(v)) for k, v in scores.items()},
        "poi": {
            f"{x}>{y}": float(metrics.probability_of_improvement(scores[x], scores[y]))
            for x, y in (("A", "B"), ("B", "A"), ("C", "A"))
        },
        "profile": {k: rly.score_distributions(v, taus).tolist() for k, v in scores.items()},
        "reps": {"aggregate": REPS, "poi": POI_REPS, "profile": PROFILE_REPS},
        "intervals": [],
    }
    for s in GLOBAL_SEEDS:
        np.random.seed(s)
        iqm = lambda x: np.array([metrics.aggregate_iqm(x)])  # noqa: E731
        _, iqm_ci = rly.get_interval_estimates(scores, iqm, reps=REPS)
        np.random.seed(s)
        mean = lambda x: np.array([metrics.aggregate_mean(x)])  # noqa: E731
        _, mean_ci = rly.get_interval_estimates(scores, mean, reps=REPS)
        np.random.seed(s)
        pairs = {"C>A": (scores["C"], scores["A"])}
        _, poi_ci = rly.get_interval_estimates(pairs, metrics.probability_of_improvement, reps=POI_REPS)
        np.random.seed(s)
        _, prof_ci = rly.create_performance_profile(scores, taus, reps=PROFILE_REPS)
        ref["intervals"].append(
            {
                "global_seed": s,
                "iqm": {k: v[:, 0].tolist() for k, v in iqm_ci.items()},
                "mean": {k: v[:, 0].tolist() for k, v in mean_ci.items()},
                "poi": {k: v[:, 0].tolist() for k, v in poi_ci.items()},
                "profile": {k: v.tolist() for k, v in prof_ci.items()},
            }
        )
    json.dump(ref, sys.stdout, indent=1)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
