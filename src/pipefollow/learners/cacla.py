"""CACLA (eqs. 5–8), its skew-normal exploration (eqs. 14–15) and supervised CACLA (eqs. 10–13).

All four heads are linear in the same RBF state features φ(s) (paper §4):

* critic ``V(s) = w_V·φ(s)`` (eqs. 5–6), actor mean ``A(s) = w_A·φ(s)`` (eq. 7),
* skew ``γ(s) = w_γ·φ(s)`` (eqs. 14–15, only with ``skew > 0``),
* supervisor trust ``k(s) = w_k·φ(s)`` (eq. 13, only when ``supervised``).

The update rules (the update itself in :mod:`.cacla_update`, the parameter record and the action
in :mod:`.cacla_act`) are compiled functions of plain arrays, so that the agent class below and
the compiled episode loop run the very same code; the
general actor-critic (:mod:`.actor_critic`), CACLA with another actor step factor, runs them and
the agent class too.
Random numbers are drawn by the caller from a ``numpy.random.Generator`` and passed in as standard
normals.
"""

from __future__ import annotations

import json
from collections.abc import Callable

import numpy as np
from numba import njit

from pipefollow.learners.cacla_act import (
    PAPER_CACLA,
    CaclaParams,
    act,
    act_heuristic_packed,
    act_packed,
    pack,
    unpack,
    update_next_packed,
    update_packed,
)
from pipefollow.learners.cacla_update import (
    HEADS,
    REPEAT_VAR,
    SAMPLE_CENTRED,
    SAMPLE_LOCATION,
    SAMPLE_MOMENTS,
    SIGN_AND_MAX,
    A,
    clip1,
    update,
)
from pipefollow.learners.episodes import features_of
from pipefollow.learners.exploration import DEGREES_PER_GAMMA
from pipefollow.learners.heuristic import heuristic_action
from pipefollow.learners.protocol import Agent, LearnerKind
from pipefollow.learners.rbf import STATE_GRID, RBFGrid, grid_features
from pipefollow.learners.sums import dot
from pipefollow.sim import decision as sim
from pipefollow.sim import episode as ep
from pipefollow.sim.observation import observe


