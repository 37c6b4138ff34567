"""Where the tracked line's way goes wrong: the decisions shown reversed, traced to where the line turned.

Usage: ``python benchmarks/tracker_way.py [--suites mixed hard sharp] [--pipes N] [--noise-seed 0]
[--show K]``

Runs the heuristic through ``camera="vision"`` in clear water (as ``benchmarks/tracker_suites.py``
does) and logs, per decision, the tracker's state before and after the frame, the detection, the
navigation's motion and the exact camera's piece. A decision is *shown reversed* as
``benchmarks/tracker_ablation.py`` counts it (the exact camera's piece within 0.3 m, drawn the
other way). Each reversed decision is traced back over the decisions before it whose tracked line
runs against the exact camera's piece (the line's direction against the piece's near → far chord)
to the frame where that run began, and that frame's rule is named: the event, and for a new line
the way's rule (``_start_line``'s mode, re-run on a copy of the state) and whether the detector's
own order of the ends was right. Prints a table of the onsets by rule (the number of runs, the
reversed decisions and their summed far-end error |Δa|) and, with ``--show``, the first ``K``
onsets of the commonest rule with the state around them.

It replaces ``VisionCamera._track`` and ``tracker.track_step`` in this process only.
"""

from __future__ import annotations

import argparse
import math
from collections import defaultdict

import numpy as np

from tracker_ablation import EVENTS, SAME_PIECE
from tracker_ablation import _ends_apart as _apart

MODES = ("as-given", "towards-far", "after-line", "contradicted")


def _install(log: list) -> None:
    from pipefollow.learners.heuristic import heuristic_action
    from pipefollow.perception import camera as cam
    from pipefollow.perception import track_step as ts
    from pipefollow.perception import tracker as tr

    real = ts.track_step
    pending: dict = {}

    def step(T, found, det, motion, nav_var, tp, hw, depth, out, frame=ts.CLEAR_FRAME):
        pending.update(before=T.copy(), found=bool(found), det=det.copy(), motion=motion.copy(),
                       nav_var=nav_var.copy(), tp=tp, hw=hw, depth=depth, frame=frame)  # fmt: skip
        real(T, found, det, motion, nav_var, tp, hw, depth, out, frame)

    tr.track_step = step

    def _track(self, s, pose, det, frame=ts.CLEAR_FRAME):
        new_episode = self.tracker._pose is None
        out = self.tracker.step(pose, det.found, (det.x1, det.y1, det.x2, det.y_near), frame).copy()
        self._show(s, out)
        tv = self.truth
        row = dict(pending, after=self.tracker.state.copy(), out=out, truth=tuple(tv), new=new_episode)
        row["err"] = math.nan
        row["rev"] = False
        if out[0] and tv.in_view:
            row["err"] = abs(heuristic_action(out[1], out[2]) - heuristic_action(tv.x1, tv.y1))
            flipped = _apart(out[1:5], (tv.x2, tv.y_near, tv.x1, tv.y1))
            row["rev"] = flipped < min(SAME_PIECE, _apart(out[1:5], tv[1:5]))
        log.append(row)

    cam.VisionCamera._track = _track


def line_against(row) -> bool:
    """Whether the tracked line (after the frame) runs against the exact camera's near → far chord."""
    from pipefollow.perception import track_step as ts

    T, tv = row["after"], row["truth"]
    if not tv[0] or T[ts.ACTIVE] == 0.0:
        return False
    dx, dy = tv[1] - tv[3], tv[2] - tv[4]
    if math.hypot(dx, dy) < 0.2:
        return False
    return math.sin(T[ts.TH]) * dx + math.cos(T[ts.TH]) * dy < 0.0


