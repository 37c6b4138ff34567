"""Benchmark a controller on a suite of pipes: one deterministic episode per pipe, beside the heuristic.

The episodes of the built-in controllers (heuristic, line-of-sight guidance), of CACLA and SARSA
policies and of exported network policies (:class:`~pipefollow.learners.mlp.MLPPolicy`: PPO, SAC) run in
one compiled call over all pipes, their points concatenated into one array with offsets; other controllers
(anything with ``act(obs, explore)``) run through the Gymnasium environment. Both give the same
numbers (tested). The summary has bootstrap confidence intervals (:mod:`pipefollow.evaluation.stats`).

Definitions:

* ``pipe_in_view``: share of decisions that end with the pipe in view; an episode is a
  *success* when it is ≥ :data:`SUCCESS_IN_VIEW` (95 %).
* ``rms_e_dist``: root mean square of ``e_dist`` over the decisions that end with the pipe in
  view (per episode; pooled over all episodes for the summary); ``None`` without such decisions.
* ``progress_m``: arc length reached along the pipe.

Random disturbances (camera noise, missed detections, a varying current) draw, for pipe ``k``,
from ``numpy.random.default_rng(SeedSequence([noise_seed, k]))`` in the order the environment
draws from its ``np_random``: the reset's camera reading, then one reading per decision. Every
controller meets the same noise on the same pipe (common random numbers for the paired comparison).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numba import njit

from pipefollow.evaluation.stats import bootstrap_ci, iqm, paired_difference
from pipefollow.learners import cacla as cacla_mod
from pipefollow.learners import mlp as mlp_mod
from pipefollow.learners import sarsa as sarsa_mod
from pipefollow.learners.heuristic import Heuristic, heuristic_action
from pipefollow.learners.los import LOS, los_action
from pipefollow.learners.rbf import STATE_GRID, grid_features
from pipefollow.sim import decision as sim
from pipefollow.sim.pipeline import Pipeline
from pipefollow.sim.suites import Suite, min_length_for

SUCCESS_IN_VIEW = 0.95
HEURISTIC, CACLA, SARSA, MLP, LOS_KIND = 0, 1, 2, 3, 4  # controller kinds of the compiled episodes

# Columns of the per-episode results.
RET, IN_VIEW, PROGRESS, SUM_E2, N_SEEN = 0, 1, 2, 3, 4

# Built-in controllers by name: a factory of an agent with ``act``/``begin_episode``. A controller
# without a compiled kind (see :func:`_compiled_kind`) runs through the environment.
CONTROLLERS: dict[str, Callable[[], object]] = {
    "heuristic": Heuristic,
    "los": LOS,
}


def load_controller(spec: str, seed: int = 0, lookahead: float | None = None):
    """A built-in controller name (:data:`CONTROLLERS`) or a policy file → an agent.

    ``lookahead`` (m) sets the LOS controller's Δ (its default when None).

    Raises:
        ValueError: ``lookahead`` given for another controller than ``los``.
    """
    if lookahead is not None:
        if spec != "los":
            raise ValueError("--lookahead applies to --controller los only")
        return LOS(lookahead)
    if spec in CONTROLLERS:
        return CONTROLLERS[spec]()
    from pipefollow.training.policy_files import load_policy

    return load_policy(spec, seed=seed)


@njit(cache=True)
def _suite_episodes(
    kind,
    w,
    hp,
    search_actions,
    search_psi,
    points_all,
    cum_all,
    offsets,
    simp,
    n_decisions,
    centres,
    grid_offsets,
    widths,
    normalized,
    theta,
    layout,
    z_all,
    out,
    poses,
    lookahead,
):
    ps = sim.unpack_params(simp)
    p = cacla_mod.unpack(hp)
    s = np.empty(sim.STATE_SIZE)
    phi = np.empty(w.shape[1])
    h0, h1 = np.empty(layout[0, 3]), np.empty(layout[0, 3])
    a_out = np.empty(layout[0, 1])
    for e in range(offsets.shape[0] - 1):
        pts = points_all[offsets[e] : offsets[e + 1]]
        cum = cum_all[offsets[e] : offsets[e + 1]]
        psi0 = math.atan2(pts[1, 1] - pts[0, 1], pts[1, 0] - pts[0, 0])
        sim.init_state(s, pts, cum, pts[0, 0], pts[0, 1], psi0, ps, z_all[e, 0])
        poses[e, 0, 0], poses[e, 0, 1], poses[e, 0, 2] = s[sim.X], s[sim.Y], s[sim.PSI]
        total = 0.0
        seen = 0
        sum_e2 = 0.0
        for t in range(n_decisions):
            a = 0.0
            if s[sim.IN_VIEW] != 0.0:
                if kind == HEURISTIC:
                    a = heuristic_action(s[sim.X1], s[sim.Y1])
                elif kind == MLP:
                    a = mlp_mod.action1(theta, layout, s[:4], h0, h1, a_out)
                elif kind == LOS_KIND:  # from the observation alone, as the LOS agent (y_near = 0)
                    a = los_action(s[sim.X1], s[sim.Y1], s[sim.X2], 0.0, lookahead)
                else:
                    grid_features(s[:4], centres, grid_offsets, widths, normalized, phi)
                    if kind == CACLA:
                        a_sup = heuristic_action(s[sim.X1], s[sim.Y1]) if p.supervised else 0.0
                        a, _ = cacla_mod.act(w, phi, 0.0, 0.0, 0.0, a_sup, p)
                    else:
                        a = sarsa_mod.choose(w, phi, search_actions, search_psi, 0.0, 0.0)
            total += sim.decide(s, a, pts, cum, ps, z_all[e, t + 1])
            if s[sim.IN_VIEW] != 0.0:
                seen += 1
                sum_e2 += s[sim.E_DIST] * s[sim.E_DIST]
            poses[e, t + 1, 0], poses[e, t + 1, 1], poses[e, t + 1, 2] = s[sim.X], s[sim.Y], s[sim.PSI]
        out[e, RET] = total
        out[e, IN_VIEW] = seen / n_decisions
        out[e, PROGRESS] = s[sim.PROGRESS_MAX]
        out[e, SUM_E2] = sum_e2
        out[e, N_SEEN] = seen


def _compiled_kind(agent):
    """``(kind, weights, packed params, search actions, search ψ)`` for the compiled episodes, or None."""
    empty = np.zeros((1, 1))
    if isinstance(agent, mlp_mod.MLPPolicy):
        return MLP, np.zeros((4, 1)), cacla_mod.pack(cacla_mod.PAPER_CACLA), np.zeros(1), empty
    if isinstance(agent, Heuristic):
        return HEURISTIC, np.zeros((4, 1)), cacla_mod.pack(cacla_mod.PAPER_CACLA), np.zeros(1), empty
    if isinstance(agent, LOS):
        return LOS_KIND, np.zeros((4, 1)), cacla_mod.pack(cacla_mod.PAPER_CACLA), np.zeros(1), empty
    if isinstance(agent, cacla_mod.Cacla) and agent.default_supervisor:
        return CACLA, agent.weights, cacla_mod.pack(agent.params), np.zeros(1), empty
    if isinstance(agent, sarsa_mod.Sarsa):
        return (
            SARSA,
            agent.weights,
            cacla_mod.pack(cacla_mod.PAPER_CACLA),
            agent.search_actions,
            agent.search_psi,
        )
    return None


_NO_NET = (np.zeros(1), np.ones((1, 4), dtype=np.int64))  # theta, layout of "no network"


def concatenate(pipes: Sequence[Pipeline]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points and arc lengths of all pipes in two arrays, pipe ``i`` at ``offsets[i]:offsets[i + 1]``."""
    offsets = np.zeros(len(pipes) + 1, dtype=np.int64)
    offsets[1:] = np.cumsum([len(p.points) for p in pipes])
    points = np.ascontiguousarray(np.concatenate([p.points for p in pipes]))
    cum = np.ascontiguousarray(np.concatenate([p.cumulative for p in pipes]))
    return points, cum, offsets


