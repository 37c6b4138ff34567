"""Summary statistics with confidence intervals, for benchmarks over many pipes.

Confidence intervals are scipy's bootstrap of the mean, BCa (bias-corrected and accelerated),
9,999 resamples, seeded: returns per pipe are skewed by the −10 of every decision the pipe is lost,
and BCa corrects for skew where the percentile interval does not. When every value is the same
the bootstrap has nothing to resample and the interval is that value on both ends.
"""

from __future__ import annotations

import numpy as np

N_RESAMPLES = 9_999
CONFIDENCE = 0.95
METHOD = "BCa"


def bootstrap_ci(values, seed: int = 0, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """Bootstrap confidence interval (BCa) of the mean of ``values``; ``(v, v)`` if all equal ``v``."""
    from scipy.stats import bootstrap

    x = np.asarray(values, dtype=np.float64)
    if x.size == 0:
        raise ValueError("no values")
    if np.all(x == x[0]):
        return float(x[0]), float(x[0])
    res = bootstrap(
        (x,),
        np.mean,
        confidence_level=confidence,
        n_resamples=N_RESAMPLES,
        method=METHOD,
        rng=np.random.default_rng(seed),
    )
    return float(res.confidence_interval.low), float(res.confidence_interval.high)


def iqm(values) -> float:
    """Interquartile mean over all values (rliable's ``aggregate_iqm``, scipy's ``trim_mean(x, 0.25)``).

    The mean of the sorted values from position ``int(0.25 n)`` to ``n − int(0.25 n)``, written out
    here: importing SciPy's statistics takes longer than a whole comparison's bootstrap.
    """
    x = np.sort(np.asarray(values, dtype=np.float64), axis=None)
    cut = int(0.25 * x.size)
    return float(np.mean(x[cut : x.size - cut]))


def paired_difference(a, b, seed: int = 0) -> dict:
    """``a − b`` per item: mean, bootstrap CI of the mean, and the share of items where ``a > b``."""
    d = np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64)
    lo, hi = bootstrap_ci(d, seed)
    return {"mean_diff": float(d.mean()), "ci95_diff": [lo, hi], "win_rate": float(np.mean(d > 0.0))}
