"""Benchmark a controller on a suite of pipes: one deterministic episode per pipe, beside the heuristic.

The episodes of the built-in controllers (heuristic, line-of-sight guidance) and of exported network
policies (:class:`~pipefollow.learners.mlp.MLPPolicy`: PPO, SAC) run in one compiled call over all
pipes, their points concatenated into one array with offsets; the policies of the learner registry
(SARSA, CACLA, the actor-critic) run in their learner's own compiled loop with σ = 0 and no learning;
other controllers (anything with ``act(obs, explore)``) run through the environment's episode
function. All give the same numbers (tested). The summary has bootstrap confidence intervals
(:mod:`pipefollow.evaluation.stats`).

Definitions:

* ``pipe_in_view``: share of decisions that end with the pipe in view.
* ``success_rate``: share of episodes with the pipe in view at ≥ 95 % of the decisions *and* followed
  forward: the pipe's end reached, or a progress of at least half the distance covered
  (:mod:`pipefollow.evaluation.success`); ``in_view_rate`` the share with the pipe in view alone;
  ``mean_progress_share`` the mean of progress / reachable; ``reached_end`` and ``turned_back``
  (followed the pipe backwards for ≥ 3 m) counts of episodes.
* ``rms_e_dist``: root mean square of ``e_dist`` over the decisions that end with the pipe in
  view (per episode; pooled over all episodes for the summary); ``None`` without such decisions.
* ``progress_m``: arc length reached along the pipe. An episode ends at the pipe's far end
  (reading ``pipe_end``), which the held-out suites' pipes are too long to reach.
* ``ci95_mean``: BCa bootstrap interval of the mean return over pipes; ``ci95_iqm``: the
  percentile interval of the IQM, the pipes resampled as rliable resamples runs
  (:mod:`pipefollow.evaluation.compare`).
* ``vs_heuristic``: *paired* per pipe: ``mean_diff`` and its interval are those of the per-pipe
  differences (controller − heuristic on the same pipe and noise, the heuristic observing through
  the same camera or sensor); ``win_rate`` is the share of pipes where the controller's return is
  higher than the heuristic's on that pipe. ``vs_heuristic_ideal`` (with a camera or sensor other
  than the ideal camera): the same against the heuristic on the ideal camera.
* ``lost_pipes``: episodes with the pipe in view at fewer than 80 % of the decisions.

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

from pipefollow.evaluation import success as sc
from pipefollow.evaluation.compare import aggregate_intervals
from pipefollow.evaluation.stats import bootstrap_ci, iqm, paired_difference
from pipefollow.files.paper_training import TEST_EPISODE_SECONDS
from pipefollow.learners import mlp as mlp_mod
from pipefollow.learners.heuristic import Heuristic, heuristic_action
from pipefollow.learners.los import LOS, los_action
from pipefollow.learners.registry import learner_of
from pipefollow.sim import decision as sim
from pipefollow.sim import episode as ep
from pipefollow.sim.episode import STAT_NAMES, Run, tracks_of
from pipefollow.sim.pipeline import Pipeline
from pipefollow.sim.suites import Suite, min_length_for
from pipefollow.training.compiled import run_episode

HEURISTIC, MLP, LOS_KIND = 0, 1, 2  # fixed controllers of the compiled episodes

# Built-in controllers by name: a factory of an agent with ``act``/``begin_episode``. A controller
# without a compiled loop runs through the environment.
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
def _controller_episodes(kind, tracks, run, net, lookahead, z_all, out, poses):
    """Deterministic episodes of a fixed controller (heuristic, LOS, network), pipe ``e`` in episode ``e``."""
    ps = sim.unpack_params(run.sim)
    decision_s = sim.decision_seconds(ps)
    s = np.empty(sim.STATE_SIZE)
    theta, layout = net
    h0, h1 = np.empty(layout[0, 3]), np.empty(layout[0, 3])
    a_out = np.empty(layout[0, 1])
    book = np.empty(ep.BOOK_SIZE)
    for e in range(tracks.starts.shape[0]):
        pts, cum, start = ep.pipe_of(tracks, e)
        sim.init_state(s, pts, cum, start[0], start[1], start[2], ps, z_all[e, 0])
        ep.start(book, poses, e, s)
        for t in range(run.n_decisions):
            a = 0.0
            if s[sim.IN_VIEW] != 0.0:
                if kind == HEURISTIC:
                    a = heuristic_action(s[sim.X1], s[sim.Y1])
                elif kind == MLP:
                    a = mlp_mod.action1(theta, layout, s[:4], h0, h1, a_out)
                else:  # LOS from the observation alone, as the LOS agent (y_near = 0)
                    a = los_action(s[sim.X1], s[sim.Y1], s[sim.X2], 0.0, lookahead)
            ep.decide(s, a, pts, cum, ps, z_all[e, t + 1], book, poses, e)
            if ep.end_of(book, s, cum, ps, run.n_decisions) == ep.PIPE_END:
                break
        ep.hold_poses(poses, e, book)
        ep.close_episode(out, e, book, s[sim.PROGRESS_MAX], decision_s)


# Fixed controllers with a compiled kind; learners run their own loop (pipefollow.learners.registry).
_FIXED_KINDS = {Heuristic: HEURISTIC, mlp_mod.MLPPolicy: MLP, LOS: LOS_KIND}
_NO_NET = (np.zeros(1), np.ones((1, 4), dtype=np.int64))  # theta, layout of "no network"


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

    ``noise_seed`` seeds the random disturbances, if any (module docstring). Learners of the
    registry run their own compiled loop without learning, the heuristic, LOS and exported networks
    one compiled loop here; other controllers (and learners the compiled loop cannot run, such as
    a custom supervisor) run through the environment's episode function.
    ``camera``: the environment's camera arguments (``camera``, ``water``, ``reward_from``); with
    the vision camera the episodes run through the environment, the images and detections drawing
    from the pipe's noise generator, and ``pipe_in_view`` and ``rms_e_dist`` are the exact camera's.

    Returns ``(results, poses)``: (pipes, 6) statistics, the columns of
    :data:`pipefollow.sim.episode.STAT_NAMES` (return, pipe_in_view, progress_m, time_lost_s,
    Σ e_dist² and the number of decisions in view); (pipes, decisions + 1, 3) poses (x, y, ψ).
    """
    from pipefollow.sim.disturbance import noise_count

    n_decisions = sim.decisions_in(seconds, params)
    out = np.zeros((len(pipes), len(STAT_NAMES)))
    poses = np.zeros((len(pipes), n_decisions + 1, 3))
    learner = learner_of(agent)
    fixed = _FIXED_KINDS.get(type(agent))
    if learner is not None:
        try:
            learner.check(agent)
        except TypeError:
            learner = None
    if (learner is None and fixed is None) or camera:
        _env_episodes(agent, pipes, seconds, params, out, poses, noise_seed, camera)
        return out, poses
    run = Run(sim.pack_params(params), np.zeros(1), n_decisions, False)
    k = noise_count(params.disturbance)
    if learner is not None and k == 0:  # one call over all pipes, episode e on pipe e
        run = run._replace(sigmas=np.zeros(len(pipes)))
        learner.run(agent, tracks_of(pipes), run, np.random.default_rng(0), np.zeros(0), out, poses)
        return out, poses
    if learner is not None:  # pipe by pipe: each with its own disturbance generator
        for e, pipe in enumerate(pipes):
            learner.run(agent, tracks_of([pipe]), run, _noise_rng(noise_seed, e), np.zeros(k), out[e : e + 1],
                        poses[e : e + 1])  # fmt: skip
        return out, poses
    z_all = np.zeros((len(pipes), n_decisions + 1, k))
    if k:
        for e in range(len(pipes)):
            z_all[e] = _noise_rng(noise_seed, e).standard_normal((n_decisions + 1, k))
    net = (agent.theta, agent.layout) if fixed == MLP else _NO_NET
    _controller_episodes(
        fixed, tracks_of(pipes), run, net, getattr(agent, "lookahead", 0.0), z_all, out, poses
    )
    return out, poses