class Cacla(Agent):
    """A CACLA agent on RBF features; works on any Gymnasium env with a Box observation.

    It holds the weights (rows :data:`V`, :data:`A`, :data:`G`, :data:`K`: critic, actor mean,
    skew, supervisor trust), draws the exploration's standard normals, caches the features of the
    last update's next state (the usual next action's state) and calls the compiled entry points
    of :mod:`.cacla_act`, so the agent and the compiled loop run the very same code. The actor's step is
    ``rule(params)``, a code of :func:`~pipefollow.learners.cacla_update.step_factor` (the
    actor-critic's agent differs in that alone), the running variance of δ that CACLA+Var updates
    is ``td_var`` and the critic's TD(λ) trace ``critic_trace``.

    Args:
        params: step sizes and options.
        grid: the RBF grid of the observation (default: the paper's 1,764-feature grid).
        rng: generator for exploration noise (or ``seed``).
        seed: seed of a new generator when ``rng`` is None.
        supervisor: ``obs -> a_sup`` for supervised CACLA (default: the paper's heuristic).
    """

    algorithm = "cacla"

    def __init__(
        self,
        params: CaclaParams = PAPER_CACLA,
        grid: RBFGrid = STATE_GRID,
        rng: np.random.Generator | None = None,
        seed: int | None = None,
        supervisor: Callable[[np.ndarray], float] | None = None,
    ) -> None:
        super().__init__(params, grid, rng, seed)
        self.weights = np.zeros((4, grid.n_features))
        self.td_var = np.ones(1)  # running variance of δ of CACLA+Var (var_0 = 1), updated in place
        self.critic_trace = np.zeros(grid.n_features)  # the critic's TD(λ) trace, zero at an episode's start
        self._packed = pack(params)
        self._rule = self.rule(params)
        self._draws = 2 if params.skew > 0.0 else 1  # skew-normal samples take two standard normals
        self.default_supervisor = supervisor is None  # the compiled training loop knows only this one
        if supervisor is None:

            def supervisor(obs):
                return heuristic_action(float(obs[0]), float(obs[1]))

        self.supervisor = supervisor
        self._phi_cache: tuple[bytes, np.ndarray] | None = None  # φ(s') of the last update

    def retune(self, params) -> None:
        """:meth:`Agent.retune`, and the packed record and actor rule the updates read.

        Raises:
            ValueError: ``params`` changes the skew or the supervisor (the heads the weights hold).
        """
        if (params.skew > 0.0) != (self.params.skew > 0.0) or params.supervised != self.params.supervised:
            raise ValueError("a phase may not change the skew or the supervisor of a trained agent")
        super().retune(params)
        self._packed = pack(params)
        self._rule = self.rule(params)

    @staticmethod
    def rule(params) -> int:
        """The actor's step factor: eq. 7's sign and max terms."""
        return SIGN_AND_MAX

    @property
    def name(self) -> str:
        """Short algorithm label."""
        return cacla_label(self.params)

    def begin_episode(self, sigma: float) -> None:
        """Set the exploration σ for the coming episode; forget any pending action and the critic's trace."""
        super().begin_episode(sigma)
        self.critic_trace[:] = 0.0

    @property
    def supervised(self) -> bool:
        """Whether a supervisor shares the actions (eq. 10)."""
        return bool(self.params.supervised)

    def _cached_features(self, obs, key: bytes) -> np.ndarray:
        """φ(obs), reusing φ(s') of the last update when ``obs`` is that s' (the usual case)."""
        cache = self._phi_cache
        if cache is not None and cache[0] == key:
            return cache[1]
        phi = self.features(obs)
        self._phi_cache = (key, phi)
        return phi

    def act(self, obs, explore: bool = True) -> float:
        """Executed action for ``obs``; with ``explore`` it samples with the current ``sigma``."""
        key = _key(obs)
        phi = self._cached_features(obs, key)
        sigma = self.sigma if explore else 0.0
        z0 = z1 = 0.0
        if sigma > 0.0:
            z0 = z1 = self.rng.standard_normal()
            if self._draws == 2:
                z1 = self.rng.standard_normal()
        if self.default_supervisor:
            x = np.asarray(obs, dtype=np.float64)
            a, a_rl, a_sup = act_heuristic_packed(self.weights, phi, sigma, z0, z1, x[0], x[1], self._packed)
        else:
            a_sup = self.supervisor(obs) if self.params.supervised else 0.0
            a, a_rl = act_packed(self.weights, phi, sigma, z0, z1, a_sup, self._packed)
        self._pending = (key, phi, a_rl, a_sup)
        return a

    def actor(self, obs) -> float:
        """The pure actor's deterministic action clip(A(s)), without the supervisor."""
        return clip1(dot(self.weights[A], self.features(obs)))

    def update(self, obs, action, reward: float, next_obs, discount: float) -> float:
        """Learn from ``obs`` → ``next_obs``; ``discount`` is γ_d^n (0 if terminal). Returns δ.

        Uses the learner's own action of the last :meth:`act` call on ``obs``; without one,
        ``action`` is taken as the learner's action.
        """
        key = _key(obs)
        if self._pending is not None and self._pending[0] == key:
            _, phi, a_rl, a_sup = self._pending
        else:
            phi = self._cached_features(obs, key)
            a_rl = float(action)
            a_sup = self.supervisor(obs) if self.params.supervised else 0.0
        self._pending = None
        next_obs = np.asarray(next_obs, dtype=np.float64)
        next_key = next_obs.tobytes()
        cache = self._phi_cache
        w, r, d, hp, rule = self.weights, float(reward), float(discount), self._packed, self._rule
        if cache is not None and cache[0] == next_key:
            return update_packed(
                w, phi, a_rl, a_sup, r, d, cache[1], hp, rule, self.td_var, self.critic_trace
            )
        if next_obs.shape != (self.grid.ndim,):
            raise ValueError(f"next_obs must have {self.grid.ndim} entries, got shape {next_obs.shape}")
        phi_next = np.empty(self.grid.n_features)
        grid, normalized = self.grid.packed, self.grid.form == "normalized"
        state = (self.td_var, self.critic_trace)
        delta, finite = update_next_packed(w, phi, a_rl, a_sup, r, d, next_obs, grid, normalized,
                                           phi_next, hp, rule, *state)  # fmt: skip
        if not finite:
            raise ValueError(f"next_obs must be finite, got {next_obs}")
        self._phi_cache = (next_key, phi_next)
        return delta