def rule(row) -> str:
    """The frame's rule: the event, and for a new line its way's mode and whether it reversed the detector."""
    from pipefollow.perception import track_step as ts

    ev = EVENTS[int(row["after"][ts.EVENT])]
    if ev not in ("started", "replaced"):
        if ev == "bend":
            tv = row["truth"]
            nx, ny = row["after"][ts.NEAR_X], row["after"][ts.NEAR_Y]
            near_is_true_far = math.hypot(nx - tv[1], ny - tv[2]) < math.hypot(nx - tv[3], ny - tv[4])
            return "bend (near end taken is the exact far end)" if near_is_true_far else "bend"
        return ev
    seen: list = []
    real = ts._start_line

    def start_line(T, x1, y1, x2, y_near, point_sd, hw, depth, border, mode):
        th, d, *_ = ts.measured_line(x2, y_near, x1, y1, point_sd)
        seen.append(
            (mode, bool(ts._reversed(T, x1, y1, x2, y_near, th, d, mode, point_sd)), (x1, y1, x2, y_near))
        )
        real(T, x1, y1, x2, y_near, point_sd, hw, depth, border, mode)

    ts._start_line = start_line
    try:
        T = row["before"].copy()
        ts.track_step.py_func(T, row["found"], row["det"].copy(), row["motion"], row["nav_var"], row["tp"],
                              row["hw"], row["depth"], np.zeros(ts.OUT_SIZE), row["frame"])  # fmt: skip
    finally:
        ts._start_line = real
    mode, flipped, ends = seen[-1]
    tv = row["truth"]
    given_right = _apart(ends, tv[1:5]) < _apart(ends, (tv[3], tv[4], tv[1], tv[2]))
    det = row["det"]
    det_right = _apart(det, tv[1:5]) < _apart(det, (tv[3], tv[4], tv[1], tv[2]))
    way = " reversed" if flipped else ""
    given, detector = ("right" if given_right else "wrong"), ("right" if det_right else "wrong")
    return f"{ev} {MODES[mode]}{way} (given {given}, detector {detector})"


def onsets(log: list) -> list:
    """Per reversed decision: the index of the frame where its run of a line against the pipe began."""
    out = []
    for k, row in enumerate(log):
        if not row["rev"]:
            continue
        j = k
        while j > 0 and not log[j]["new"] and line_against(log[j - 1]):
            j -= 1
        out.append((k, j))
    return out


def main() -> None:
    from tracker_suites import judge

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suites", nargs="+", default=["mixed", "hard", "sharp"])
    ap.add_argument("--pipes", type=int, default=None)
    ap.add_argument("--noise-seed", type=int, default=0)
    ap.add_argument("--show", type=int, default=0)
    args = ap.parse_args()
    for name in args.suites:
        log: list = []
        _install(log)
        judge(name, args.pipes, "vision", "clear", args.noise_seed)
        n_rev = sum(r["rev"] for r in log)
        print(f"## {name}: {len(log)} decisions, {n_rev} shown reversed, "
              f"Σ|Δa| {np.nansum([r['err'] for r in log if r['rev']]):.0f}")  # fmt: skip
        groups: dict = defaultdict(lambda: [set(), 0, 0.0])
        for k, j in onsets(log):
            if not line_against(log[k]) and j == k:  # the line's way right: the shown ends are not the line's
                key = "line right, shown ends reversed: " + rule(log[k])
            else:
                key = rule(log[j])
            g = groups[key]
            g[0].add(j)
            g[1] += 1
            g[2] += log[k]["err"]
        for key, (runs, n, e) in sorted(groups.items(), key=lambda kv: -kv[1][2]):
            print(f"  {n:4d} decisions, {len(runs):3d} runs, Σ|Δa| {e:6.1f}: {key}")
            if args.show:
                for j in sorted(runs)[: args.show]:
                    _print_around(log, j)


def _print_around(log: list, j: int) -> None:
    from pipefollow.perception import track_step as ts

    for i in range(max(0, j - 2), min(len(log), j + 2)):
        r = log[i]
        T0, T1, d, tv = r["before"], r["after"], r["det"], r["truth"]
        print(f"      [{i}{'*' if i == j else ''}] ev={EVENTS[int(T1[ts.EVENT])]} found={r['found']} "
              f"det=({d[0]:.2f},{d[1]:.2f})<-({d[2]:.2f},{d[3]:.2f}) "
              f"truth=({tv[1]:.2f},{tv[2]:.2f})<-({tv[3]:.2f},{tv[4]:.2f}) "
              f"th {T0[ts.TH]:.2f}->{T1[ts.TH]:.2f} d {T0[ts.D]:.2f}->{T1[ts.D]:.2f} "
              f"act {T0[ts.ACTIVE]:.0f}->{T1[ts.ACTIVE]:.0f} far {T1[ts.HAS_FAR]:.0f}({T1[ts.FAR_X]:.2f},"
              f"{T1[ts.FAR_Y]:.2f}) end {T1[ts.HAS_END]:.0f} out=({r['out'][1]:.2f},{r['out'][2]:.2f})<-"
              f"({r['out'][3]:.2f},{r['out'][4]:.2f}) rev={r['rev']} against={line_against(r)}")  # fmt: skip


if __name__ == "__main__":
    main()
