"""The heuristic through the tracked camera (or another sensor) against the ideal camera, suite by suite.

Usage: ``python benchmarks/tracker_suites.py [--suites heldout heldout-hard heldout-sharp]
[--pipes N] [--camera vision] [--sensor camera] [--water clear] [--burial 0] [--noise-seed 0]``

Each suite's pipes run one 60-s episode each with the heuristic on ``--camera`` through
``--sensor`` (as ``pipefollow benchmark --controller heuristic --suite S --camera vision --sensor
camera --water clear --burial 0`` runs them; ``--sensor sonar`` or ``fls`` takes the ideal camera, as the
environment requires) and on the ideal camera, with the same noise. One line per suite: the loss of return
against the ideal camera (mean of the per-pipe differences, bootstrap CI), the pipes lost
(pipe in view < 0.8) that the ideal camera keeps, the episodes that turned back, and the success
rates. A training family's first ``--pipes`` (100) pipes serve to choose settings (the held-out
suites judge them); ``sharp``, a level without a training family, is taken from the training
stream the same way. ``--list`` also prints the lost and turned-back pipes' indices.
"""

from __future__ import annotations

import argparse


def suite_of(suite_name: str):
    """A held-out suite, a training family, or a level without one from the training stream (``sharp``)."""
    from pipefollow.sim.suites import LEVELS, SUITES, TRAIN_STREAM, Suite, get_suite

    if suite_name not in SUITES and suite_name in LEVELS:  # a level without a training family
        return Suite(suite_name, suite_name, TRAIN_STREAM, None, "the level's training-stream pipes")
    return get_suite(suite_name)


def judge(
    suite_name: str,
    n_pipes: int | None,
    camera: str,
    water: str,
    noise_seed: int,
    sensor: str = "camera",
    burial: float = 0.0,
) -> dict:
    """One suite's line (module docstring) as a dict."""
    from pipefollow.evaluation.benchmark import LOST_IN_VIEW, benchmark
    from pipefollow.learners.heuristic import Heuristic
    from pipefollow.perception.camera import SONAR_ALONE

    suite = suite_of(suite_name)
    camera = "ideal" if sensor in SONAR_ALONE else camera  # a sonar alone: no camera image
    cam = {"camera": camera, "sensor": sensor, "water": {"preset": water, "burial": burial}}
    kw = {"controller": "heuristic", "n_pipes": n_pipes, "noise_seed": noise_seed}
    run = benchmark(Heuristic(), suite, camera=cam, **kw)
    ideal = benchmark(Heuristic(), suite, **kw)
    s, i = run.summary, ideal.summary
    diff = s["vs_heuristic_ideal"]  # the heuristic itself: compared with the ideal camera only
    ev, iv = s["episodes"], i["episodes"]
    pairs = enumerate(zip(ev, iv, strict=True))
    lost = [k for k, (a, b) in pairs if a["pipe_in_view"] < LOST_IN_VIEW <= b["pipe_in_view"]]
    back = [k for k, e in enumerate(ev) if e["turned_back"]]
    return {
        "suite": suite_name,
        "loss": -diff["mean_diff"],
        "loss_ci": (-diff["ci95_diff"][1], -diff["ci95_diff"][0]),
        "lost": lost,
        "turned_back": back,
        "ideal_turned_back": i["turned_back"],
        "success": s["success_rate"],
        "ideal_success": i["success_rate"],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suites", nargs="+", default=["heldout", "heldout-hard", "heldout-sharp"])
    ap.add_argument("--pipes", type=int, default=None)
    ap.add_argument("--camera", default="vision")
    ap.add_argument("--sensor", default="camera", choices=["camera", "sonar", "fused", "fls", "fused-fls"])
    ap.add_argument("--water", default="clear")
    ap.add_argument("--burial", type=float, default=0.0, help="the share of the pipe's width under sand")
    ap.add_argument("--noise-seed", type=int, default=0)
    ap.add_argument("--list", action="store_true", help="print the lost and turned-back pipes")
    args = ap.parse_args()
    print("| suite | loss vs ideal [95 % CI] | lost (ideal keeps) | turned back (ideal) | success (ideal) |")
    print("|---|---|---|---|---|")
    for name in args.suites:
        r = judge(name, args.pipes, args.camera, args.water, args.noise_seed, args.sensor, args.burial)
        lo, hi = r["loss_ci"]
        print(
            f"| {name} | {r['loss']:.1f} [{lo:.1f}, {hi:.1f}] | {len(r['lost'])} | "
            f"{len(r['turned_back'])} ({r['ideal_turned_back']}) | "
            f"{r['success']:.0%} ({r['ideal_success']:.0%}) |",
            flush=True,
        )
        if args.list:
            print(f"  lost: {r['lost']}  turned back: {r['turned_back']}", flush=True)


if __name__ == "__main__":
    main()