def _key(obs) -> bytes:
    """An observation's identity for the caches: its float64 bytes."""
    return np.asarray(obs, dtype=np.float64).tobytes()


SAMPLE_SUFFIX = {SAMPLE_LOCATION: "", SAMPLE_CENTRED: " centred", SAMPLE_MOMENTS: " mean/s.d."}


def cacla_label(p: CaclaParams) -> str:
    """Label such as ``supervised CACLA, skew 22.5°``."""
    name = "supervised CACLA" if p.supervised else "CACLA"
    if p.actor_repeats == REPEAT_VAR:
        name += "+Var"
    if p.critic_lambda > 0.0:
        name += f", TD({p.critic_lambda:g})"
    if p.skew > 0.0:
        name += f", skew {p.skew * DEGREES_PER_GAMMA:g}°" + SAMPLE_SUFFIX[p.skew_sample]
    return name


# ---------------------------------------------------------------------------------------------
# The compiled episodes (the protocol of pipefollow.sim.episode) and what the layers above need


@njit(cache=True)
def episodes(w, hp, rule, var, trace, tracks, run, grid, rng, env_rng, dz, stats, poses):
    """CACLA's episodes in compiled code: the same numbers as its agent in the environment.

    ``rule`` is the actor's step factor (:meth:`Cacla.rule`; the actor-critic's runs here too),
    ``var`` the running variance of δ of CACLA+Var (a one-entry array, updated in place), ``trace``
    the critic's eligibility trace of TD(λ) (set to zero at each episode's start).
    ``rng`` draws the exploration, ``env_rng`` the disturbances (:mod:`pipefollow.sim.episode`).
    """
    p = unpack(hp)
    ps = sim.unpack_params(run.sim)
    decision_s = sim.decision_seconds(ps)
    nf = w.shape[1]
    s = np.empty(sim.STATE_SIZE)
    obs = np.empty(grid.slots.shape[0])  # the observation (pipefollow.sim.observation)
    phi, phi_pend, phi_next = np.empty(nf), np.empty(nf), np.empty(nf)
    # the heads' values on φ(s) from acting, reused by the update of the transition from s: no
    # weight moves in between (the one pending transition is updated before the next action)
    heads, heads_pend = np.empty(HEADS), np.empty(HEADS)
    book = np.empty(ep.BOOK_SIZE)
    skewed = p.skew > 0.0
    n = run.n_decisions
    for e in range(run.sigmas.shape[0]):
        sigma = run.sigmas[e]
        points, cum, start = ep.pipe_of(tracks, e)
        ep.start_episode(s, points, cum, start, ps, env_rng, dz, book, poses, e)
        trace[:] = 0.0
        have_phi = False  # phi already holds φ(s) of the current state (computed for the last update)
        a_rl_p = a_sup_p = 0.0
        for _ in range(n):
            visible = s[sim.IN_VIEW] != 0.0
            a = a_rl = a_sup = 0.0
            if visible:
                if not have_phi:
                    observe(s, grid.slots, obs)
                    grid_features(obs, grid.centres, grid.offsets, grid.widths, grid.normalized, phi)
                z0 = z1 = 0.0
                if sigma > 0.0:
                    z0 = rng.standard_normal()
                    z1 = rng.standard_normal() if skewed else z0
                a_sup = heuristic_action(s[sim.X1], s[sim.Y1]) if p.supervised else 0.0
                a, a_rl = act(w, phi, sigma, z0, z1, a_sup, p, heads)
            have_phi = False
            r = ep.draw_and_decide(s, a, points, cum, ps, env_rng, dz, book, poses, e)
            end = ep.end_of(book, s, cum, ps, n)
            if run.learn:
                ep.carry(book, visible, r, p.discount)
                if visible:
                    phi, phi_pend = phi_pend, phi  # keep φ(s) for the update; no copy
                    heads, heads_pend = heads_pend, heads
                    a_rl_p, a_sup_p = a_rl, a_sup
                if ep.due(book, s[sim.IN_VIEW] != 0.0, end != ep.GOES_ON):
                    observe(s, grid.slots, obs)
                    grid_features(obs, grid.centres, grid.offsets, grid.widths, grid.normalized, phi_next)
                    disc = ep.bootstrap(book, end)
                    update(w, phi_pend, a_rl_p, a_sup_p, book[ep.ACC], disc, phi_next, p, rule, var, trace,
                           heads_pend)  # fmt: skip
                    book[ep.PENDING] = 0.0
                    phi, phi_next = phi_next, phi  # φ(s') is the next decision's φ(s)
                    have_phi = True
            if end == ep.PIPE_END:
                break
        ep.hold_poses(poses, e, book)
        ep.close_episode(stats, e, book, s[sim.PROGRESS_MAX], decision_s)


