"""Each controller's loss through a sensor against its own ideal camera, run by run.

Usage: ``python benchmarks/sensor_seeds.py --controllers heuristic los cacla=FILE ...
[--suites heldout heldout-hard heldout-sharp] [--sensor fused] [--camera vision] [--water turbid]
[--burial 0] [--seeds 0 1 2 3 4] [--pipes N] [--goal 25]``

The closed-loop table (``examples/closed_loop_table.py``) measures every cell at noise seed 0 with
one policy a learner. This runs a controller (a built-in name or a policy file, as ``pipefollow
benchmark --controller`` takes it; ``NAME=FILE`` labels a file, and files given the same NAME are
one learner's training seeds) on each suite's pipes, 60 s each, through ``--sensor`` in ``--water``
(``--sensor sonar`` or ``fls``: with the ideal camera) and on the ideal camera, with the same noise (the
benchmark's generator of pipe ``k``: ``SeedSequence([seed, k])``), at every noise seed of
``--seeds``. One line per controller and suite: the loss of mean return against its own ideal camera
in each run (each policy at each noise seed: the mean of the per-pipe differences), their mean and
range, the pipes lost (in view < 0.8 where its ideal camera keeps them) summed over the runs, and in
how many runs the loss is at most ``--goal`` (issue 23's 25 a pipe in turbid water).
"""

from __future__ import annotations

import argparse
from pathlib import Path


def losses(spec: str, suite_name: str, camera: dict, seeds, n_pipes: int | None) -> tuple[list, int]:
    """The loss at each seed and the pipes lost over all of them (module docstring)."""
    from pipefollow.evaluation.benchmark import LOST_IN_VIEW, load_controller, run_episodes
    from pipefollow.sim import episode as ep
    from pipefollow.sim.suites import get_suite, min_length_for

    suite = get_suite(suite_name)
    pipes = suite.pipes(n_pipes or suite.count or 100, min_length_for(60.0))
    out, lost = [], 0
    for seed in seeds:
        ideal, _ = run_episodes(load_controller(spec), pipes, 60.0, noise_seed=seed)
        seen, _ = run_episodes(load_controller(spec), pipes, 60.0, noise_seed=seed, camera=camera)
        out.append(float((ideal[:, ep.STAT_RETURN] - seen[:, ep.STAT_RETURN]).mean()))
        kept = ideal[:, ep.STAT_IN_VIEW] >= LOST_IN_VIEW
        lost += int((kept & (seen[:, ep.STAT_IN_VIEW] < LOST_IN_VIEW)).sum())
    return out, lost


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--controllers", nargs="+", default=["heuristic"], help="names, files or NAME=FILE")
    ap.add_argument("--suites", nargs="+", default=["heldout", "heldout-hard", "heldout-sharp"])
    ap.add_argument("--camera", default="vision")
    ap.add_argument("--sensor", default="fused", choices=["camera", "sonar", "fused", "fls", "fused-fls"])
    ap.add_argument("--water", default="turbid")
    ap.add_argument("--burial", type=float, default=0.0, help="the share of the pipe's width under sand")
    ap.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2, 3, 4])
    ap.add_argument("--pipes", type=int, default=None, help="the first N pipes of each suite [all]")
    ap.add_argument("--goal", type=float, default=25.0, help="the loss a pipe a run must not exceed")
    args = ap.parse_args()
    from pipefollow.perception.camera import SONAR_ALONE

    camera = {
        "camera": "ideal" if args.sensor in SONAR_ALONE else args.camera,  # a sonar alone: no camera image
        "sensor": args.sensor,
        "water": {"preset": args.water, "burial": args.burial},
    }
    runs_are = f"loss a pipe a run (noise seeds {', '.join(map(str, args.seeds))})"
    print(f"| controller | suite | {runs_are} | mean [min, max] | lost | ≤ {args.goal:g} |")
    print("|---|---|---|---|---|---|")
    groups: dict[str, list[str]] = {}  # label → its policies (a learner's training seeds)
    for item in args.controllers:
        label, _, spec = ("", "", item) if Path(item).exists() else item.rpartition("=")
        groups.setdefault(label or spec, []).append(spec)
    for label, specs in groups.items():
        for suite in args.suites:
            runs, lost = [], 0
            for spec in specs:
                per_seed, n_lost = losses(spec, suite, camera, args.seeds, args.pipes)
                runs += per_seed
                lost += n_lost
            mean, lo, hi = sum(runs) / len(runs), min(runs), max(runs)
            met = sum(1 for v in runs if v <= args.goal)
            each = " / ".join(f"{v:.1f}" for v in runs)
            spread = f"{mean:.1f} [{lo:.1f}, {hi:.1f}]"
            print(f"| {label} | {suite} | {each} | {spread} | {lost} | {met} of {len(runs)} |", flush=True)


if __name__ == "__main__":
    main()
