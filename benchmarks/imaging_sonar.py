"""The heuristic through the fused sensor with the forward-looking imaging sonar, against the profiler's.

Usage: ``python benchmarks/imaging_sonar.py [--suites mixed hard sharp] [--pipes 100] [--water
turbid] [--burial 0] [--noise-seed 0] [--way tracked|own] [--memory N] [--detect JSON]
[--profiler]``

The heuristic runs through ``camera="vision", sensor="fused-fls"`` in ``--water`` as
``benchmarks/tracker_suites.py --sensor fused-fls`` runs it (``--profiler``: ``sensor="fused"``,
the look-ahead profiler, the reference). The readings measured beside the sensor's own, in this
process only: ``--way own`` shows the sonar's view in a murky frame in its map's own order of the
ends instead of ordered the way of the tracked line (``SonarSensors._as_output``); ``--memory``
the pings its map keeps; ``--detect`` :func:`~pipefollow.perception.imaging_detect.detect_image`'s
settings, e.g. ``'{"threshold": 4}'``. One line: per suite the loss a pipe against the ideal
camera [95 % bootstrap CI], the pipes lost that the ideal camera keeps, and the episodes that
turned back (followed the pipe backwards ≥ 3 m; the ideal camera's in brackets): eq. 19 pays a
pipe followed backwards as one followed forwards, so a low loss with many turned back is a sensor
that gives up the pipe's way (docs/decisions.md, "A forward-looking imaging sonar").
"""

from __future__ import annotations

import argparse
import json

from tracker_suites import judge


def patch(way: str, memory: int | None, detect: dict | None) -> None:
    """The imaging sonar's ``memory`` and ``detect``, its murky view shown ``way``'s (this process)."""
    from pipefollow.perception import sensor as S
    from pipefollow.perception.imaging_track import ImagingSensor

    init = S.SonarSensors.__init__

    def __init__(self, settings, camera, lost_reward):
        init(self, settings, camera, lost_reward)
        if isinstance(self.sonar, ImagingSensor) and (memory is not None or detect):
            kw = {} if memory is None else {"memory": memory}
            self.sonar = ImagingSensor(self.sonar.sonar, self.sonar.diameter, self.sonar.burial, camera,
                                       detect=detect, **kw)  # fmt: skip

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
    ap.add_argument("--way", default="tracked", choices=["tracked", "own"])
    ap.add_argument("--memory", type=int, default=None, help="pings the map keeps (default: the map's own)")
    ap.add_argument("--profiler", action="store_true", help="keep the profiler (the reference)")
    ap.add_argument("--detect", type=json.loads, default={}, help="detect_image's settings, JSON")
    args = ap.parse_args()
    if not args.profiler:
        patch(args.way, args.memory, args.detect)
    label = (
        "profiler"
        if args.profiler
        else f"imaging, {args.way}, memory {args.memory} {json.dumps(args.detect)}"
    )
    sensor = "fused" if args.profiler else "fused-fls"
    cells = []
    for name in args.suites:
        r = judge(name, args.pipes, "vision", args.water, args.noise_seed, sensor, args.burial)
        lo, hi = r["loss_ci"]
        back = f"{len(r['turned_back'])} ({r['ideal_turned_back']})"
        cells.append(f"{r['loss']:.1f} [{lo:.1f}, {hi:.1f}], {len(r['lost'])}, {back}")
    print(f"| {label} | {args.water} {args.burial} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
