"""Trace the heuristic with the vision camera: what each decision's detection was, against the truth.

Usage: ``python benchmarks/vision_trace.py [--seeds 0 1 2 3 4] [--pipes N] [--water clear]``

The held-out suite's episodes run as ``pipefollow benchmark --controller heuristic --camera vision``
runs them (same environment, same noise generators). Every detection the controller acts on is
classified against the exact camera's visible piece:

* ``correct``: found, both ends within 0.3 m (or not found and no pipe in view);
* ``miss``: a pipe in view, not found; ``false``: found without a pipe in view;
* ``swap``: both ends within 0.3 m only once near and far are swapped;
* ``bend``: another gross error (an end off by > 0.3 m) with a vertex of the pipe in the
  footprint: mostly one leg of the bend reported as the whole piece;
* ``gross``: any other gross error.

It prints one line per seed with the counts and the success rate of the traced episodes.
"""

from __future__ import annotations

import argparse
import math
from collections import Counter

import numpy as np

KINDS = ("correct", "miss", "false", "swap", "bend", "gross")
GROSS_M = 0.3


def classify(truth, det, vertex_in_view: bool) -> str:
    """One decision's class (module docstring)."""
    seen, x1, y1, x2, yn = truth
    if not seen:
        return "false" if det.found else "correct"
    if not det.found:
        return "miss"
    far = math.hypot(det.x1 - x1, det.y1 - y1)
    near = math.hypot(det.x2 - x2, det.y_near - yn)
    if max(far, near) <= GROSS_M:
        return "correct"
    if max(math.hypot(det.x2 - x1, det.y_near - y1), math.hypot(det.x1 - x2, det.y1 - yn)) <= GROSS_M:
        return "swap"
    return "bend" if vertex_in_view else "gross"


def vertex_in_view(points, pose, half_width, depth) -> bool:
    """Whether an inner vertex of the pipe lies in the footprint."""
    x, y, psi = pose
    dx, dy = points[1:-1, 0] - x, points[1:-1, 1] - y
    cs, sn = math.cos(psi), math.sin(psi)
    lat, fwd = -sn * dx + cs * dy, cs * dx + sn * dy
    return bool(np.any((np.abs(lat) <= half_width) & (fwd >= 0.0) & (fwd <= depth)))


def trace(seed: int, n_pipes: int, water: str) -> tuple[Counter, float]:
    """Counts of the classes over the first ``n_pipes`` held-out episodes and their success rate."""
    from pipefollow.envs.env import PipelineFollowingEnv
    from pipefollow.evaluation.benchmark import _noise_rng
    from pipefollow.evaluation.success import SUCCESS_IN_VIEW
    from pipefollow.learners.heuristic import Heuristic
    from pipefollow.perception.camera import VisionCamera
    from pipefollow.sim import decision as sim
    from pipefollow.sim.suites import get_suite, min_length_for
    from pipefollow.training.compiled import run_episode

    pipes = get_suite("heldout").pipes(n_pipes, min_length_for(60.0))
    counts: Counter = Counter()
    successes = 0
    original = VisionCamera._look
    for i, pipe in enumerate(pipes):
        log = []

        def look(self, s, points, cum, rng, log=log):
            original(self, s, points, cum, rng)
            pose = (s[sim.X], s[sim.Y], s[sim.PSI])
            cam = self.camera
            log.append((self.truth, self.detection, vertex_in_view(points, pose, cam.half_width, cam.depth)))

        VisionCamera._look = look
        try:
            env = PipelineFollowingEnv(pipe, 60.0, camera="vision", water=water)
            env.np_random = _noise_rng(seed, i)
            stats = run_episode(env, Heuristic())
        finally:
            VisionCamera._look = original
        for truth, det, bend in log[:-1]:  # the last image is after the last decision
            counts[classify(truth, det, bend)] += 1
        in_view = stats.pipe_in_view
        successes += in_view >= SUCCESS_IN_VIEW
    return counts, successes / len(pipes)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--pipes", type=int, default=100)
    parser.add_argument("--water", default="clear")
    args = parser.parse_args()
    print("| seed | " + " | ".join(KINDS) + " | success |")
    print("|---" * (len(KINDS) + 2) + "|")
    total: Counter = Counter()
    rates = []
    for seed in args.seeds:
        counts, rate = trace(seed, args.pipes, args.water)
        total += counts
        rates.append(rate)
        print(f"| {seed} | " + " | ".join(str(counts[k]) for k in KINDS) + f" | {rate:.0%} |", flush=True)
    print("| all | " + " | ".join(str(total[k]) for k in KINDS) + f" | {np.mean(rates):.1%} |")


if __name__ == "__main__":
    main()
