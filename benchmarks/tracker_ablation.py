"""Where the tracked camera loses return against the ideal one: oracle ablations of the tracker.

Usage: ``python benchmarks/tracker_ablation.py [--modes base truth-detections ...]
[--suites mixed hard sharp] [--pipes N] [--noise-seed 0]``

Each mode runs the heuristic through ``camera="vision"`` in clear water (as
``benchmarks/tracker_suites.py`` does) with one part of the chain replaced by the exact camera's
answer, and prints per suite the loss of return against the ideal camera, the pipes lost, the
turned-back episodes and the success, then the decisions where the tracker and the exact camera
disagree on "in view" (of the decisions the tracker misses, in brackets those whose piece's centre
line stays within half a pipe diameter of the footprint's border, where the image holds less than
the pipe's width), the decisions whose piece is the exact camera's drawn the other way (its ends
within 0.3 m of the exact ones, swapped) with their share of the far end's error, and the far
end's error as the heuristic's action (|Δa|, the action is the far end's bearing) split by what
the frame's detection did:

* ``base``: the tracker as it is;
* ``truth-detections``: the tracker fed with the exact camera's piece instead of the detector's
  (isolates the detector; what is left is the filter's);
* ``truth-order``: the detector's ends put in the exact camera's near/far order (isolates swaps);
* ``detection-verbatim``: in a frame whose detection the tracker took, the detection itself
  shown (ordered by the tracker's near end) instead of the tracked line (the line's smoothing);
* ``truth-geometry``: the exact camera's piece shown whenever both see the pipe (isolates the
  geometry; what is left is "in view");
* ``truth-in-view``: the exact camera's in-view flag (isolates the in-view decisions);
* ``no-memory``: the tracker without its memory of the pieces it showed (``PipeTracker(memory=None)``);
* ``map-of-detections``: a memory of the pipe the detector has found, exactly placed: each frame
  whose detection is the exact camera's piece (its ends within 0.3 m, either way) marks that
  piece's stretch of the pipe as seen, and where the tracker shows no pipe, the exact camera's
  piece of the stretches seen so far (``acoustic_ceiling.SeenMap``) is shown, ordered the
  tracked line's way (an oracle of a map the vehicle would keep of its detections; navigation's
  errors over the few seconds of memory are millimetres: docs/decisions.md, "the navigation").

It replaces ``VisionCamera._track`` in this process only (the package is not changed).
"""

from __future__ import annotations

import argparse
import math

import numpy as np

MODES = (
    "base", "truth-detections", "truth-order", "detection-verbatim", "truth-geometry", "truth-in-view",
    "map-of-detections", "no-memory",
)  # fmt: skip
SAME_PIECE = 0.3  # m: a shown piece whose ends (summed) lie this near the exact camera's is the same piece
EVENTS = ("none", "accepted", "bend", "rejected", "started", "replaced")


