"""What an acoustic sensor that looks ahead could give the heuristic in murky water: an oracle ceiling.

Usage: ``python benchmarks/acoustic_ceiling.py [--bands profiler 0-3 0.7-3 1.4-2.86] [--ways
tracked own tracker] [--suites mixed hard sharp] [--pipes N] [--noise-seed 0] [--sd 0.02]
[--water turbid]``

The heuristic runs through the fused sensor (``camera="vision", sensor="fused"``) in ``--water``
(turbid: no frame is clear enough to search, so the sonar alone feeds the tracker) as
``benchmarks/tracker_suites.py --sensor fused`` runs it, with the look-ahead profiler as it is
(band ``profiler``) or with the profiler's view replaced by an oracle: the exact camera's piece of pipe
clipped to a band of the footprint ``A ≤ forward ≤ B`` metres ahead of the AUV's centre, each end
off by a normal lateral error of ``--sd`` m. A band is what a sensor sees of the footprint: the
whole of it (``0-3``), all but the stretch under the vehicle's nose (``0.7-3``), or the seabed strip
that a forward-looking imaging sonar with a 20° vertical beam tilted 45° down sees from 2 m
(``1.4-2.86``; the vertical aperture of e.g. the Teledyne BlueView M900-130 and the Blueprint
Oculus M750d). The oracle has no false detections, no noise but ``--sd`` and never misses a piece
in its band; where it sees nothing the profiler still pings, and its fix (a point on the tracked
line, the search's side) is used as the fused sensor uses it. ``--ways``: how the sensor's piece
is shown where the frame is murky:

* ``tracked``: as the fused sensor shows the sonar's view today, its ends ordered the way of the
  tracked line (``SonarSensors._as_output``);
* ``own``: in the piece's own order: for a band, the exact camera's (an oracle of the pipe's way
  too); for the profiler, its line's end further forward as the far one;
* ``tracker``: the tracker's own output where it shows the pipe (the piece fed to it as the
  measurement, as today), the piece as ``tracked`` where it does not.

The row with band ``0-3`` and way ``own`` is the exact camera through the fused path (a check:
its loss is the noise's); ``profiler`` with ``tracked`` is the fused sensor as it is. Each line:
per suite the loss a pipe against the ideal camera [95 % bootstrap CI], the pipes lost that the
ideal camera keeps and the episodes that turned back (eq. 19 pays a pipe followed backwards as
one followed forwards: "The sonar's view the way of the tracked line" in docs/decisions.md). It
replaces ``SonarSensors._ping`` (for a band) and ``_as_output`` (for two ways) in this process
only: the package is not changed.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from tracker_suites import judge

WAYS = ("tracked", "own", "tracker")


def band_of(text: str) -> tuple[float, float]:
    """``"A-B"`` as ``(A, B)`` metres ahead, ``0 ≤ A < B``."""
    try:
        a, b = (float(v) for v in text.split("-"))
    except ValueError:
        raise SystemExit(f"--bands: {text!r} is not A-B (metres ahead, e.g. 0.7-3)") from None
    if not 0.0 <= a < b:
        raise SystemExit(f"--bands: {text!r} needs 0 <= A < B")
    return a, b


def clipped_piece(x1, y1, x2, y_near, a, b):
    """The piece (far ``x1, y1``, near ``x2, y_near``) clipped to ``a ≤ y ≤ b``, or None.

    The clipped piece keeps its way: its far end is on the original far end's side. Pieces whose
    part in the band is shorter than 5 cm along the forward axis count as none.
    """
    lo, hi = max(a, min(y_near, y1)), min(b, max(y_near, y1))
    if hi - lo < 0.05:
        return None
    dy = y1 - y_near

    def lateral(y):
        return x2 if dy == 0.0 else x2 + (y - y_near) / dy * (x1 - x2)

    near, far = (lo, hi) if y1 >= y_near else (hi, lo)
    return lateral(far), far, lateral(near), near


class SeenMap:
    """The stretches of one pipe that a band has held so far: an oracle of a sensor with a perfect map.

    The pipe is sampled every centimetre of arc length; a sample is seen once it lay in the band
    ``a ≤ forward ≤ b`` within ``swath`` metres to either side of the track. Unseen stretches
    shorter than ``fill`` (between two seen ones) count as seen: a map joins its sightings.
    """

    STEP = 0.01

    def __init__(self, points, cum, band, swath, fill) -> None:
        self.points, self.cum, self.band, self.swath, self.fill = points, cum, band, swath, fill
        self.s = np.arange(0.0, cum[-1], self.STEP)
        self.x, self.y = np.interp(self.s, cum, points[:, 0]), np.interp(self.s, cum, points[:, 1])
        self.seen = np.zeros(self.s.size, dtype=bool)

    def update(self, x: float, y: float, psi: float) -> None:
        """Mark what the band holds from pose (x, y, ψ)."""
        dx, dy = self.x - x, self.y - y
        c, sn = math.cos(psi), math.sin(psi)
        lateral, forward = -sn * dx + c * dy, c * dx + sn * dy
        a, b = self.band
        self.seen |= (forward >= a) & (forward <= b) & (np.abs(lateral) <= self.swath)

    def mark(self, s_from: float, s_to: float) -> None:
        """Mark the stretch of arc length ``[s_from, s_to]`` seen."""
        self.seen[np.searchsorted(self.s, s_from) : np.searchsorted(self.s, s_to, side="right")] = True

    def hidden(self) -> tuple[np.ndarray, np.ndarray]:
        """The unseen stretches as sorted arc-length intervals (the camera's buried stretches' form)."""
        edges = np.flatnonzero(np.diff(np.concatenate(([1], self.seen.view(np.int8), [1]))))
        starts, ends = edges[0::2], edges[1::2]  # runs of unseen samples [start, end)
        lo, hi = self.s[starts] - 0.5 * self.STEP, self.s[np.minimum(ends, self.s.size) - 1] + 0.5 * self.STEP
        hi = np.where(ends >= self.s.size, math.inf, hi)  # unseen to the pipe's end
        lo = np.where(starts == 0, -math.inf, lo)
        keep = (hi - lo >= self.fill) | (starts == 0) | (ends >= self.s.size)
        if not keep.any():
            return np.array([math.inf]), np.array([math.inf])
        return lo[keep], hi[keep]


def patch(
    band: tuple[float, float] | None,
    way: str,
    sd: float,
    memory: bool = False,
    swath: float = 3.4,
    fill: float = 0.6,
    p_detect: float = 1.0,
) -> None:
    """The fused sensor's ping replaced by the band oracle (unless None), its murky view by ``way``'s."""
    from pipefollow.perception import sensor as S
    from pipefollow.perception.sonar_detect import SonarFix
    from pipefollow.perception.sonar_track import NO_VIEW, SonarView
    from pipefollow.perception.track_step import OUT_IN_VIEW
    from pipefollow.sim import decision as sim
    from pipefollow.sim.camera import PAPER_CAMERA, observe

    ping, as_output, reset = S.SonarSensors._ping, S.SonarSensors._as_output, S.SonarSensors.reset
    a, b = band if band is not None else (0.0, 0.0)

    def _ping(self, s, points, cum):
        piece = None
        if memory:  # the exact camera's piece of what the band has seen
            seen = getattr(self, "_seen_map", None)
            if seen is None or seen.points is not points:
                seen = self._seen_map = SeenMap(points, cum, (a, b), swath, fill)
            if p_detect >= 1.0 or self._rng.random() < p_detect:
                seen.update(s[sim.X], s[sim.Y], s[sim.PSI])
            hid_from, hid_to = seen.hidden()
            v = observe(
                points, cum, s[sim.X], s[sim.Y], s[sim.PSI], s[sim.PROGRESS], PAPER_CAMERA, hid_from, hid_to
            )
            piece = (v.x1, v.y1, v.x2, v.y_near) if v.in_view else None
        elif s[sim.IN_VIEW] != 0.0 and (p_detect >= 1.0 or self._rng.random() < p_detect):
            # the exact camera's piece (the simulator's slots before the sensor's)
            piece = clipped_piece(s[sim.X1], s[sim.Y1], s[sim.X2], s[sim.Y_NEAR], a, b)
        if piece is None:  # the profiler's ping: its fix for the search and the track, no view
            ping(self, s, points, cum)
            self.sonar.view = NO_VIEW
            return NO_VIEW
        x1, y1, x2, yn = piece
        x1 += sd * self._rng.standard_normal()
        x2 += sd * self._rng.standard_normal()
        angle = math.atan2(x1 - x2, y1 - yn)
        view = SonarView(True, x1, y1, x2, yn, x2 - yn * math.tan(angle), angle, True, 1)
        mid = 0.5 * (y1 + yn)
        self.sonar.fix = SonarFix(True, lateral=0.5 * (x1 + x2), forward=mid, confidence=1.0)
        self.sonar.view = view
        return view

    def _as_output_own(self, view, tracker):
        return self._shown_piece(view.x1, view.y1, view.x2, view.y_near)

    def _as_output_tracker(self, view, tracker):
        return tracker.out if tracker.out[OUT_IN_VIEW] != 0.0 else as_output(self, view, tracker)

    def _reset(self, *args):
        self._seen_map = None  # a new episode: an empty map
        reset(self, *args)

    if band is not None:
        S.SonarSensors._ping, S.SonarSensors.reset = _ping, _reset
    if way == "own":
        S.SonarSensors._as_output = _as_output_own
    elif way == "tracker":
        S.SonarSensors._as_output = _as_output_tracker


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bands", nargs="+", default=["profiler", "0-3", "0.7-3", "1.4-2.86"])
    ap.add_argument("--ways", nargs="+", default=list(WAYS), choices=WAYS)
    ap.add_argument("--suites", nargs="+", default=["mixed", "hard", "sharp"])
    ap.add_argument("--pipes", type=int, default=100)
    ap.add_argument("--noise-seed", type=int, default=0)
    ap.add_argument("--sd", type=float, default=0.02, help="the oracle's lateral error at each end (m)")
    ap.add_argument("--water", default="turbid")
    ap.add_argument("--memory", action="store_true", help="a band's oracle remembers what it has seen")
    ap.add_argument("--swath", type=float, default=3.4, help="with --memory: the band's half-width (m)")
    ap.add_argument("--fill", type=float, default=0.6, help="with --memory: unseen gaps joined (m)")
    ap.add_argument("--p-detect", type=float, default=1.0, help="the chance that a ping sees its band")
    args = ap.parse_args()
    mapped = " + map" if args.memory else ""
    rows = [(b if b == "profiler" else f"{b} m{mapped}", None if b == "profiler" else band_of(b), w)
            for b in args.bands for w in args.ways]  # fmt: skip
    print("| band | way | " + " | ".join(args.suites) + " |")
    print("|---|---|" + "---|" * len(args.suites))
    from pipefollow.perception import sensor as S

    kept = S.SonarSensors._ping, S.SonarSensors._as_output, S.SonarSensors.reset
    for label, band, way in rows:
        S.SonarSensors._ping, S.SonarSensors._as_output, S.SonarSensors.reset = kept
        patch(band, way, args.sd, args.memory, args.swath, args.fill, args.p_detect)
        cells = []
        for name in args.suites:
            r = judge(name, args.pipes, "vision", args.water, args.noise_seed, "fused")
            lo, hi = r["loss_ci"]
            cells.append(f"{r['loss']:.1f} [{lo:.1f}, {hi:.1f}], {len(r['lost'])}, {len(r['turned_back'])}")
        print(f"| {label} | {way} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
