"""The heuristic through the fused sensor with a forward-looking imaging sonar in place of the profiler.

Usage: ``python benchmarks/imaging_sonar.py [--suites mixed hard sharp] [--pipes 100] [--water
turbid] [--burial 0] [--noise-seed 0] [--way own|tracked] [--memory 8] [--profiler]``

The heuristic runs through ``camera="vision", sensor="fused"`` in ``--water`` as
``benchmarks/tracker_suites.py --sensor fused`` runs it, with the fused sensor's look-ahead profiler
replaced, in this process only, by :class:`~pipefollow.perception.imaging_track.ImagingSensor` (the
imaging sonar's ping, :func:`~pipefollow.perception.imaging_detect.detect_image` and the map of the
pieces found; ``--profiler`` keeps the profiler, the reference). ``--way``: the sonar's view shown
in a murky frame in the map's own order of its ends (``own``) or ordered the way of the tracked
line as the fused sensor orders the profiler's (``tracked``, ``SonarSensors._as_output``). One line:
per suite the loss a pipe against the ideal camera [95 % bootstrap CI], the pipes lost that the
ideal camera keeps and the episodes that turned back. The environments do not offer the imaging
sonar yet: this measures whether they should.
"""

from __future__ import annotations

import argparse

from tracker_suites import judge


def patch(way: str, memory: int) -> None:
    """The fused sensor's profiler replaced by the imaging sonar, its murky view shown ``way``'s."""
    from pipefollow.perception import sensor as S
    from pipefollow.perception.imaging_track import ImagingSensor

    init = S.SonarSensors.__init__

    def __init__(self, settings, camera, lost_reward):
        init(self, settings, camera, lost_reward)
        burial = S.sonar_burial(settings.water)
        self.sonar = ImagingSensor(
            diameter=settings.water.pipe_diameter, burial=burial, camera=camera, memory=memory
        )

    S.SonarSensors.__init__ = __init__
    if way == "own":
        S.SonarSensors._as_output = lambda self, view, tracker: self._shown_piece(
            view.x1, view.y1, view.x2, view.y_near
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suites", nargs="+", default=["mixed", "hard", "sharp"])
    ap.add_argument("--pipes", type=int, default=100)
    ap.add_argument("--water", default="turbid")
    ap.add_argument("--burial", type=float, default=0.0)
    ap.add_argument("--noise-seed", type=int, default=0)
    ap.add_argument("--way", default="own", choices=["own", "tracked"])
    ap.add_argument("--memory", type=int, default=8, help="pings whose pieces the map keeps")
    ap.add_argument("--profiler", action="store_true", help="keep the profiler (the reference)")
    args = ap.parse_args()
    if not args.profiler:
        patch(args.way, args.memory)
    label = "profiler" if args.profiler else f"imaging, {args.way}, memory {args.memory}"
    cells = []
    for name in args.suites:
        r = judge(name, args.pipes, "vision", args.water, args.noise_seed, "fused", args.burial)
        lo, hi = r["loss_ci"]
        cells.append(f"{r['loss']:.1f} [{lo:.1f}, {hi:.1f}], {len(r['lost'])}, {len(r['turned_back'])}")
    print(f"| {label} | {args.water} {args.burial} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