def _noise_rng(noise_seed: int, k: int) -> np.random.Generator:
    """The generator of pipe ``k``'s random disturbances (module docstring)."""
    return np.random.default_rng(np.random.SeedSequence([noise_seed, k]))


def run_episodes(
    agent,
    pipes: Sequence[Pipeline],
    seconds: float,
    params: sim.SimParams = sim.PAPER_SIM,
    noise_seed: int = 0,
    camera: dict | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """One deterministic episode (σ = 0) of ``agent`` per pipe.

    ``noise_seed`` seeds the random disturbances, if any (module docstring). ``camera``: the
    environment's camera arguments (``camera``, ``water``, ``reward_from``); with the vision
    camera the episodes run through the environment, the images and detections drawing from the
    pipe's noise generator, and ``pipe_in_view`` and ``rms_e_dist`` are the exact camera's.

    Returns ``(results, poses)``: (pipes, 5) columns return, pipe_in_view, progress_m, Σ e_dist²
    and number of decisions in view; (pipes, decisions + 1, 3) poses (x, y, ψ).
    """
    n_decisions = int(round(seconds / (params.dt * params.substeps)))
    out = np.zeros((len(pipes), 5))
    poses = np.zeros((len(pipes), n_decisions + 1, 3))
    compiled = _compiled_kind(agent)
    if compiled is None or camera:
        _env_episodes(agent, pipes, seconds, params, out, poses, noise_seed, camera)
        return out, poses
    from pipefollow.sim.disturbance import noise_count

    k = noise_count(params.disturbance)
    z_all = np.zeros((len(pipes), n_decisions + 1, k))
    if k:
        for e in range(len(pipes)):
            z_all[e] = _noise_rng(noise_seed, e).standard_normal((n_decisions + 1, k))
    kind, w, hp, sa, spsi = compiled
    # the heuristic, LOS and the networks compute no features
    grid = STATE_GRID if kind in (HEURISTIC, MLP, LOS_KIND) else agent.grid
    grid_arrays, normalized = grid.packed, grid.form == "normalized"
    theta, layout = (agent.theta, agent.layout) if kind == MLP else _NO_NET
    points, cum, offsets = concatenate(pipes)
    _suite_episodes(
        kind, w, hp, sa, spsi, points, cum, offsets, sim.pack_params(params), n_decisions,
        *grid_arrays, normalized, theta, layout, z_all, out, poses, getattr(agent, "lookahead", 0.0),
    )  # fmt: skip
    return out, poses


def _env_episodes(agent, pipes, seconds, params, out, poses, noise_seed: int = 0, camera=None) -> None:
    """:func:`run_episodes` through the Gymnasium environment, for controllers without a compiled kind."""
    from pipefollow.envs.env import PipelineFollowingEnv

    for i, pipe in enumerate(pipes):
        env = PipelineFollowingEnv(pipe, seconds, params=params, **(camera or {}))
        env.np_random = _noise_rng(noise_seed, i)
        agent.begin_episode(0.0)
        obs, info = env.reset()
        done = False
        seen, total, sum_e2 = 0, 0.0, 0.0
        while not done:
            a = agent.act(obs, explore=False) if info["pipe_in_view"] else 0.0
            obs, r, terminated, truncated, info = env.step([a])
            total += r
            if info.get("true_pipe_in_view", info["pipe_in_view"]):  # the exact camera's view
                seen += 1
                sum_e2 += info.get("true_e_dist", info["e_dist"]) ** 2
            done = terminated or truncated
        out[i] = (total, seen / env.max_decisions, info["progress_m"], sum_e2, seen)
        poses[i] = np.array(env.trail)


@dataclass(frozen=True)
class BenchmarkRun:
    """A benchmark's summary (:meth:`to_dict`, the JSON) and the data behind its plot."""

    summary: dict
    pipes: list[Pipeline]
    returns: np.ndarray
    heuristic_returns: np.ndarray
    poses: np.ndarray
    heuristic_poses: np.ndarray


def _rms(sum_e2: float, n: float) -> float | None:
    return math.sqrt(sum_e2 / n) if n > 0 else None


def benchmark(
    agent,
    suite: Suite,
    *,
    controller: str,
    seconds: float = 60.0,
    params: sim.SimParams = sim.PAPER_SIM,
    n_pipes: int | None = None,
    seed: int = 0,
    noise_seed: int = 0,
    camera: dict | None = None,
) -> BenchmarkRun:
    """Run ``agent`` and the heuristic on the suite's pipes and summarize (module docstring).

    Args:
        agent: the controller (an agent with ``act``).
        controller: its label in the summary.
        suite: the pipes: all of a held-out suite, or the first ``n_pipes`` of a training family.
        seconds: episode length.
        params: the simulated system, disturbances included, for every episode.
        n_pipes: number of pipes (default: the whole held-out suite; 100 of a training family).
        seed: seed of the bootstrap resampling.
        noise_seed: seed of the random disturbances (module docstring), the same for both.
        camera: the environment's camera arguments for ``agent`` (:func:`run_episodes`); the
            heuristic it is compared with always runs on the ideal camera.
    """
    n = n_pipes if n_pipes is not None else (suite.count or 100)
    pipes = suite.pipes(n, min_length_for(seconds))
    res, poses = run_episodes(agent, pipes, seconds, params, noise_seed, camera)
    is_heuristic = isinstance(agent, Heuristic) and not camera
    if is_heuristic:
        h_res, h_poses = res, poses
    else:
        h_res, h_poses = run_episodes(Heuristic(), pipes, seconds, params, noise_seed)
    ret = res[:, RET]
    lo, hi = bootstrap_ci(ret, seed)
    summary = {
        "controller": controller,
        "suite": suite.name,
        "n_episodes": len(pipes),
        "mean_return": float(ret.mean()),
        "ci95_return": [lo, hi],
        "iqm_return": iqm(ret),
        "success_rate": float(np.mean(res[:, IN_VIEW] >= SUCCESS_IN_VIEW)),
        "mean_pipe_in_view": float(res[:, IN_VIEW].mean()),
        "rms_e_dist": _rms(float(res[:, SUM_E2].sum()), float(res[:, N_SEEN].sum())),
        "mean_progress_m": float(res[:, PROGRESS].mean()),
    }
    if not is_heuristic:
        summary["vs_heuristic"] = paired_difference(ret, h_res[:, RET], seed)
    summary["episodes"] = [
        {
            "name": pipe.name,
            "return": float(row[RET]),
            "pipe_in_view": float(row[IN_VIEW]),
            "progress_m": float(row[PROGRESS]),
            "rms_e_dist": _rms(row[SUM_E2], row[N_SEEN]),
        }
        for pipe, row in zip(pipes, res, strict=True)
    ]
    return BenchmarkRun(summary, pipes, ret, h_res[:, RET].copy(), poses, h_poses)


def format_summary(r: dict, seconds: float) -> str:
    """A benchmark summary as a few lines of text."""
    lo, hi = r["ci95_return"]
    rms = "—" if r["rms_e_dist"] is None else f"{r['rms_e_dist']:.3f} m"
    lines = [
        f"{r['controller']} on '{r['suite']}': {r['n_episodes']} pipes, {seconds:g} s each, σ = 0",
        f"  mean return    {r['mean_return']:9.2f}  (95 % CI {lo:.2f} to {hi:.2f}; "
        f"IQM {r['iqm_return']:.2f})",
        f"  success rate   {r['success_rate']:9.1%}  (pipe in view ≥ 95 % of the decisions)",
        f"  pipe in view   {r['mean_pipe_in_view']:9.1%}",
        f"  rms e_dist     {rms:>9}",
        f"  progress       {r['mean_progress_m']:7.2f} m",
    ]
    if "vs_heuristic" in r:
        v = r["vs_heuristic"]
        dlo, dhi = v["ci95_diff"]
        lines.append(
            f"  vs heuristic   {v['mean_diff']:+9.2f}  (95 % CI {dlo:+.2f} to {dhi:+.2f}; "
            f"better on {v['win_rate']:.0%} of the pipes)"
        )
    return "\n".join(lines)