def _env_episodes(agent, pipes, seconds, params, out, poses, noise_seed: int = 0, camera=None) -> None:
    """:func:`run_episodes` through the environment's episode function, for any controller or camera."""
    from pipefollow.envs.env import PipelineFollowingEnv

    for i, pipe in enumerate(pipes):
        state = getattr(agent, "state", "paper")  # what a learner observes (sim.observation)
        env = PipelineFollowingEnv(pipe, seconds, params=params, state=state, **(camera or {}))
        env.np_random = _noise_rng(noise_seed, i)
        stats = run_episode(env, agent)
        out[i] = stats.as_full_row()
        k = len(stats.poses)  # fewer than the decisions if the episode ended at the pipe's end
        poses[i, :k] = stats.poses
        poses[i, k:] = stats.poses[-1]


@dataclass(frozen=True)
class BenchmarkRun:
    """A benchmark's summary (:meth:`to_dict`, the JSON) and the data behind its plot.

    ``heuristic_returns``/``heuristic_poses`` are the reference's: the heuristic through the same
    camera or sensor (``vs_heuristic``); ``ideal_returns`` the heuristic's on the ideal camera
    (``vs_heuristic_ideal``; the same as the reference's without a camera).
    """

    summary: dict
    pipes: list[Pipeline]
    returns: np.ndarray
    heuristic_returns: np.ndarray
    poses: np.ndarray
    heuristic_poses: np.ndarray
    ideal_returns: np.ndarray | None = None


