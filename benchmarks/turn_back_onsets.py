"""Where the episodes that follow the pipe backwards begin to: the tracker's event and the sonar's view.

Usage: ``python benchmarks/turn_back_onsets.py [--suite sharp] [--pipes 100] [--sensor fused-fls]
[--water turbid] [--noise-seed 0]``

Runs the heuristic on a suite's pipes (a level without a training family is taken from the
training stream, as ``benchmarks/tracker_suites.py`` takes it) through ``camera="vision"`` and
``--sensor`` in ``--water``, each episode as ``pipefollow benchmark`` runs it (the same noise
generator per pipe). In the episodes that turned back (``evaluation.success``: ≥ 3 m of progress
lost in view), the *onset* is the first decision of the first run of three or more decisions
whose shown piece (the observation's near → far) points against the exact camera's piece (more
than 2.5 rad apart; both in view, the exact piece longer than 0.5 m). One line per such episode:
the onset's decision, the camera tracker's event in that frame and, for a sensor with a sonar,
whether the sonar's own view there agreed with the exact piece, pointed against it, or neither.
Then the onsets counted by event and view.
"""

from __future__ import annotations

import argparse
import math
from collections import Counter

RUN = 3  # decisions in a row shown reversed that make an onset
REVERSED_RAD = 2.5  # the shown piece this far from the exact one's direction is drawn the other way
AGREES_RAD = 0.6  # the sonar's view this near the exact piece's direction agrees with it
MIN_PIECE_M = 0.5  # exact pieces shorter than this are not judged (their direction is noise)
EVENTS = ("none", "accepted", "bend", "rejected", "started", "replaced")


def _direction(x1: float, y1: float, x2: float, y_near: float) -> float:
    """The piece's direction from its near end to its far end (rad from forward to starboard)."""
    return math.atan2(x1 - x2, y1 - y_near)


def _apart(a: float, b: float) -> float:
    """How far apart two directions are (rad, 0–π)."""
    from pipefollow.sim.controller import wrap_angle

    return abs(wrap_angle(a - b))


def _sonar_view(sensors, exact: float) -> str:
    """How the sonar's own view of this decision lies against the exact piece's direction ``exact``."""
    sonar = getattr(sensors, "sonar", None)
    if sonar is None:
        return "no sonar"
    v = sonar.view
    if not v.in_view:
        return "none"
    d = _apart(_direction(v.x1, v.y1, v.x2, v.y_near), exact)
    return "against" if d > REVERSED_RAD else "agrees" if d < AGREES_RAD else "other"


def onsets(suite_name: str, n_pipes: int, sensor: str, water: str, noise_seed: int) -> list[dict]:
    """The onset of every episode that turned back (module docstring), in pipe order."""
    from pipefollow.envs.env import PipelineFollowingEnv
    from pipefollow.evaluation.benchmark import _noise_rng
    from pipefollow.evaluation.success import TURNED_BACK_M
    from pipefollow.learners.heuristic import heuristic_action
    from pipefollow.sim import decision as sim
    from pipefollow.sim import episode as ep
    from pipefollow.sim.suites import min_length_for
    from tracker_suites import suite_of

    suite = suite_of(suite_name)
    seconds = 60.0
    out = []
    for k, pipe in enumerate(suite.pipes(n_pipes, min_length_for(seconds))):
        env = PipelineFollowingEnv(pipe, seconds, camera="vision", sensor=sensor, water=water)
        env.np_random = _noise_rng(noise_seed, k)
        obs, info = env.reset()
        t, run, first, onset, done = 0, 0, None, None, False
        while not done:
            action = heuristic_action(obs[0], obs[1])
            sensors = env._vision
            cam = getattr(sensors, "vision", sensors)  # the camera of a fused sensor, or the camera itself
            truth, s = cam.truth, env.state
            if onset is None and truth.in_view and info["pipe_in_view"]:
                exact = _direction(truth.x1, truth.y1, truth.x2, truth.y_near)
                if math.hypot(truth.x1 - truth.x2, truth.y1 - truth.y_near) > MIN_PIECE_M:
                    shown = _direction(s[sim.X1], s[sim.Y1], s[sim.X2], s[sim.Y_NEAR])
                    run = run + 1 if _apart(shown, exact) > REVERSED_RAD else 0
                    if run == 1:
                        event, view = EVENTS[int(cam.tracker.event)], _sonar_view(sensors, exact)
                        first = {"pipe": k, "decision": t, "event": event, "view": view}
                    if run >= RUN:
                        onset = first
            obs, _, terminated, truncated, info = env.step([action])
            done, t = terminated or truncated, t + 1
        if env.book[ep.BACK] >= TURNED_BACK_M:
            out.append(onset or {"pipe": k, "decision": None, "event": "-", "view": "-"})
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", default="sharp")
    ap.add_argument("--pipes", type=int, default=100)
    ap.add_argument("--sensor", default="fused-fls", choices=["camera", "sonar", "fused", "fls", "fused-fls"])
    ap.add_argument("--water", default="turbid")
    ap.add_argument("--noise-seed", type=int, default=0)
    args = ap.parse_args()
    found = onsets(args.suite, args.pipes, args.sensor, args.water, args.noise_seed)
    print("| pipe | onset (decision) | tracker event | sonar's view there |")
    print("|---|---|---|---|")
    for o in found:
        print(f"| {o['pipe']} | {o['decision']} | {o['event']} | {o['view']} |")
    counts = Counter((o["event"], o["view"]) for o in found)
    print(f"\n{len(found)} episodes turned back; onsets by (event, view):")
    for (event, view), n in counts.most_common():
        print(f"  {event:9s} {view:9s} {n}")


if __name__ == "__main__":
    main()
