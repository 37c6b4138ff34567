"""Comparisons of learners over training seeds × pipes, as RL papers report them (rliable's definitions).

A learner's scores are a matrix of returns, one row per run (a policy trained with its own seed)
and one column per task (a pipe). Following Agarwal et al., "Deep RL at the edge of the
statistical precipice" (NeurIPS 2021) and their library rliable (``rliable/library.py``,
``rliable/metrics.py``):

* **IQM**: the mean of the middle 50 % of all runs × pipes (``scipy.stats.trim_mean(x, 0.25)``
  over the flattened matrix); **mean**: the mean over pipes of the mean over runs.
* **Stratified bootstrap**: a replicate draws, for every pipe separately, as many runs as there
  are, with replacement (the pipes are kept; the uncertainty is that of the training seeds). The
  95 % interval is the 2.5th and 97.5th percentile of the replicates (``numpy.percentile``, linear).
  With one run per learner the interval has no width: it needs several training seeds.
* **Probability of improvement** P(X > Y): per pipe, the Mann–Whitney U statistic of X's runs
  against Y's divided by the number of pairs (ties count one half), averaged over pipes; its
  interval resamples X's and Y's runs independently within each pipe.
* **Performance profile**: for each return τ, the share of runs × pipes with a return above τ,
  with stratified-bootstrap intervals.

rliable draws its replicates from NumPy's global legacy generator; here they come from an explicit
``numpy.random.Generator``, so the intervals equal rliable's up to the Monte-Carlo error of the
bootstrap (tests/data/rliable_reference.json holds rliable's values and the command that made
them). The point estimates are exact.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numba import njit

from pipefollow.evaluation.stats import CONFIDENCE, iqm

REPS = 50_000  # rliable's default for interval estimates
PROFILE_REPS = 2_000  # rliable's default for performance profiles
POI_REPS = 2_000
_CHUNK_VALUES = 4_000_000  # floats per block of replicates (bounds the memory to ≈ 32 MB)


def mean(scores: np.ndarray) -> float:
    """Mean over pipes of the mean over runs (rliable's ``aggregate_mean``)."""
    return float(np.mean(np.mean(np.asarray(scores, dtype=np.float64), axis=0)))


def _check(scores) -> np.ndarray:
    x = np.asarray(scores, dtype=np.float64)
    if x.ndim != 2 or x.size == 0:
        raise ValueError(f"scores must be a non-empty (runs, pipes) matrix, not of shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError("scores must be finite")
    return x


@njit(cache=True)
def _replicate_stats(idx, order, values, cut, ks, out_iqm, out_mean, out_share):
    """IQM, mean and shares above τ of stratified replicates given by their drawn runs.

    ``idx[b, i, j]`` is the run drawn as the ``i``-th of pipe ``j`` in replicate ``b``. Each
    replicate is described exactly by how often it drew each cell (run, pipe); its statistics are
    sums over the matrix's sorted values (``values``, cell ``order[p]`` at position ``p``) weighted by
    those counts, so no replicate is built or sorted. The IQM is scipy's ``trim_mean(·, 0.25)``: the
    values at sorted positions ``cut`` to ``n − cut``. ``ks[t]``: the number of values ≤ τ_t.
    """
    b_n, n_runs, n_pipes = idx.shape
    n = n_runs * n_pipes
    w = np.zeros(n, dtype=np.int64)
    cum = np.zeros(n, dtype=np.int64)
    lo, hi = cut, n - cut
    for b in range(b_n):
        w[:] = 0
        for i in range(n_runs):
            for j in range(n_pipes):
                w[idx[b, i, j] * n_pipes + j] += 1
        total = 0
        s_all = 0.0
        s_mid = 0.0
        for p in range(n):
            c = w[order[p]]
            prev = total
            total += c
            cum[p] = total
            if c:
                v = values[p]
                s_all += c * v
                inside = min(max(total, lo), hi) - min(max(prev, lo), hi)
                s_mid += inside * v
        out_iqm[b] = s_mid / (hi - lo)
        out_mean[b] = s_all / n
        for t in range(ks.shape[0]):
            k = ks[t]
            out_share[b, t] = 1.0 if k == 0 else (n - cum[k - 1]) / n


def _stratified(x: np.ndarray, reps: int, rng: np.random.Generator, taus: np.ndarray):
    """(iqm, mean, shares above ``taus``) of ``reps`` stratified replicates of ``x``."""
    n_runs, n_pipes = x.shape
    order = np.argsort(x.ravel(), kind="stable")
    values = x.ravel()[order]
    ks = np.searchsorted(values, taus, side="right").astype(np.int64)
    out_iqm, out_mean = np.empty(reps), np.empty(reps)
    out_share = np.empty((reps, len(taus)))
    block = max(1, _CHUNK_VALUES // x.size)
    for start in range(0, reps, block):
        stop = min(reps, start + block)
        idx = rng.integers(0, n_runs, size=(stop - start, n_runs, n_pipes))
        _replicate_stats(
            idx, order, values, int(0.25 * x.size), ks,
            out_iqm[start:stop], out_mean[start:stop], out_share[start:stop],
        )  # fmt: skip
    return out_iqm, out_mean, out_share


def _interval(values: np.ndarray, confidence: float) -> list[float]:
    tail = 100.0 * (1.0 - confidence) / 2.0
    lo, hi = np.percentile(values, [tail, 100.0 - tail], axis=0)
    return [float(lo), float(hi)] if np.ndim(lo) == 0 else [lo.tolist(), hi.tolist()]


def aggregate_intervals(
    scores, reps: int = REPS, seed: int = 0, confidence: float = CONFIDENCE
) -> dict[str, float | list[float]]:
    """IQM and mean of a (runs, pipes) matrix with stratified-bootstrap percentile intervals."""
    x = _check(scores)
    iqms, means, _ = _stratified(x, reps, np.random.default_rng(seed), np.empty(0))
    return {
        "iqm": iqm(x),
        "ci95_iqm": _interval(iqms, confidence),
        "mean": mean(x),
        "ci95_mean": _interval(means, confidence),
    }


def _poi_per_pipe(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """P(X > Y) per pipe from the runs of x (…, n, pipes) and y (…, m, pipes); ties count one half."""
    gt = (x[..., :, None, :] > y[..., None, :, :]).sum(axis=(-3, -2))
    eq = (x[..., :, None, :] == y[..., None, :, :]).sum(axis=(-3, -2))
    return (gt + 0.5 * eq) / (x.shape[-2] * y.shape[-2])


def probability_of_improvement(x, y) -> float:
    """P(X > Y) averaged over pipes (rliable's ``probability_of_improvement``)."""
    x, y = _check(x), _check(y)
    if x.shape[1] != y.shape[1]:
        raise ValueError(f"X has {x.shape[1]} pipes, Y {y.shape[1]}")
    return float(_poi_per_pipe(x, y).mean())


def poi_interval(
    x, y, reps: int = POI_REPS, seed: int = 0, confidence: float = CONFIDENCE
) -> dict[str, float | list[float]]:
    """P(X > Y) with the interval of rliable's independent stratified bootstrap of X's and Y's runs."""
    x, y = _check(x), _check(y)
    point = probability_of_improvement(x, y)
    rng = np.random.default_rng(seed)
    per_rep = max(1, _CHUNK_VALUES // (x.shape[0] * y.shape[0] * x.shape[1]))
    values, done = [], 0
    while done < reps:
        b = min(per_rep, reps - done)
        xs = x[rng.integers(0, x.shape[0], size=(b, *x.shape)), np.arange(x.shape[1])]
        ys = y[rng.integers(0, y.shape[0], size=(b, *y.shape)), np.arange(y.shape[1])]
        values.append(_poi_per_pipe(xs, ys).mean(axis=-1))
        done += b
    return {"probability": point, "ci95": _interval(np.concatenate(values), confidence)}


def performance_profile(
    scores, taus, reps: int = PROFILE_REPS, seed: int = 0, confidence: float = CONFIDENCE
) -> dict[str, list[float]]:
    """Share of runs × pipes with a return above each τ, with stratified-bootstrap intervals."""
    x = _check(scores)
    taus = np.atleast_1d(np.asarray(taus, dtype=np.float64))
    _, _, shares = _stratified(x, reps, np.random.default_rng(seed), taus)
    lo, hi = _interval(shares, confidence)
    share = [float(np.mean(x > t)) for t in taus]
    return {"tau": taus.tolist(), "share": share, "ci95_low": lo, "ci95_high": hi}


@dataclass(frozen=True)
class Comparison:
    """The result of :func:`compare`: :attr:`summary` is what ``pipefollow compare --json`` prints."""

    summary: dict
    scores: dict[str, np.ndarray]


def compare(
    scores: Mapping[str, np.ndarray],
    *,
    reps: int = REPS,
    profile_points: int = 101,
    seed: int = 0,
) -> Comparison:
    """IQM, mean, pairwise probabilities of improvement and performance profiles of several learners.

    Args:
        scores: learner label → (runs, pipes) matrix of returns; all on the same pipes.
        reps: bootstrap replicates of the IQM and mean intervals (PoI and profiles: rliable's 2,000).
        profile_points: number of returns τ, evenly spaced over the range of all scores.
        seed: seed of every bootstrap (learner ``i`` uses ``SeedSequence([seed, i])``).
    """
    mats = {label: _check(s) for label, s in scores.items()}
    pipes = {m.shape[1] for m in mats.values()}
    if len(pipes) != 1:
        raise ValueError(f"learners were scored on different numbers of pipes: {sorted(pipes)}")
    seeds = np.random.SeedSequence(seed).spawn(len(mats) + len(mats) ** 2)
    lo = min(float(m.min()) for m in mats.values())
    hi = max(float(m.max()) for m in mats.values())
    taus = np.linspace(lo, hi, profile_points) if hi > lo else np.array([lo])
    learners = {}
    for i, (label, m) in enumerate(mats.items()):
        rng_seed = int(seeds[i].generate_state(1)[0])
        learners[label] = {
            "runs": int(m.shape[0]),
            **aggregate_intervals(m, reps, rng_seed),
            "profile": performance_profile(m, taus, seed=rng_seed),
        }
    labels = list(mats)
    poi = []
    for i, a in enumerate(labels):
        for j, b in enumerate(labels):
            if i != j:
                s = int(seeds[len(mats) + i * len(mats) + j].generate_state(1)[0])
                poi.append({"x": a, "y": b, **poi_interval(mats[a], mats[b], seed=s)})
    summary = {
        "pipes": int(next(iter(pipes))),
        "reps": reps,
        "learners": learners,
        "probability_of_improvement": poi,
    }
    return Comparison(summary, mats)


def format_summary(s: dict, head: str = "") -> str:
    """``pipefollow compare``'s text: a row per learner, the probabilities of improvement, the files.

    ``s`` is the command's summary (its ``--json``); ``head`` follows the head line (the camera's
    line, if any).
    """
    lines = [
        f"{len(s['learners'])} learners on '{s['suite']}': {s['pipes']} pipes, {s['seconds']:g} s each; "
        f"95 % stratified-bootstrap intervals over runs ({s['reps']} replicates){head}",
        f"{'learner':<34} {'runs':>4} {'IQM':>8} {'95 % CI':>19} {'mean':>8} {'95 % CI':>19} "
        f"{'success':>7} {'progress':>8} {'back':>4}",
    ]
    for label, r in s["learners"].items():
        iq, mn = r["ci95_iqm"], r["ci95_mean"]
        lines.append(
            f"{label[:34]:<34} {r['runs']:>4} {r['iqm']:>8.2f} {iq[0]:>9.2f}–{iq[1]:<9.2f} "
            f"{r['mean']:>8.2f} {mn[0]:>9.2f}–{mn[1]:<9.2f} "
            f"{r['success_rate']:>7.0%} {r['mean_progress_share']:>8.0%} {r['turned_back']:>4d}"
        )
    lines.append(
        "success: pipe in view ≥ 95 % of the decisions and followed forward; progress: of the reachable; "
        "back: episodes that followed the pipe backwards ≥ 3 m"
    )
    if s["probability_of_improvement"]:
        lines.append("probability of improvement P(X > Y), per pipe over runs, averaged over pipes:")
        for p in s["probability_of_improvement"]:
            lo, hi = p["ci95"]
            lines.append(f"  P({p['x']} > {p['y']}) = {p['probability']:.2f}  (95 % CI {lo:.2f}–{hi:.2f})")
    if any(r["runs"] == 1 for r in s["learners"].values()):
        lines.append("note: a learner with one run has intervals of no width; train several seeds")
    if "plot" in s:
        lines.append(f"plot: {s['plot']}")
    if "scores_file" in s:
        lines.append(f"scores (rliable's layout): {s['scores_file']}")
    return "\n".join(lines)