def _rms(sum_e2: float, n: float) -> float | None:
    return math.sqrt(sum_e2 / n) if n > 0 else None


LOST_IN_VIEW = 0.8  # an episode with the pipe in view at fewer decisions than this lost its pipe


def summarize(
    res: np.ndarray,
    pipes: Sequence[Pipeline],
    *,
    controller: str,
    suite: str,
    seed: int = 0,
    references: dict[str, np.ndarray] | None = None,
) -> dict:
    """The summary of a benchmark's statistics ``res`` (one row per pipe; module docstring).

    ``references`` maps a key of the summary (``vs_heuristic``, ``vs_heuristic_ideal``) to the
    returns per pipe of a reference run on the same pipes and noise: the paired difference to it.
    ``lost_pipes`` counts the episodes with the pipe in view at fewer than :data:`LOST_IN_VIEW`
    of the decisions.
    """
    ret = res[:, ep.STAT_RETURN]
    lengths = np.array([p.length for p in pipes])
    lo, hi = bootstrap_ci(ret, seed)
    # the pipes as the runs of one task, in rliable's terms: its percentile interval of the IQM
    iqm_ci = aggregate_intervals(ret[:, None], seed=seed)["ci95_iqm"]
    summary = {
        "controller": controller,
        "suite": suite,
        "n_episodes": len(pipes),
        "mean_return": float(ret.mean()),
        "ci95_mean": [lo, hi],
        "iqm_return": iqm(ret),
        "ci95_iqm": iqm_ci,
        **sc.summary(res, lengths),
        "lost_pipes": int(np.sum(res[:, ep.STAT_IN_VIEW] < LOST_IN_VIEW)),
        "mean_pipe_in_view": float(res[:, ep.STAT_IN_VIEW].mean()),
        "rms_e_dist": _rms(float(res[:, ep.STAT_SUM_E2].sum()), float(res[:, ep.STAT_N_SEEN].sum())),
        "mean_progress_m": float(res[:, ep.STAT_PROGRESS].mean()),
    }
    for key, ref in (references or {}).items():
        summary[key] = paired_difference(ret, ref, seed)
    summary["episodes"] = [
        {
            "name": pipe.name,
            "return": float(row[ep.STAT_RETURN]),
            "pipe_in_view": float(row[ep.STAT_IN_VIEW]),
            "progress_m": float(row[ep.STAT_PROGRESS]),
            "rms_e_dist": _rms(row[ep.STAT_SUM_E2], row[ep.STAT_N_SEEN]),
            **sc.episode_fields(row, pipe.length),
        }
        for pipe, row in zip(pipes, res, strict=True)
    ]
    return summary


def heuristic_camera(camera: dict | None) -> dict | None:
    """The heuristic's camera arguments beside a controller's.

    The same camera, sensor and water with the vector observation: the heuristic reads the pipe's
    end points, not an image. On the ideal camera alone the water then changes nothing (the
    environment refuses it there), so it is left out.
    """
    if not camera:
        return camera
    out = {k: v for k, v in camera.items() if k != "observation"}
    if out.get("camera", "ideal") == "ideal" and out.get("sensor", "camera") == "camera":
        out.pop("water", None)
    return out