def patch(mode: str, log: list) -> None:
    """Replace ``VisionCamera._track`` by the mode's version, which appends a row per decision to ``log``."""
    from pipefollow.learners.heuristic import heuristic_action
    from pipefollow.perception import camera as cam
    from pipefollow.perception import track_step as ts
    from pipefollow.sim import decision as sim
    from pipefollow.sim.camera import observe

    look = cam.VisionCamera.__dict__.get("_unpatched_look", cam.VisionCamera._look)
    cam.VisionCamera._unpatched_look = look

    def _look(self, s, points, cum, *args):  # each frame's: the pipe, for the map's mode
        self._pipe = (points, cum)
        return look(self, s, points, cum, *args)

    def _map_piece(self, s, det):
        """The map's piece in view (far, near ends) after marking a right detection's stretch, or None."""
        from acoustic_ceiling import SeenMap

        points, cum = self._pipe
        seen = getattr(self, "_seen_map", None)
        if seen is None or seen.points is not points:
            seen = self._seen_map = SeenMap(points, cum, (0.0, 0.0), 0.0, 0.6)
        pose = s[sim.X], s[sim.Y], s[sim.PSI], s[sim.PROGRESS]
        tv = observe(points, cum, *pose, self.camera)
        d = (det.x1, det.y1, det.x2, det.y_near)
        near = (tv.x2, tv.y_near, tv.x1, tv.y1)
        if det.found and tv.in_view and min(_ends_apart(d, tv[1:5]), _ends_apart(d, near)) <= SAME_PIECE:
            seen.mark(tv.s_near, tv.s_far)
        v = observe(points, cum, *pose, self.camera, *seen.hidden())
        return (v.x1, v.y1, v.x2, v.y_near) if v.in_view else None

    def _track(self, s, pose, det, frame=ts.CLEAR_FRAME):
        tv = self.truth
        found, d = det.found, (det.x1, det.y1, det.x2, det.y_near)
        if mode == "truth-detections":
            found, d = tv.in_view, (tv.x1, tv.y1, tv.x2, tv.y_near)
        elif mode == "truth-order" and found and tv.in_view:
            if _ends_apart(d, (tv.x2, tv.y_near, tv.x1, tv.y1)) < _ends_apart(d, tv[1:5]):
                d = (d[2], d[3], d[0], d[1])
        if mode == "no-memory":
            self.tracker.memory = None
        out = self.tracker.step(pose, found, d, frame).copy()
        T, event = self.tracker.state, int(self.tracker.event)
        if mode == "detection-verbatim" and found and event != int(ts.REJECTED) and event != 0:
            nx, ny = T[ts.NEAR_X], T[ts.NEAR_Y]
            if math.hypot(d[2] - nx, d[3] - ny) <= math.hypot(d[0] - nx, d[1] - ny):
                out[1:5] = d
            else:
                out[1:5] = (d[2], d[3], d[0], d[1])
        elif mode == "truth-geometry" and out[0] and tv.in_view:
            out[1:5] = (tv.x1, tv.y1, tv.x2, tv.y_near)
        elif mode == "truth-in-view":
            out[0] = 1.0 if tv.in_view else 0.0
            if tv.in_view and not T[ts.ACTIVE]:
                out[1:5] = (tv.x1, tv.y1, tv.x2, tv.y_near)
        elif mode == "map-of-detections":
            piece = _map_piece(self, s, det)
            if not out[0] and piece is not None:
                out[0], out[1:5] = 1.0, self.tracker.ordered(*piece)
                out[ts.OUT_SIDE] = 1.0 if out[1] >= 0.0 else -1.0
        self._show(s, out)
        seen = out[0] != 0.0
        err, reversed_ends = math.nan, 0.0
        if seen and tv.in_view:
            err = abs(heuristic_action(out[1], out[2]) - heuristic_action(tv.x1, tv.y1))
            flipped = _ends_apart(out[1:5], (tv.x2, tv.y_near, tv.x1, tv.y1))
            # the exact camera's piece within SAME_PIECE, drawn the other way
            reversed_ends = float(flipped < min(SAME_PIECE, _ends_apart(out[1:5], tv[1:5])))
        inside = _deepest(tv, self.camera) if tv.in_view else 0.0
        log.append((event, float(tv.in_view), float(seen), err, reversed_ends, inside))

    cam.VisionCamera._track = _track
    cam.VisionCamera._look = _look if mode == "map-of-detections" else look


def _ends_apart(a, b) -> float:
    """The summed distance (m) of two pieces' far ends and of their near ends (``x1, y1, x2, y_near``)."""
    return math.hypot(a[0] - b[0], a[1] - b[1]) + math.hypot(a[2] - b[2], a[3] - b[3])


def _deepest(tv, camera) -> float:
    """How far (m) the exact camera's piece (its chord, 21 points) reaches inside the footprint's border."""
    t = np.linspace(0.0, 1.0, 21)
    x, y = tv.x2 + t * (tv.x1 - tv.x2), tv.y_near + t * (tv.y1 - tv.y_near)
    return float(np.max(np.minimum(np.minimum(camera.half_width - np.abs(x), y), camera.depth - y)))


def main() -> None:
    from pipefollow.perception.water import CLEAR
    from tracker_suites import judge

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", nargs="+", default=list(MODES), choices=MODES)
    ap.add_argument("--suites", nargs="+", default=["mixed", "hard", "sharp"])
    ap.add_argument("--pipes", type=int, default=None)
    ap.add_argument("--noise-seed", type=int, default=0)
    args = ap.parse_args()
    print("| mode | suite | loss | lost | turned back | success | missed in view (within ½ D of the border) "
          "| false in view | shown reversed: n, Σ\\|Δa\\| of all Σ\\|Δa\\| | "
          + " | ".join(f"{e}: n, mean \\|Δa\\|" for e in EVENTS) + " |")  # fmt: skip
    print("|---" * (9 + len(EVENTS)) + "|")
    for mode in args.modes:
        for name in args.suites:
            log: list = []
            patch(mode, log)
            r = judge(name, args.pipes, "vision", "clear", args.noise_seed)
            rows = np.array(log)
            event, true_in, seen, err, rev, inside = rows.T
            both = (true_in == 1.0) & (seen == 1.0)
            missed = (true_in == 1.0) & (seen == 0.0)
            grazing = int(np.sum(missed & (inside <= 0.5 * CLEAR.pipe_diameter)))
            flipped = both & (rev == 1.0)
            cells = []
            for k in range(len(EVENTS)):
                m = both & (event == k)
                cells.append(f"{int(m.sum())}, {np.mean(err[m]) if m.any() else 0.0:.3f}")
            print(
                f"| {mode} | {name} | {r['loss']:.1f} | {len(r['lost'])} | {len(r['turned_back'])} | "
                f"{r['success']:.0%} | {int(missed.sum())} ({grazing}) | "
                f"{int(np.sum((true_in == 0.0) & (seen == 1.0)))} | "
                f"{int(flipped.sum())}, {np.sum(err[flipped]):.0f} of {np.sum(err[both]):.0f} | "
                + " | ".join(cells)
                + " |",
                flush=True,
            )


if __name__ == "__main__":
    main()
