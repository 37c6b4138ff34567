"""Episodes and training: through the Gymnasium environment, and as one compiled loop.

Both paths follow the same protocol (docs/design.md):

* one decision per second; the agent acts only while the pipe is in view, otherwise the search
  behaviour flies the AUV and the agent's action is ignored;
* a decision whose next state sees the pipe gives an ordinary one-step update; while the pipe is
  lost no update is made, and when it is back in view (or the episode ends) one semi-Markov
  update ``δ = Σ γ^j r_j + γ^n V(s_reacq) − V(s)`` is made from the last state in view;
* the 20-s end is a time limit: agents bootstrap from the last state;
* exploration σ falls linearly from ``sigma_start`` to ``sigma_end`` over the episodes.

The compiled path (:func:`train_compiled`) composes the same compiled stage and update
functions as the environment and agent classes, consumes the same random numbers in the same
order, and so gives the same trajectory, returns and weights (tested to 1e-9). The agent's
generator drives exploration; a second generator, ``env_rng``, plays the environment's
``np_random``: per episode two uniforms (the start perturbation the environment draws at every
reset) and one block of standard normals per camera reading for the random disturbances.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numba import njit

from pipefollow.learners import cacla as cacla_mod
from pipefollow.learners import sarsa as sarsa_mod
from pipefollow.learners.exploration import linear_sigma
from pipefollow.learners.heuristic import heuristic_action
from pipefollow.learners.rbf import dim_activations, grid_features
from pipefollow.sim import decision as sim
from pipefollow.sim.pipeline import Pipeline

# Columns of the per-episode statistics.
RETURN, IN_VIEW, PROGRESS, TIME_LOST = 0, 1, 2, 3
STAT_NAMES = ("return", "pipe_in_view", "progress_m", "time_lost_s")


@dataclass(frozen=True)
class EpisodeStats:
    """What one episode gave.

    Attributes:
        ret: accumulated reward.
        pipe_in_view: fraction of decisions that ended with the pipe in view.
        progress_m: arc length reached along the pipe (m).
        time_lost_s: time with the pipe out of view at decision ends (s).
        poses: (decisions + 1, 3) poses (x, y, ψ) if recorded, else None.
    """

    ret: float
    pipe_in_view: float
    progress_m: float
    time_lost_s: float
    poses: np.ndarray | None = None

    def as_row(self) -> tuple[float, float, float, float]:
        """(return, pipe_in_view, progress_m, time_lost_s)."""
        return (self.ret, self.pipe_in_view, self.progress_m, self.time_lost_s)


def run_episode(
    env,
    agent,
    *,
    learn: bool = False,
    explore: bool = False,
    sigma: float = 0.0,
    seed: int | None = None,
    options: dict | None = None,
) -> EpisodeStats:
    """Run one episode of ``agent`` in a :class:`~pipefollow.envs.env.PipelineFollowingEnv`.

    With ``learn`` the agent is updated as described in the module docstring.
    """
    agent.begin_episode(sigma if explore else 0.0)
    obs, info = env.reset(seed=seed, options=options)
    decision_s = env.unwrapped.params.dt * env.unwrapped.params.substeps
    gamma = agent.discount if learn else 0.0
    pending = None
    acc = disc = 0.0
    total, seen, steps = 0.0, 0, 0
    done = False
    while not done:
        visible = info["pipe_in_view"]
        a = agent.act(obs, explore=explore) if visible else 0.0
        next_obs, r, terminated, truncated, info = env.step([a])
        total += r
        steps += 1
        seen += info.get("true_pipe_in_view", info["pipe_in_view"])  # the vision camera's truth
        done = terminated or truncated
        if learn:
            if visible:
                pending, acc, disc = (obs, a), r, gamma
            elif pending is not None:
                acc += disc * r
                disc *= gamma
            if pending is not None and (info["pipe_in_view"] or done):
                agent.update(pending[0], pending[1], acc, next_obs, 0.0 if terminated else disc)
                pending = None
        obs = next_obs
    env_u = env.unwrapped
    return EpisodeStats(
        total, seen / steps, float(info["progress_m"]), (steps - seen) * decision_s, np.array(env_u.trail)
    )


def train(
    env,
    agent,
    episodes: int,
    *,
    sigma_start: float = 1.0,
    sigma_end: float = 0.01,
    callback: Callable[[int, EpisodeStats], None] | None = None,
) -> np.ndarray:
    """Train ``agent`` for ``episodes`` episodes in ``env``; returns (episodes, 4) statistics."""
    stats = np.empty((episodes, 4))
    for e in range(episodes):
        sigma = linear_sigma(e, episodes, sigma_start, sigma_end)
        ep = run_episode(env, agent, learn=True, explore=True, sigma=sigma)
        stats[e] = ep.as_row()
        if callback is not None:
            callback(e, ep)
    return stats


# ---------------------------------------------------------------------------------------------
# The compiled path


@njit(cache=True)
def _reset_draws(env_rng, z):
    """What the environment's reset draws without start noise: the first camera reading's ``z``."""
    sim.draw_normals(env_rng, z)


@njit(cache=True)
def _cacla_episodes(
    w,
    hp,
    points,
    cum,
    start,
    simp,
    sigmas,
    n_decisions,
    centres,
    offsets,
    widths,
    normalized,
    rng,
    stats,
    env_rng,
    dz,
):
    p = cacla_mod.unpack(hp)
    ps = sim.unpack_params(simp)
    decision_s = ps.dt * ps.substeps
    nf = w.shape[1]
    s = np.empty(sim.STATE_SIZE)
    phi = np.empty(nf)
    phi_pend = np.empty(nf)
    phi_next = np.empty(nf)
    skewed = p.skew > 0.0
    for e in range(sigmas.shape[0]):
        sigma = sigmas[e]
        _reset_draws(env_rng, dz)
        sim.init_state(s, points, cum, start[0], start[1], start[2], ps, dz)
        pending = False
        have_phi = False  # phi already holds φ(s) of the current state (computed for the last update)
        a_rl_p = a_sup_p = acc = disc = 0.0
        total = 0.0
        seen = 0
        for t in range(n_decisions):
            visible = s[sim.IN_VIEW] != 0.0
            a = 0.0
            if visible:
                if not have_phi:
                    grid_features(s[:4], centres, offsets, widths, normalized, phi)
                z0 = z1 = 0.0
                if sigma > 0.0:
                    z0 = rng.standard_normal()
                    z1 = rng.standard_normal() if skewed else z0
                a_sup = heuristic_action(s[sim.X1], s[sim.Y1]) if p.supervised else 0.0
                a, a_rl = cacla_mod.act(w, phi, sigma, z0, z1, a_sup, p)
            have_phi = False
            sim.draw_normals(env_rng, dz)
            r = sim.decide(s, a, points, cum, ps, dz)
            total += r
            now_visible = s[sim.IN_VIEW] != 0.0
            seen += 1 if now_visible else 0
            if visible:
                pending = True
                phi, phi_pend = phi_pend, phi  # keep φ(s) for the update; no copy
                a_rl_p, a_sup_p, acc, disc = a_rl, a_sup, r, p.discount
            elif pending:
                acc += disc * r
                disc *= p.discount
            if pending and (now_visible or t == n_decisions - 1):
                grid_features(s[:4], centres, offsets, widths, normalized, phi_next)
                cacla_mod.update(w, phi_pend, a_rl_p, a_sup_p, acc, disc, phi_next, p)
                pending = False
                phi, phi_next = phi_next, phi  # φ(s') is the next decision's φ(s)
                have_phi = True
        stats[e, 0] = total
        stats[e, 1] = seen / n_decisions
        stats[e, 2] = s[sim.PROGRESS_MAX]
        stats[e, 3] = (n_decisions - seen) * decision_s


@njit(cache=True)
def _sarsa_episodes(
    W,
    alpha,
    discount,
    search_actions,
    search_psi,
    a_centres,
    a_width,
    a_normalized,
    points,
    cum,
    start,
    simp,
    sigmas,
    n_decisions,
    centres,
    offsets,
    widths,
    normalized,
    rng,
    stats,
    env_rng,
    dz,
):
    ps = sim.unpack_params(simp)
    decision_s = ps.dt * ps.substeps
    nf = W.shape[1]
    s = np.empty(sim.STATE_SIZE)
    phi = np.empty(nf)
    phi_pend = np.empty(nf)
    phi_next = np.empty(nf)
    psi = np.empty(a_centres.shape[0])
    psi_next = np.empty(a_centres.shape[0])
    for e in range(sigmas.shape[0]):
        sigma = sigmas[e]
        _reset_draws(env_rng, dz)
        sim.init_state(s, points, cum, start[0], start[1], start[2], ps, dz)
        has_next = False  # an on-policy action chosen by the last update for the current state
        a_next = 0.0
        pending = False
        a_p = acc = disc = 0.0
        total = 0.0
        seen = 0
        for t in range(n_decisions):
            visible = s[sim.IN_VIEW] != 0.0
            a = 0.0
            if visible:
                if has_next:
                    a = a_next
                    phi[:] = phi_next
                    has_next = False
                else:
                    grid_features(s[:4], centres, offsets, widths, normalized, phi)
                    z = rng.standard_normal() if sigma > 0.0 else 0.0
                    a = sarsa_mod.choose(W, phi, search_actions, search_psi, sigma, z)
            sim.draw_normals(env_rng, dz)
            r = sim.decide(s, a, points, cum, ps, dz)
            total += r
            now_visible = s[sim.IN_VIEW] != 0.0
            seen += 1 if now_visible else 0
            if visible:
                pending = True
                phi_pend[:] = phi
                a_p, acc, disc = a, r, discount
            elif pending:
                acc += disc * r
                disc *= discount
            if pending and (now_visible or t == n_decisions - 1):
                grid_features(s[:4], centres, offsets, widths, normalized, phi_next)
                z = rng.standard_normal() if sigma > 0.0 else 0.0
                a_next = sarsa_mod.choose(W, phi_next, search_actions, search_psi, sigma, z)
                has_next = True
                dim_activations(a_p, a_centres, a_width, a_normalized, psi)
                dim_activations(a_next, a_centres, a_width, a_normalized, psi_next)
                sarsa_mod.update(W, phi_pend, psi, acc, disc, phi_next, psi_next, alpha)
                pending = False
        stats[e, 0] = total
        stats[e, 1] = seen / n_decisions
        stats[e, 2] = s[sim.PROGRESS_MAX]
        stats[e, 3] = (n_decisions - seen) * decision_s


def compiled_setup(agent, episodes, episode_seconds, sigma_start, sigma_end, params, env_rng):
    """What every compiled training loop needs, after checking the agent and the disturbances.

    Returns ``(σ per episode, decisions per episode, an empty (episodes, 4) statistics array,
    packed parameters, the disturbances' generator, an array for their normals)``.

    Raises:
        ValueError: random disturbances without a seeded ``env_rng``.
        TypeError: an agent without a compiled loop, or supervised by another than the heuristic.
    """
    from pipefollow.sim.disturbance import check, noise_count

    if not isinstance(agent, (cacla_mod.Cacla, sarsa_mod.Sarsa)):
        raise TypeError(f"no compiled training loop for {type(agent).__name__}")
    if isinstance(agent, cacla_mod.Cacla) and agent.params.supervised and not agent.default_supervisor:
        raise TypeError(
            "the compiled loop supervises with the heuristic only; use train() for other supervisors"
        )
    check(params.disturbance)
    dz = np.zeros(noise_count(params.disturbance))
    if env_rng is None:
        if dz.size:
            raise ValueError("params.disturbance has random parts: pass a seeded env_rng")
        env_rng = np.random.default_rng(0)  # not drawn from: no random parts
    sigmas = np.array([linear_sigma(e, episodes, sigma_start, sigma_end) for e in range(episodes)])
    n_decisions = int(round(episode_seconds / (params.dt * params.substeps)))
    return sigmas, n_decisions, np.empty((episodes, 4)), sim.pack_params(params), env_rng, dz


def train_compiled(
    agent,
    pipeline: Pipeline,
    episodes: int,
    *,
    episode_seconds: float = 20.0,
    sigma_start: float = 1.0,
    sigma_end: float = 0.01,
    params: sim.SimParams = sim.PAPER_SIM,
    progress: Callable[[int], None] | None = None,
    chunk: int = 50,
    env_rng: np.random.Generator | None = None,
) -> np.ndarray:
    """Train a :class:`~pipefollow.learners.cacla.Cacla` or a ``Sarsa`` agent in compiled code.

    It gives the same numbers as :func:`train` on ``PipelineFollowingEnv(pipeline, episode_seconds,
    params=params)`` with the same agent state and generator, and with ``env_rng`` in the state of
    the environment's ``np_random``. ``env_rng`` is required when ``params.disturbance`` has random
    parts (camera noise, misses, a varying current). Runs ``chunk`` episodes per compiled call
    and reports the episodes done to ``progress``. Returns (episodes, 4) statistics.
    """
    run = compiled_setup(agent, episodes, episode_seconds, sigma_start, sigma_end, params, env_rng)
    sigmas, n_decisions, stats, simp, env_rng, dz = run
    centres, offsets, widths = agent.grid.packed
    normalized = agent.grid.form == "normalized"
    start = np.array([pipeline.points[0, 0], pipeline.points[0, 1], pipeline.start_heading])
    pts, cum = pipeline.points, pipeline.cumulative
    for lo in range(0, episodes, max(1, chunk)):
        hi = min(episodes, lo + max(1, chunk))
        sig, out = sigmas[lo:hi], stats[lo:hi]
        if isinstance(agent, cacla_mod.Cacla):
            _cacla_episodes(
                agent.weights,
                cacla_mod.pack(agent.params),
                pts,
                cum,
                start,
                simp,
                sig,
                n_decisions,
                centres,
                offsets,
                widths,
                normalized,
                agent.rng,
                out,
                env_rng,
                dz,
            )
        else:  # a Sarsa agent (compiled_setup refused the others)
            ac, _, aw = agent.action_grid.packed
            _sarsa_episodes(
                agent.weights,
                agent.params.alpha,
                agent.params.discount,
                agent.search_actions,
                agent.search_psi,
                ac,
                float(aw[0]),
                agent.action_grid.form == "normalized",
                pts,
                cum,
                start,
                simp,
                sig,
                n_decisions,
                centres,
                offsets,
                widths,
                normalized,
                agent.rng,
                out,
                env_rng,
                dz,
            )
        if progress is not None:
            progress(hi)
    agent.begin_episode(sigmas[-1] if episodes else sigma_start)
    return stats


# ---------------------------------------------------------------------------------------------
# Training on a new random pipe every episode (pipeline suites)
