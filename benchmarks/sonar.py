"""Benchmarks of the sonars: render a ping, detect the pipe, track it; env.step with and without them.

Usage: ``python benchmarks/sonar.py [--repeats N] [--cpu] [--json FILE]`` (``--json``: the record of
``stored.py``, with the load and the machine; ``docs/speed/sonar.json``)

Poses are taken along a heuristic episode on a held-out pipe (ideal camera); the sonar is
``LOOK_AHEAD_SONAR`` (128 beams over ±60°, 3 rays a beam, 1 cm noise and quantisation, the fan
tilted 45° forward), the sensor's default; the forward-looking imaging sonar is ``FLS`` (128 beams
over 130°, 88 range bins of 2.5 cm, speckle) with its detector and map (``sensor="fls"``). Each line
is the median
of N blocks of 200 calls; all lines are timed in turns in the same run, so they meet the same load
(the machine is shared: compare within one run).
"""

from __future__ import annotations

import argparse
import math
import platform
import statistics
import time

import numpy as np

CLOCK = time.perf_counter  # or time.process_time (--cpu)


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
    import gymnasium as gym
    import numba

    import pipefollow.envs  # noqa: F401 (registers the environment)
    from pipefollow.perception.imaging_detect import detect_image
    from pipefollow.perception.imaging_sonar import FLS, bearings, bin_ranges, render_image
    from pipefollow.perception.imaging_track import ImagingMap, ImagingSensor
    from pipefollow.perception.sonar import LOOK_AHEAD_SONAR, beam_angles, fan_line, render_ping
    from pipefollow.perception.sonar_detect import detect_profile
    from pipefollow.perception.sonar_track import SonarSensor, SonarTrack
    from pipefollow.sim import decision as sim
    from pipefollow.sim.suites import get_suite, min_length_for

    pipe = get_suite("heldout").pipes(1, min_length_for(600.0))[0]
    env = gym.make("pipefollow/PipelineFollowing-v0", pipeline=pipe, episode_seconds=600.0).unwrapped
    obs, _ = env.reset(seed=0)
    poses = []
    for _ in range(200):
        poses.append((env.state[sim.X], env.state[sim.Y], env.state[sim.PSI]))
        obs, *_ = env.step([math.atan2(obs[0], obs[1]) / (0.5 * math.pi)])
    rng = np.random.default_rng(0)
    sonar = LOOK_AHEAD_SONAR
    angles, out = beam_angles(sonar), np.empty(sonar.n_beams)
    pings = [render_ping(pipe.points, pipe.cumulative, p, rng, sonar) for p in poses]
    track = SonarTrack(fan_line(sonar))
    sensor = SonarSensor(sonar)
    it = iter(range(10**9))

    def render():
        render_ping(pipe.points, pipe.cumulative, poses[next(it) % 200], rng, sonar, angles=angles, out=out)

    def detect():
        detect_profile(pings[next(it) % 200])

    fixes = [detect_profile(p) for p in pings]

    def follow():
        k = next(it) % 200
        track.update(poses[k], fixes[k])

    def decision():
        sensor.step(pipe.points, pipe.cumulative, poses[next(it) % 200], rng)

    fls_angles, fls_ranges = bearings(FLS), bin_ranges(FLS)
    fls_out = np.empty((FLS.n_beams, fls_ranges.size))
    images = [render_image(pipe.points, pipe.cumulative, p, rng) for p in poses]
    pieces = [detect_image(im, angles=fls_angles, ranges=fls_ranges) for im in images]
    fls_map = ImagingMap()
    fls_sensor = ImagingSensor()

    def fls_render():
        p = poses[next(it) % 200]
        render_image(pipe.points, pipe.cumulative, p, rng, angles=fls_angles, out=fls_out)

    def fls_detect():
        detect_image(images[next(it) % 200], angles=fls_angles, ranges=fls_ranges)

    def fls_map_update():
        k = next(it) % 200
        fls_map.update(poses[k], pieces[k])

    def fls_decision():
        fls_sensor.step(pipe.points, pipe.cumulative, poses[next(it) % 200], rng)

    def stepper(**kwargs):
        """One decision of the heuristic following the pipe (as in a real run) with the given sensor."""
        e = gym.make("pipefollow/PipelineFollowing-v0", pipeline=pipe, episode_seconds=600.0, **kwargs)
        last = list(e.reset(seed=0))

        def step():
            o, info = last[0], last[-1]
            a = math.atan2(o[0], o[1]) / (0.5 * math.pi) if info["pipe_in_view"] else 0.0
            o, _, terminated, truncated, info = e.step([a])
            last[:] = e.reset() if terminated or truncated else (o, info)

        return step

    stages = (
        ("render_ping (128 beams)", render, ""),
        ("detect_profile", detect, ""),
        ("SonarTrack.update (line through the last pings)", follow, ""),
        ("SonarSensor.step: render + detect + track, one decision", decision, "≤ 0.1 ms"),
        ("env.step, ideal camera", stepper(), ""),
        ('env.step, sensor="sonar"', stepper(sensor="sonar"), ""),
        ('env.step, sensor="fused" (ideal camera)', stepper(sensor="fused"), ""),
        ("render_image (imaging sonar, 128 × 88 cells)", fls_render, ""),
        ("detect_image", fls_detect, ""),
        ("ImagingMap.update (the map's view)", fls_map_update, ""),
        ("ImagingSensor.step: render + detect + map, one decision", fls_decision, ""),
        ('env.step, sensor="fls"', stepper(sensor="fls"), ""),
    )
    times: dict[str, list[float]] = {name: [] for name, _, _ in stages}
    for _, fn, _ in stages:
        fn()
    for _ in range(args.repeats):  # in turns
        for name, fn, _ in stages:
            t = CLOCK()
            for _ in range(200):
                fn()
            times[name].append((CLOCK() - t) / 200)
    print(f"{platform.machine()}, Python {platform.python_version()}, numba {numba.__version__}")
    print(f"{args.repeats} repeats of 200 calls, {'CPU' if args.cpu else 'wall'} time")
    print("| benchmark | median | target |\n|---|---|---|")
    for name, _, target in stages:
        t = statistics.median(times[name])
        ok = ""
        if target:
            ok = " ✓" if t <= float(target.split()[1]) * 1e-3 else " ✗"
        print(f"| {name} | {t * 1e3:.4f} ms | {target}{ok} |")
    if args.json:
        rows = [
            (name, statistics.median(times[name]), float(target.split()[1]) * 1e-3 if target else None, None)
            for name, _, target in stages
        ]
        stored.write(args.json, "sonar", "CPU" if args.cpu else "wall", args.repeats, load_before, rows)


if __name__ == "__main__":
    main()