def benchmark(
    agent,
    suite: Suite,
    *,
    controller: str,
    seconds: float = TEST_EPISODE_SECONDS,
    params: sim.SimParams = sim.PAPER_SIM,
    n_pipes: int | None = None,
    seed: int = 0,
    noise_seed: int = 0,
    camera: dict | None = None,
) -> BenchmarkRun:
    """Run ``agent`` and the heuristic on the suite's pipes and summarize (module docstring).

    The heuristic runs through the same camera or sensor as ``agent`` (``camera``), on the same
    pipes and noise: ``vs_heuristic`` is the paired difference to it (absent for the heuristic
    itself). With a camera, the heuristic also runs on the ideal camera: ``vs_heuristic_ideal``.

    Args:
        agent: the controller (an agent with ``act``).
        controller: its label in the summary.
        suite: the pipes: all of a held-out suite, or the first ``n_pipes`` of a training family.
        seconds: episode length.
        params: the simulated system, disturbances included, for every episode.
        n_pipes: number of pipes (default: the whole held-out suite; 100 of a training family).
        seed: seed of the bootstrap resampling.
        noise_seed: seed of the random disturbances (module docstring), the same for both.
        camera: the environment's camera arguments (:func:`run_episodes`), for ``agent`` and the
            heuristic it is compared with.
    """
    n = n_pipes if n_pipes is not None else (suite.count or 100)
    pipes = suite.pipes(n, min_length_for(seconds))
    res, poses = run_episodes(agent, pipes, seconds, params, noise_seed, camera)
    is_heuristic = isinstance(agent, Heuristic)
    if is_heuristic:
        h_res, h_poses = res, poses
    else:
        h_camera = heuristic_camera(camera)
        h_res, h_poses = run_episodes(Heuristic(), pipes, seconds, params, noise_seed, h_camera)
    references = {} if is_heuristic else {"vs_heuristic": h_res[:, ep.STAT_RETURN]}
    ideal = h_res[:, ep.STAT_RETURN]
    if camera:  # the second reference: the heuristic on the ideal camera
        ideal = run_episodes(Heuristic(), pipes, seconds, params, noise_seed)[0][:, ep.STAT_RETURN]
        references["vs_heuristic_ideal"] = ideal
    summary = summarize(res, pipes, controller=controller, suite=suite.name, seed=seed, references=references)
    if camera:  # the camera and water of the controller and of the heuristic beside it
        from pipefollow.perception.camera import camera_settings

        settings = camera_settings(**camera)
        summary["camera"] = settings.camera
        if settings.sensor != "camera":
            summary["sensor"] = settings.sensor
        summary["water"] = settings.water._asdict()
        episodes = summary.pop("episodes")  # the episodes stay last
        summary["episodes"] = episodes
    ret = res[:, ep.STAT_RETURN]
    return BenchmarkRun(summary, pipes, ret, h_res[:, ep.STAT_RETURN].copy(), poses, h_poses, ideal.copy())


def format_summary(r: dict, seconds: float) -> str:
    """A benchmark summary as a few lines of text."""
    lo, hi = r["ci95_mean"]
    ilo, ihi = r["ci95_iqm"]
    rms = "—" if r["rms_e_dist"] is None else f"{r['rms_e_dist']:.3f} m"
    lines = [
        f"{r['controller']} on '{r['suite']}': {r['n_episodes']} pipes, {seconds:g} s each, σ = 0",
        f"  mean return    {r['mean_return']:9.2f}  (95 % CI {lo:.2f} to {hi:.2f})",
        f"  IQM return     {r['iqm_return']:9.2f}  (95 % CI {ilo:.2f} to {ihi:.2f})",
        f"  success rate   {r['success_rate']:9.1%}  (pipe in view ≥ 95 %, followed forward)",
        f"  in view ≥ 95 % {r['in_view_rate']:9.1%}  (of the episodes)",
        f"  pipe in view   {r['mean_pipe_in_view']:9.1%}",
        f"  rms e_dist     {rms:>9}",
        f"  progress       {r['mean_progress_m']:7.2f} m  ({r['mean_progress_share']:.0%} of the reachable)",
        f"  reached end    {r['reached_end']:>9d}  (episodes)",
        f"  turned back    {r['turned_back']:>9d}  (episodes that followed the pipe backwards ≥ 3 m)",
        f"  lost the pipe  {r['lost_pipes']:>9d}  (episodes with the pipe in view < 80 %)",
    ]
    same = "camera" in r  # a camera or sensor: the heuristic beside it observed through the same
    for key, label, where in (
        ("vs_heuristic", "vs heuristic", "through the same sensor" if same else ""),
        ("vs_heuristic_ideal", "vs heuristic", "on the ideal camera"),
    ):
        if key in r:
            v = r[key]
            dlo, dhi = v["ci95_diff"]
            lines.append(
                f"  {label:<14} {v['mean_diff']:+9.2f}  (95 % CI {dlo:+.2f} to {dhi:+.2f}; "
                f"better on {v['win_rate']:.0%} of the pipes{'; ' + where if where else ''})"
            )
    return "\n".join(lines)
