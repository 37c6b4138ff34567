"""Benchmarks of the vision camera: render, detect, env.step and reset beside the ideal camera, the tracker.

Usage: ``python benchmarks/vision.py [--repeats N] [--cpu] [--json FILE]`` (``--json``: the record
of ``stored.py``, with the load and the machine; ``docs/speed/vision.json``)

Frames are taken along a heuristic episode on a held-out pipe (clear water, 64 × 96). Times are
medians over repeats of blocks of calls; render, detect and the two together are timed in turns,
and so are the two env.step lines (the machine is shared: compare within one run).
"""

from __future__ import annotations

import argparse
import math
import platform
import statistics
import time

import numpy as np

CLOCK = time.perf_counter  # or time.process_time (--cpu): the process's CPU time, which waiting for
# a core on a shared machine does not inflate


def blocks(fn, repeats: int, inner: int) -> list[float]:
    out = []
    for _ in range(repeats):
        t = CLOCK()
        for _ in range(inner):
            fn()
        out.append((CLOCK() - t) / inner)
    return out


def reset_rows(gym, pipe, ideal_step, repeats: int) -> list[tuple[str, float, str]]:
    """``reset`` of vision and image environments beside ``env.step`` of the ideal camera, in turns.

    "same seed" resets with one of three seeds in turn, so a scene's textures come from the cache
    (perception.textures.TextureCache); "new seed" resets with a seed never used before, so they are
    made from the texture banks (clear water: the growth tile left blank; "with marine growth": the
    growth tile made too). The banks themselves are made once per process, timed once at the end.
    """
    from pipefollow.perception import textures

    def make(**kw):
        return gym.make("pipefollow/PipelineFollowing-v0", pipeline=pipe, **kw).unwrapped

    vision, image = make(camera="vision"), make(observation="image")
    grown = make(camera="vision", water={"preset": "clear", "growth": 0.3})
    seeds = iter(range(10, 10**9))
    same = iter(range(10**9))
    cases = {
        "reset, vision camera, a seed seen before (cached)": lambda: vision.reset(seed=next(same) % 3),
        "reset, vision camera, a new seed": lambda: vision.reset(seed=next(seeds)),
        "reset, vision camera with marine growth, a new seed": lambda: grown.reset(seed=next(seeds)),
        "reset, image observation (ideal camera), a new seed": lambda: image.reset(seed=next(seeds)),
        "env.step, ideal camera (beside the resets)": ideal_step,
    }
    for fn in cases.values():
        fn(), fn()
    times: dict[str, list[float]] = {name: [] for name in cases}
    for _ in range(repeats):
        for name, fn in cases.items():
            times[name] += blocks(fn, 1, 200 if fn is ideal_step else 10)
    rows = [(name, statistics.median(t), "" if "step" in name else "≤ 1 ms") for name, t in times.items()]
    textures.bank.cache_clear()
    t = CLOCK()
    textures.bank("seabed"), textures.bank("growth")
    rows.append(("texture banks, made once per process (one call)", CLOCK() - t, ""))
    return rows


