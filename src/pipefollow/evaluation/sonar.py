"""How well the multibeam profiler's detector finds the pipe, alone and in the heuristic's loop.

* :func:`sonar_statistics` renders pings of straight pipes crossing the fan at random lateral
  positions and angles, and pipe-free pings, and runs
  :func:`~pipefollow.perception.sonar_detect.detect_profile` on each: the detection rate, the
  false-alarm rate and the lateral error against the rendered truth.
* :func:`heuristic_on_sonar` runs the heuristic controller on the held-out suite with the
  observation from :class:`~pipefollow.perception.sonar_track.SonarSensor` instead of the exact
  camera, as an environment with the sonar would (reward eq. 19 from the true geometry, −10
  while the sonar has lost the pipe), beside the same controller on the exact camera.

The figure of sample profiles is :func:`pipefollow.evaluation.perception_figures.sonar_profiles`.

Ping ``k`` of a condition draws from ``default_rng(SeedSequence([seed, condition, k]))``.
"""

from __future__ import annotations

import math

import numpy as np

from pipefollow.perception.sonar import DOWNWARD_SONAR, Sonar, fan_line, render_ping
from pipefollow.perception.sonar_detect import detect_profile

EMPTY = np.zeros((0, 2))


def straight_pipe(
    lateral: float, angle: float, length: float = 40.0, forward: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """A straight pipe (points, arc lengths) through camera ``(lateral, forward)`` of an AUV at (0, 0, ψ = 0).

    ``angle`` (rad) turns it from the track (north) towards starboard (east).
    """
    d = np.array([math.cos(angle), math.sin(angle)])
    p0 = np.array([forward, lateral])
    return np.array([p0 - 0.5 * length * d, p0 + 0.5 * length * d]), np.array([0.0, length])


def sonar_statistics(
    sonar: Sonar = DOWNWARD_SONAR,
    burial: float = 0.0,
    diameter: float = 0.25,
    n: int = 1000,
    lateral: tuple[float, float] = (-1.0, 1.0),
    max_angle: float = 0.5,
    seed: int = 0,
) -> dict:
    """Detection rate, false-alarm rate and lateral error (cm) over ``n`` pings with and without a pipe.

    The pipe crosses the fan's seabed line (:func:`~pipefollow.perception.sonar.fan_line`) at a
    lateral position uniform in ``lateral`` (default: the camera's footprint) and an angle to the
    track uniform in ``±max_angle`` (rad). The error is the detection's lateral position against
    the pipe's centre line at the detection's forward position.
    """
    found, false, errors = 0, 0, []
    line = fan_line(sonar)
    for k in range(n):
        rng = np.random.default_rng(np.random.SeedSequence([seed, 1, k]))
        x0, angle = rng.uniform(*lateral), rng.uniform(-max_angle, max_angle)
        ping = render_ping(
            *straight_pipe(x0, angle, forward=line), (0.0, 0.0, 0.0), rng, sonar, diameter, burial
        )
        fix = detect_profile(ping, diameter)
        if fix.found:
            found += 1
            errors.append(fix.lateral - (x0 + (fix.forward - line) * math.tan(angle)))
        rng = np.random.default_rng(np.random.SeedSequence([seed, 2, k]))
        false += detect_profile(render_ping(EMPTY, EMPTY[:, 0], (0.0, 0.0, 0.0), rng, sonar), diameter).found
    e = np.abs(np.array(errors)) * 100.0
    return {
        "burial": burial,
        "pings": n,
        "detection_rate": found / n,
        "false_alarm_rate": false / n,
        "median_error_cm": float(np.median(e)) if e.size else math.nan,
        "p95_error_cm": float(np.percentile(e, 95)) if e.size else math.nan,
        "max_error_cm": float(e.max()) if e.size else math.nan,
        "mean_error_cm": float(np.mean(errors) * 100.0) if e.size else math.nan,
    }


def heuristic_on_sonar(
    suite,
    n_pipes: int = 100,
    sonar: Sonar | None = None,
    burial: float = 0.0,
    seconds: float = 60.0,
    seed: int = 0,
) -> dict:
    """Mean return, share of decisions with the pipe truly in view and progress (m), per camera.

    Pipe ``k``'s episode draws from ``default_rng(SeedSequence([seed, 4, k]))``; ``sonar=None`` is
    :data:`~pipefollow.perception.sonar.LOOK_AHEAD_SONAR`. The exact camera's row runs the same
    episodes without the sonar.
    """
    from pipefollow.learners.heuristic import heuristic_action
    from pipefollow.perception.sonar import LOOK_AHEAD_SONAR
    from pipefollow.perception.sonar_track import SonarSensor
    from pipefollow.sim import decision as sim
    from pipefollow.sim.suites import min_length_for

    pipes = suite.pipes(n_pipes, min_length_for(seconds))
    packed = sim.pack_params(sim.PAPER_SIM)
    lost = sim.PAPER_SIM.lost_reward
    out = {}
    for camera in ("exact", "sonar"):
        returns, in_view, progress, followed = [], [], [], 0
        for k, pipe in enumerate(pipes):
            s = np.zeros(sim.STATE_SIZE)
            p0 = pipe.points[0]
            sim.init_state_packed(s, pipe.points, pipe.cumulative, p0[0], p0[1], pipe.start_heading, packed)
            rng = np.random.default_rng(np.random.SeedSequence([seed, 4, k]))
            sensor = SonarSensor(sonar or LOOK_AHEAD_SONAR, burial=burial)
            if camera == "sonar":
                sensor.look(s, pipe.points, pipe.cumulative, rng)
            total, seen = 0.0, 0
            n = int(round(seconds))
            for _ in range(n):
                a = heuristic_action(s[sim.X1], s[sim.Y1]) if s[sim.IN_VIEW] else 0.0
                r = sim.decide_packed(s, a, pipe.points, pipe.cumulative, packed)
                seen += s[sim.IN_VIEW] != 0.0  # the exact camera's verdict, before the sonar's slots
                if camera == "sonar":
                    sensor.look(s, pipe.points, pipe.cumulative, rng)
                    if s[sim.OVERRIDDEN] != 0.0 or s[sim.IN_VIEW] == 0.0:
                        r = lost
                total += r
            returns.append(total)
            in_view.append(seen / n)
            progress.append(s[sim.PROGRESS])
            followed += seen / n >= 0.9
        out[camera] = {
            "mean_return": float(np.mean(returns)),
            "in_view": float(np.mean(in_view)),
            "progress_m": float(np.mean(progress)),
            "pipes_in_view_90": int(followed),
            "pipes": len(pipes),
        }
    return out
