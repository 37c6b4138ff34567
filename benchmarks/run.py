"""Benchmarks: medians of the hot paths, each beside its floor and target, in one run.

Usage: ``python benchmarks/run.py [--repeats N] [--no-reproduce] [--cold] [--readings] [--json FILE]``
(``--json``: the record of ``stored.py``, with the load and the machine; ``docs/speed/run.json``).

The floors are estimates of what compiled C would need (issue "Speed near the physical limit"):
an RK4 substep ≈ 0.09 µs; a 500-episode trial is 200,000 substeps plus 10,000 learning updates,
so ≥ 0.04 s for CACLA and ≥ 0.1 s for SARSA; the 35-trial reproduction ≈ 1-2 s of compute on
2 cores (we take 1.5 s). Times are medians over repeats; compare ratios within one run, as the
machine is shared and noisy.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np


def median_time(fn, repeats: int, inner: int = 1) -> float:
    """Median over ``repeats`` of the time per call of ``fn`` (called ``inner`` times per repeat)."""
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        for _ in range(inner):
            fn()
        times.append((time.perf_counter() - t) / inner)
    return statistics.median(times)


def bench_substep(repeats):
    from numba import njit

    from pipefollow.sim import decision as sim

    @njit(cache=False)
    def substeps(s, n, p):
        for _ in range(n):
            sim.closed_loop_rk4(s, 3.0, 0.5, 0.0, True, p.dt, p)

    s = np.zeros(sim.STATE_SIZE)
    n = 100_000
    substeps(s, 10, sim.PAPER_SIM)
    return median_time(lambda: substeps(s, n, sim.PAPER_SIM), repeats) / n


def bench_env_step(repeats):
    import gymnasium as gym

    import pipefollow.envs  # noqa: F401  (registers the environment)

    # a day's episode: the id's TimeLimit (20 steps) is raised to it
    env = gym.make("pipefollow/PipelineFollowing-v0", episode_seconds=86_400, max_episode_steps=86_400)
    env.reset(seed=0)
    action = np.array([0.1], dtype=np.float32)
    env.step(action)
    return median_time(_stepper(env, action), repeats, inner=2000)


def _stepper(env, action):
    """One ``env.step``; at the pipe's end (79 decisions on paper-left) a new episode, its reset timed too.

    Without the reset almost every timed step came after the episode's end, the pipe out of view.
    """

    def step():
        if env.step(action)[2]:
            env.reset()

    return step


NOTES: list[str] = []


def bench_env_step_disturbed(repeats):
    """A current of 0.1 m/s and camera noise of 0.05 m, timed in turns with a plain environment.

    The shared machine's load moves by tens of percent within seconds, so the cost ratio is the
    median of the per-repeat ratios of the two, measured back to back.
    """
    import gymnasium as gym

    import pipefollow.envs  # noqa: F401  (registers the environment)
    from pipefollow.sim.disturbance import make_disturbance

    dist = make_disturbance(0.1, 45.0, camera_noise=0.05)
    envs = [
        gym.make(
            "pipefollow/PipelineFollowing-v0", episode_seconds=86_400, max_episode_steps=86_400, disturbance=d
        )
        for d in (None, dist)
    ]
    action = np.array([0.1], dtype=np.float32)
    for env in envs:
        env.reset(seed=0)
        env.step(action)
    plain, disturbed = [], []
    steps = [_stepper(env, action) for env in envs]
    for _ in range(repeats):
        plain.append(median_time(steps[0], 1, inner=2000))
        disturbed.append(median_time(steps[1], 1, inner=2000))
    ratio = statistics.median(d / p for d, p in zip(disturbed, plain, strict=True))
    NOTES.append(
        f"env.step with current + camera noise / plain, paired: {ratio:.3f} "
        f"(plain {statistics.median(plain) * 1e6:.2f} µs in the same turns)"
    )
    return statistics.median(disturbed)


def bench_features(repeats):
    from pipefollow.learners.rbf import STATE_GRID

    x = np.array([0.3, 2.1, -0.2, 0.35])
    out = np.empty(STATE_GRID.n_features)
    STATE_GRID.features(x, out)
    return median_time(lambda: STATE_GRID.features(x, out), repeats, inner=5000)


def _decision_bench(agent, repeats):
    rng = np.random.default_rng(1)
    obs = [rng.uniform([-1, 0, -1, 0], [1, 3, 1, 0.5]) for _ in range(64)]
    state = {"i": 0}

    def one():
        i = state["i"] = (state["i"] + 1) % 63
        a = agent.act(obs[i])
        agent.update(obs[i], a, -0.3, obs[i + 1], 0.8)

    one()
    return median_time(one, repeats, inner=1000)


def bench_cacla_decision(repeats):
    from pipefollow.training.agents import make_agent

    return _decision_bench(
        make_agent("cacla", skew_deg=22.5, supervised=True, rng=np.random.default_rng(0)), repeats
    )


def bench_sarsa_decision(repeats):
    from pipefollow.training.agents import make_agent

    return _decision_bench(make_agent("sarsa", rng=np.random.default_rng(0)), repeats)


def _trial_bench(algorithm, repeats, **kw):
    from pipefollow.sim.pipeline import builtin
    from pipefollow.training.agents import make_agent
    from pipefollow.training.compiled import train_compiled

    pipe = builtin("paper-left")
    train_compiled(make_agent(algorithm, rng=np.random.default_rng(0), **kw), pipe, 2)  # compile

    def one():
        train_compiled(make_agent(algorithm, rng=np.random.default_rng(0), **kw), pipe, 500, chunk=500)

    return median_time(one, max(3, repeats // 3))


def bench_render_frame(repeats):
    """One ``env.render()`` in rgb_array mode (the Fig. 2 view), mid-episode, with its trail."""
    from pipefollow.envs.env import PipelineFollowingEnv
    from pipefollow.learners.heuristic import Heuristic

    env = PipelineFollowingEnv("paper-validation", episode_seconds=60, render_mode="rgb_array")
    obs, _ = env.reset(seed=0)
    agent = Heuristic()
    for _ in range(30):  # half-way: a trail of 30 decisions
        obs, *_ = env.step([agent.act(obs)])
    env.render()  # the first frame builds the figure
    return median_time(env.render, repeats, inner=5)


def bench_reproduce(repeats, extra=(), runs=None, cold=False):
    """Wall time of ``pipefollow reproduce --no-figures``, a fresh process (``cold``: an empty cache)."""
    exe = os.path.join(os.path.dirname(sys.executable), "pipefollow")
    times = []
    for _ in range(runs or max(1, repeats // 5)):
        with tempfile.TemporaryDirectory() as out, tempfile.TemporaryDirectory() as cache:
            env = dict(os.environ, NUMBA_CACHE_DIR=cache) if cold else None
            t = time.perf_counter()
            subprocess.run(
                [exe, "reproduce", "--out", out, "--no-figures", *extra],
                check=True,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                env=env,
            )
            times.append(time.perf_counter() - t)
    return statistics.median(times)


def bench_suite_benchmark(repeats):
    """``pipefollow benchmark`` of a CACLA policy: 100 held-out pipes × 60 s, heuristic and CIs included."""
    from pipefollow.evaluation.benchmark import benchmark
    from pipefollow.sim.suites import get_suite
    from pipefollow.training.agents import make_agent
    from pipefollow.training.random_pipes import train_random_compiled

    agent = make_agent("cacla", rng=np.random.default_rng(0))
    rng = np.random.default_rng(1)
    train_random_compiled(agent, get_suite("mixed"), 200, pipe_rng=rng, episode_seconds=60)
    suite = get_suite("heldout")
    benchmark(agent, suite, controller="cacla")  # compile
    return median_time(lambda: benchmark(agent, suite, controller="cacla"), max(3, repeats // 3))


def bench_random_training(repeats):
    """CACLA on a new pipe of the mixed family every episode: 2,500 episodes × 40 s = 100,000 decisions."""
    from pipefollow.sim.suites import get_suite
    from pipefollow.training.agents import make_agent
    from pipefollow.training.random_pipes import train_random_compiled

    suite = get_suite("mixed")

    def one(episodes=2500):
        agent = make_agent("cacla", rng=np.random.default_rng(0))
        train_random_compiled(agent, suite, episodes, pipe_rng=np.random.default_rng(1), episode_seconds=40)

    one(2)  # compile
    return median_time(one, max(3, repeats // 5))


def _train_through(camera, repeats):
    """CACLA trained through ``camera`` in the environment (training.through_env): time per decision.

    200 episodes × 10 s on the mixed family (2,000 decisions) a repeat; ``camera`` None is the
    compiled loop on the same pipes' family, for the ratio.
    """
    from pipefollow import readings as rd
    from pipefollow.training.phases import train_phases
    from pipefollow.training.runs import new_agent

    def one(episodes=200):
        agent = new_agent("cacla", 0, rd.DEFAULT)
        train_phases(agent, [("random:mixed", episodes)], seed=0, episode_seconds=10.0, camera=camera)

    one(2)  # compile, load the textures' bank
    return median_time(one, max(3, repeats // 5)) / 2000


def bench_vector_env(repeats):
    """One step of the batched vector env with 64 AUVs, timed in turns with 64 single ``env.step`` calls."""
    import gymnasium as gym

    import pipefollow.envs  # noqa: F401  (registers the environment)

    n = 64
    mode = "vector_entry_point"
    day = {"episode_seconds": 86_400, "max_episode_steps": 86_400}
    vec = gym.make_vec("pipefollow/PipelineFollowing-v0", n, vectorization_mode=mode, **day)
    vec.reset(seed=0)
    single = gym.make("pipefollow/PipelineFollowing-v0", **day)
    single.reset(seed=0)
    actions = np.full((n, 1), 0.1, dtype=np.float32)
    action = actions[0]
    vec.step(actions), single.step(action)

    def sixty_four():
        for _ in range(n):
            single.step(action)

    batched, singles = [], []
    for _ in range(repeats):
        batched.append(median_time(lambda: vec.step(actions), 1, inner=50))
        singles.append(median_time(sixty_four, 1, inner=50))
    ratio = statistics.median(b / s for b, s in zip(batched, singles, strict=True))
    NOTES.append(
        f"vector env, 64 AUVs: one batched step / 64 single env.step, paired: {ratio:.3f} (target ≤ 0.333; "
        f"batched {statistics.median(batched) * 1e6:.0f} µs = {statistics.median(batched) / n * 1e6:.2f} µs "
        f"per AUV, single {statistics.median(singles) / n * 1e6:.2f} µs)"
    )
    return statistics.median(batched)


def bench_mlp_benchmark(repeats):
    """Compiled benchmark episodes (100 held-out pipes × 60 s) of a 64×64 MLP policy, in turns with CACLA."""
    from pipefollow.evaluation.benchmark import run_episodes
    from pipefollow.learners.mlp import MLPPolicy
    from pipefollow.sim.suites import get_suite, min_length_for
    from pipefollow.training.agents import make_agent

    rng = np.random.default_rng(0)
    sizes = [4, 64, 64, 1]
    mlp = MLPPolicy(
        [rng.normal(size=(o, i)) / np.sqrt(i) for i, o in zip(sizes[:-1], sizes[1:], strict=True)],
        [rng.normal(size=o) * 0.1 for o in sizes[1:]],
        ["tanh", "tanh", "identity"],
    )
    cacla = make_agent("cacla", rng=np.random.default_rng(0))
    cacla.weights[:] = rng.normal(size=cacla.weights.shape) * 0.1
    pipes = get_suite("heldout").pipes(None, min_length_for(60.0))
    run_episodes(mlp, pipes, 60.0), run_episodes(cacla, pipes, 60.0)  # compile
    t_mlp, t_cacla = [], []
    for _ in range(repeats):
        t_mlp.append(median_time(lambda: run_episodes(mlp, pipes, 60.0), 1))
        t_cacla.append(median_time(lambda: run_episodes(cacla, pipes, 60.0), 1))
    ratio = statistics.median(m / c for m, c in zip(t_mlp, t_cacla, strict=True))
    NOTES.append(
        f"benchmark episodes, MLP 64×64 / CACLA policy, paired: {ratio:.3f} (target ≤ 2; "
        f"CACLA {statistics.median(t_cacla) * 1e3:.1f} ms for 6,000 decisions)"
    )
    return statistics.median(t_mlp)


def bench_ppo_throughput(repeats):
    """PPO, 16,384 steps with the default settings (8 environments), on the vector env vs DummyVecEnv."""
    try:
        import torch
        from stable_baselines3.common.utils import set_random_seed
        from stable_baselines3.common.vec_env import DummyVecEnv, VecMonitor
    except ImportError:
        NOTES.append("PPO throughput: skipped (extra 'deep' not installed)")
        return float("nan")
    from pipefollow.envs.env import PipelineFollowingEnv
    from pipefollow.envs.vector_env import PipelineFollowingVectorEnv
    from pipefollow.training import deep

    hp = deep.hyperparameters("ppo")
    steps = 16_384
    torch.set_num_threads(1)

    def train(kind):
        set_random_seed(0)
        if kind == "vector":
            env = deep.SB3VecEnv(PipelineFollowingVectorEnv(hp["n_envs"], "random:mixed", episode_seconds=90))
        else:
            env = DummyVecEnv([lambda: PipelineFollowingEnv("random:mixed", 90) for _ in range(hp["n_envs"])])
        model = deep.make_model("ppo", VecMonitor(env), hp, seed=0)
        t = time.perf_counter()
        model.learn(total_timesteps=steps)
        return steps / (time.perf_counter() - t)

    train("vector"), train("dummy")  # warm up
    vec, dummy = [], []
    for _ in range(max(3, repeats // 5)):
        vec.append(train("vector"))
        dummy.append(train("dummy"))
    ratio = statistics.median(v / d for v, d in zip(vec, dummy, strict=True))
    NOTES.append(
        f"PPO steps/s, vector env / DummyVecEnv, paired: {ratio:.3f} (target ≥ 1; "
        f"{statistics.median(vec):.0f} vs {statistics.median(dummy):.0f} steps/s, 8 envs, 1 torch thread)"
    )
    return 1.0 / statistics.median(vec)


# name, function, floor (s), target (s), unit for display
BENCHES = [
    ("RK4 substep (closed loop)", bench_substep, 0.09e-6, None),
    ("env.step (1-s decision)", bench_env_step, 20 * 0.09e-6, 15e-6),
    ("env.step, current + cam. noise", bench_env_step_disturbed, 20 * 0.09e-6, 15e-6),
    ("RBF features, 1,764", bench_features, None, 5e-6),
    ("CACLA decision (act+update)", bench_cacla_decision, None, 10e-6),
    ("SARSA decision (act+update)", bench_sarsa_decision, None, 40e-6),
    ("CACLA trial, 500 episodes", lambda r: _trial_bench("cacla", r), 0.04, 0.1),
    (
        "supervised skew CACLA trial",
        lambda r: _trial_bench("cacla", r, skew_deg=22.5, supervised=True),
        0.04,
        0.1,
    ),
    ("SARSA trial, 500 episodes", lambda r: _trial_bench("sarsa", r), 0.1, 0.3),
    ("benchmark, 100 pipes × 60 s", bench_suite_benchmark, None, 1.0),
    ("random-pipe CACLA, 100k dec.", bench_random_training, None, 3.0),
    ("CACLA training, compiled, per dec.", lambda r: _train_through(None, r), None, None),
    ("…through the env, ideal, per dec.", lambda r: _train_through({"camera": "ideal"}, r), None, None),
    (
        "…through fused, turbid, per dec.",
        lambda r: _train_through({"camera": "vision", "sensor": "fused", "water": "turbid"}, r),
        None,
        None,
    ),
    ("render one frame (rgb_array)", bench_render_frame, None, 30e-3),
    ("vector env step, 64 AUVs", bench_vector_env, 64 * 20 * 0.09e-6, 64 * 3e-6),
    ("benchmark episodes, MLP 64×64", bench_mlp_benchmark, None, None),
    ("PPO (SB3), time per step", bench_ppo_throughput, None, None),
    ("pipefollow reproduce (warm)", bench_reproduce, 1.5, 8.0),
    # one run with an empty compile cache (compiling dominates: a minute of CPU); opt in with --cold
    ("pipefollow reproduce (cold)", lambda r: bench_reproduce(r, runs=1, cold=True), None, 15.0),
    # 13 training readings × 8 trials × 10 repeats (1,040 trials); opt in with --readings
    (
        "reproduce --experiment readings",
        lambda r: bench_reproduce(r, ("--experiment", "readings"), runs=1),
        None,
        180.0,
    ),
]


def fmt(seconds: float) -> str:
    """Human units."""
    if seconds < 1e-3:
        return f"{seconds * 1e6:8.2f} µs"
    if seconds < 1.0:
        return f"{seconds * 1e3:8.2f} ms"
    return f"{seconds:8.2f} s "


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=15, help="repeats per benchmark (median)")
    ap.add_argument("--no-reproduce", action="store_true", help="skip the full-reproduction benchmark")
    ap.add_argument("--readings", action="store_true", help="also time the readings experiment (minutes)")
    ap.add_argument("--cold", action="store_true", help="also time one reproduce with an empty compile cache")
    ap.add_argument("--json", help="also write the figures, the load and the machine to this JSON file")
    ap.add_argument("--only", metavar="TEXT", help="run only the benchmarks whose name contains TEXT")
    args = ap.parse_args(argv)
    import stored

    load_before = stored.load_average()
    print(
        f"# {time.strftime('%Y-%m-%d')} · {platform.processor() or platform.machine()} · "
        f"{os.cpu_count()} cores · Python {platform.python_version()}"
    )
    print(f"{'benchmark':<32}{'median':>12}{'floor':>12}{'×floor':>8}{'target':>12}  ok")
    results = {}
    for name, fn, floor, target in BENCHES:
        if (args.no_reproduce and "reproduce" in name) or ("readings" in name and not args.readings):
            continue
        if "cold" in name and not args.cold:
            continue
        if args.only and args.only not in name:
            continue
        t = fn(args.repeats)
        results[name] = {"median_s": t, "floor_s": floor, "target_s": target}
        ratio = f"{t / floor:7.1f}×" if floor else " " * 8
        ok = "" if target is None else ("yes" if t <= target else "NO")
        print(
            f"{name:<32}{fmt(t):>12}{fmt(floor) if floor else '':>12}{ratio}"
            f"{fmt(target) if target else '':>12}  {ok}",
            flush=True,
        )
    for note in NOTES:
        print(note)
    if args.json:
        rows = [(name, r["median_s"], r["target_s"], r["floor_s"]) for name, r in results.items()]
        stored.write(args.json, "run", "wall", args.repeats, load_before, rows, NOTES)
    return 0


if __name__ == "__main__":
    sys.exit(main())