def check_compiled(agent: Cacla) -> None:
    """Refuse what the compiled loop cannot run: a supervisor other than the paper's heuristic.

    Raises:
        TypeError: a custom supervisor.
    """
    if agent.params.supervised and not agent.default_supervisor:
        raise TypeError(
            "the compiled loop supervises with the heuristic only; use train() for other supervisors"
        )


def run_compiled(agent: Cacla, tracks, run, env_rng, dz, stats, poses) -> None:
    """:func:`episodes` for ``agent`` (a CACLA or an actor-critic agent)."""
    grid = features_of(agent.grid, agent.state)
    episodes(agent.weights, pack(agent.params), agent.rule(agent.params), agent.td_var, agent.critic_trace,
             tracks, run, grid, agent.rng, env_rng, dz, stats, poses)  # fmt: skip


def policy_fields(agent: Cacla) -> dict:
    """The arrays of a policy file: parameters and grid as JSON, the weights (and CACLA+Var's variance)."""
    params = {k: (bool(v) if isinstance(v, bool) else v) for k, v in agent.params._asdict().items()}
    for k in ("actor_repeats", "var_rate", "critic_lambda"):  # options beyond the paper: only when set,
        if params[k] == getattr(PAPER_CACLA, k):  # so that files of the paper's learners read as before
            del params[k]
    fields = {
        "params": np.array(json.dumps(params)),
        "grid": np.array(json.dumps(agent.grid.to_dict())),
        "weights": agent.weights,
    }
    if agent.params.actor_repeats == REPEAT_VAR:
        fields["td_var"] = agent.td_var
    return fields


def from_policy(
    data: dict,
    seed: int | None = None,
    agent_class: type | None = None,
    params_class: type = CaclaParams,
):
    """An agent and its weights from a policy file's arrays (see :func:`policy_fields`)."""
    params = json.loads(str(data["params"]))
    grid = RBFGrid.from_dict(json.loads(str(data["grid"])))
    weights = np.asarray(data["weights"], dtype=np.float64)
    agent = (agent_class or Cacla)(params_class(**params), grid=grid, seed=seed)
    agent.readings = str(data.get("readings", "default"))
    if "td_var" in data:  # CACLA+Var's running variance of δ, for training on
        agent.td_var[...] = np.asarray(data["td_var"], dtype=np.float64).reshape(1)
    return agent, weights


def make(params: CaclaParams, grid: RBFGrid, rng: np.random.Generator | None = None, *,
         readings: str = "default", agent_class: type | None = None) -> Cacla:  # fmt: skip
    """A fresh CACLA agent (or ``agent_class``) with ``params`` on ``grid``, readings id ``readings``."""
    agent = (agent_class or Cacla)(params, grid=grid, rng=rng)
    agent.readings = readings
    return agent


LEARNER = LearnerKind(
    name="cacla",
    title="CACLA",
    summary="CACLA (eqs. 5-8; skew-normal exploration eqs. 14-15; supervised eqs. 10-13)",
    agent_class=Cacla,
    options=frozenset({"skew_deg", "supervised", "actor_repeats", "critic_lambda"}),
    step_sizes={
        "alpha_v": "alpha_v",
        "alpha_pi": "alpha_pi",
        "discount": "discount",
        "delta_k": "delta_k",
        "forgetting": "forgetting",
        "var_rate": "var_rate",
    },  # fmt: skip
    make=make,
    check=check_compiled,
    run=run_compiled,
    policy_fields=policy_fields,
    from_policy=from_policy,
)