def tracker_rows(repeats: int) -> list[tuple[str, float, str]]:
    """The tracker per decision: the compiled step; with the navigation and the memory; without the memory."""
    from pipefollow.perception.track_step import track_step
    from pipefollow.perception.tracker import PipeTracker

    t, line = PipeTracker(), PipeTracker(memory=None)
    t.reset(np.random.default_rng(0), (0.0, 0.0, 0.0))
    line.reset(np.random.default_rng(0), (0.0, 0.0, 0.0))
    k = iter(range(10**9))
    motion, det = np.array([0.0, 0.5, 0.01]), np.array([0.1, 3.0, 0.05, 0.0])

    def compiled():
        i = next(k)
        track_step(t.state, i % 7 != 0, det, motion, t.navigation.variances, t._tp, 1.0, 3.0, t.out)

    def whole():
        i = next(k)
        t.step((0.5 * i, 0.0, 0.01 * i), i % 7 != 0, (0.1, 3.0, 0.05, 0.0))

    def alone():
        i = next(k)
        line.step((0.5 * i, 0.0, 0.01 * i), i % 7 != 0, (0.1, 3.0, 0.05, 0.0))

    compiled(), whole(), alone()
    tc, tw, ta = [], [], []
    for _ in range(repeats):
        tc += blocks(compiled, 1, 2000)
        tw += blocks(whole, 1, 2000)
        ta += blocks(alone, 1, 2000)
    return [
        ("tracker, compiled step (track_step)", statistics.median(tc), "≤ 0.02 ms"),
        ("tracker, one decision (navigation + track_step + memory)", statistics.median(tw), "≤ 0.02 ms"),
        ("tracker, one decision without its memory", statistics.median(ta), ""),
    ]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--cpu", action="store_true", help="CPU time (time.process_time), not wall time.")
    parser.add_argument("--json", default=None, help="also write the figures, the load and the machine here")
    args = parser.parse_args()
    import stored

    load_before = stored.load_average()
    global CLOCK
    if args.cpu:
        CLOCK = time.process_time
    import cv2
    import gymnasium as gym

    import pipefollow.envs  # noqa: F401 (registers the environment)
    from pipefollow.envs.vector_env import PipelineFollowingVectorEnv
    from pipefollow.perception.detector import detect_pipe
    from pipefollow.perception.image import Renderer
    from pipefollow.perception.textures import make_textures
    from pipefollow.perception.water import CLEAR
    from pipefollow.sim import decision as sim
    from pipefollow.sim.suites import get_suite, min_length_for

    pipe = get_suite("heldout").pipes(1, min_length_for(600.0))[0]
    # poses along a heuristic episode (ideal camera)
    env = gym.make("pipefollow/PipelineFollowing-v0", pipeline=pipe, episode_seconds=600.0).unwrapped
    obs, _ = env.reset(seed=0)
    poses = []
    for _ in range(200):
        poses.append((env.state[sim.X], env.state[sim.Y], env.state[sim.PSI]))
        obs, *_ = env.step([math.atan2(obs[0], obs[1]) / (0.5 * math.pi)])
    rng = np.random.default_rng(0)
    tex = make_textures(rng)
    renderer = Renderer(CLEAR)
    out = np.empty((CLEAR.height, CLEAR.width), np.uint8)
    images = [renderer.render(pipe.points, pipe.cumulative, p, tex, rng).copy() for p in poses]
    it = iter(range(10**9))

    def render():
        renderer.render(pipe.points, pipe.cumulative, poses[next(it) % 200], tex, rng, out=out)

    def detect():
        detect_pipe(images[next(it) % 200])

    def both():
        k = next(it) % 200
        renderer.render(pipe.points, pipe.cumulative, poses[k], tex, rng, out=out)
        detect_pipe(out)

    rows = []
    # in turns, so the three meet the same load and render + detect can be compared with the sum
    stages = (("render", render), ("detect_pipe", detect), ("render + detect (one decision)", both))
    times: dict[str, list[float]] = {name: [] for name, _ in stages}
    for _, fn in stages:
        fn()
    for _ in range(args.repeats):
        for name, fn in stages:
            times[name] += blocks(fn, 1, 200)
    for name, _ in stages:
        rows.append((name, statistics.median(times[name]), "≤ 0.3 ms" if "+" in name else ""))

    def stepper(camera):
        """One decision of the heuristic following the pipe (the pipe in view, as in a real run)."""
        e = gym.make(
            "pipefollow/PipelineFollowing-v0", pipeline=pipe, episode_seconds=600.0, max_episode_steps=600,
            camera=camera,
        )  # fmt: skip
        last = list(e.reset(seed=0))

        def step():
            obs, info = last[0], last[-1]
            a = math.atan2(obs[0], obs[1]) / (0.5 * math.pi) if info["pipe_in_view"] else 0.0
            obs, _, terminated, truncated, info = e.step([a])
            last[:] = e.reset() if terminated or truncated else (obs, info)

        return step

    ideal, vision, raw = stepper("ideal"), stepper("vision"), stepper("vision-raw")
    ideal(), vision(), raw()
    ti, tv, tr = [], [], []
    for _ in range(args.repeats):  # in turns, so all meet the same load
        ti += blocks(ideal, 1, 200)
        tv += blocks(vision, 1, 200)
        tr += blocks(raw, 1, 200)
    rows.append(("env.step, ideal camera", statistics.median(ti), ""))
    rows.append(("env.step, vision camera (detector + tracker)", statistics.median(tv), "≤ 0.4 ms"))
    rows.append(("env.step, vision-raw camera (detector alone)", statistics.median(tr), ""))
    rows += reset_rows(gym, pipe, ideal, args.repeats)
    rows += tracker_rows(args.repeats)
    vec = PipelineFollowingVectorEnv(16, pipe, episode_seconds=86_400.0, camera="vision")
    vec.reset(seed=0)
    zeros = np.zeros(16)
    tvec = blocks(lambda: vec.step(zeros), args.repeats, 20)
    rows.append(("vector env, 16 AUVs, vision camera, per AUV", statistics.median(tvec) / 16, ""))
    print(f"{platform.machine()}, Python {platform.python_version()}, OpenCV {cv2.__version__}")
    print(f"{args.repeats} repeats, {'CPU' if args.cpu else 'wall'} time")
    print("| benchmark | median | target |\n|---|---|---|")
    for name, t, target in rows:
        ok = ""
        if target:
            limit = float(target.split()[1]) * 1e-3
            ok = " ✓" if t <= limit else " ✗"
        print(f"| {name} | {t * 1e3:.3f} ms | {target}{ok} |")
    if args.json:
        limit = [float(target.split()[1]) * 1e-3 if target else None for _, _, target in rows]
        rows = [(name, t, lim, None) for (name, t, _), lim in zip(rows, limit, strict=True)]
        stored.write(args.json, "vision", "CPU" if args.cpu else "wall", args.repeats, load_before, rows)


if __name__ == "__main__":
    main()
