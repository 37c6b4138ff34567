"""A map of what a forward-looking sonar saw, and the pipe it shows in the camera's footprint.

The imaging sonar (:mod:`pipefollow.perception.imaging_sonar`) images the seabed 0.9–3.9 m
ahead, its vertical beam mostly 1.4–2.9 m; the camera's footprint reaches from under the AUV's
nose to 3 m ahead. What the sonar saw a few pings ago lies in the footprint now.
:class:`ImagingMap` keeps the highlights
(:attr:`~pipefollow.perception.imaging_detect.ImageFix.points`) of the last ``memory`` pings in the
earth frame, placed by the pose of their ping, and at each decision runs the detector's line
search (:func:`~pipefollow.perception.imaging_detect.line_piece`) on those that now lie in the
footprint (within :data:`MARGIN`): the strongest line, and a second one among the others that
meets it at more than :data:`BEND_DEG` within :data:`LINK_M` of both pieces (a bend: two legs).

Which end is which (the pipe's way), as the camera's near end is where the pipe enters the
footprint and its far end where it leaves:

* two legs: the near leg is the one nearer the last view's near end (remembered in the earth
  frame; the AUV's centre in the first view), the near end its end away from the corner, the far
  end the other leg's end away from it;
* one line: the way of the last view (remembered as a direction in the earth frame) if there was
  one; else its end nearer the AUV's centre is the near end. The line is the strongest; with no
  last view (the first, or after a view without the pipe) and a second line found, the one of the
  two that passes nearer the AUV's centre (at a hook the strongest can be the leg beyond the corner).

Each end is clipped to the footprint along its line (a leg's towards the corner), which keeps
the line's direction (clamped coordinate by coordinate if the line misses the footprint, within
:data:`MARGIN` of it). docs/decisions.md ("A forward-looking imaging sonar") has
the readings measured beside this one (a map of each ping's straight piece; the newer highlights'
end as the far one; no memory of the last near end).

:class:`ImagingSensor` is one decision's work for an environment, with the profiler's
:class:`~pipefollow.perception.sonar_track.SonarSensor`'s interface (``reset``, ``step``,
``fix``, ``view``): render a ping, detect the pipe, update the map, show it.
"""

from __future__ import annotations

import inspect
import math

import numpy as np
from numba import njit

from pipefollow.perception.imaging_detect import (
    FACE,
    HOUGH_BIN,
    HOUGH_STEP_DEG,
    INLIER,
    MAX_CELLS,
    MIN_CELLS,
    MIN_LENGTH,
    ImageFix,
    detect_image,
    line_piece,
)
from pipefollow.perception.imaging_sonar import (
    FLS,
    ImagingSonar,
    bearings,
    bin_ranges,
    check_imaging_sonar,
    render_image,
)
from pipefollow.perception.sonar import check_pipe
from pipefollow.perception.sonar_detect import SonarFix
from pipefollow.perception.sonar_track import NO_VIEW, SonarView
from pipefollow.sim.camera import PAPER_CAMERA, CameraParams, clip_segment, to_camera
from pipefollow.sim.disturbance import NO_BURIAL

# the map's settings, chosen on the training suites (docs/decisions.md, "A forward-looking imaging sonar")
MEMORY = 8  # pings whose highlights the map keeps
MARGIN = 0.1  # m: highlights this far outside the footprint still count in it
BEND_DEG = 25.0  # two lines closer in direction than this are one leg
LINK_M = 1.0  # m: two legs whose pieces come this near their lines' crossing meet at a bend


class ImagingMap:
    """The last ``memory`` pings' highlights and the pipe they show in the footprint (module docstring)."""

    def __init__(self, memory: int = MEMORY, camera: CameraParams = PAPER_CAMERA, diameter: float = 0.25,
                 along: float = 0.0) -> None:  # fmt: skip
        if isinstance(memory, bool) or not isinstance(memory, int) or memory < 1:
            raise ValueError(f"memory must be a whole number of pings ≥ 1, got {memory!r}")
        self.memory, self.camera = memory, camera
        self._points = np.zeros((memory * MAX_CELLS, 3))  # earth x, y, ping; the newest at (count-1) % len
        self._count = 0
        self._ping = 0
        self._last = np.full(4, math.nan)  # the last view's way and near end (earth), NaN for none
        st = (MIN_CELLS, MIN_LENGTH, INLIER, math.radians(HOUGH_STEP_DEG), HOUGH_BIN, along,
              FACE * 0.5 * diameter, math.radians(BEND_DEG), LINK_M, MARGIN)  # fmt: skip
        self._settings = np.array(st, dtype=np.float64)
        self.last = NO_VIEW

    def reset(self) -> None:
        """Forget every highlight (a new episode)."""
        self._count = 0
        self._ping = 0
        self._last[:] = math.nan
        self.last = NO_VIEW

    def update(self, pose: tuple[float, float, float], fix: ImageFix) -> SonarView:
        """Add the ping's highlights seen from ``pose``; returns :meth:`view` from ``pose``."""
        x, y, psi = pose
        self._ping += 1
        self._count = _add_points(
            self._points, self._count, fix.points, float(x), float(y), float(psi), self._ping
        )
        self.last = self._view(pose, fix.found, self._last)
        return self.last

    def view(self, pose: tuple[float, float, float], detected: bool = True) -> SonarView:
        """The pipe the highlights show in the camera's footprint from ``pose`` (class docstring).

        A look from any pose: the map's memory of the last view's way and near end, which
        :meth:`update` keeps, is not changed.
        """
        return self._view(pose, detected, self._last.copy())

    def _view(self, pose, detected: bool, last: np.ndarray) -> SonarView:
        x, y, psi = pose
        cam = self.camera
        r = _map_view(self._points, self._count, self._ping - self.memory, float(x), float(y), float(psi),
                      cam.half_width, cam.depth, self._settings, last)  # fmt: skip
        n, x1, y1, x2, yn, lateral, angle = r  # n: the highlights the view was found in (SonarView.pings)
        if n == 0:
            return SonarView(False, 0.0, 0.0, 0.0, 0.0, lateral, angle, detected, 0)
        return SonarView(True, x1, y1, x2, yn, lateral, angle, detected, n)


@njit(cache=True)
def _add_points(E, count, points, x, y, psi, ping):
    cs, sn = math.cos(psi), math.sin(psi)
    m = E.shape[0]
    for i in range(points.shape[0]):
        k = count % m
        l, f = points[i, 0], points[i, 1]
        E[k, 0], E[k, 1], E[k, 2] = x + cs * f - sn * l, y + sn * f + cs * l, ping
        count += 1
    return count


@njit(cache=True)
def _map_view(E, count, oldest, x, y, psi, half_width, depth, st, last):
    """:meth:`ImagingMap.view`'s arithmetic: ``(highlights used, x1, y1, x2, y_near, lateral, angle)``.

    ``last`` holds the last view's way (earth frame, 0–1) and near end (2–3), NaN for none; updated.
    """
    min_cells, min_length, inlier, d_theta, d_bin = int(st[0]), st[1], st[2], st[3], st[4]
    along, shift, bend, link, margin = st[5], st[6], st[7], st[8], st[9]
    m = E.shape[0]
    cs, sn = math.cos(psi), math.sin(psi)
    live = min(count, m)
    px, py = np.empty(live), np.empty(live)
    n = 0
    for i in range(live):
        k = (count - 1 - i) % m
        if E[k, 2] <= oldest:
            break
        dx, dy = E[k, 0] - x, E[k, 1] - y
        l, f = -sn * dx + cs * dy, cs * dx + sn * dy
        if abs(l) <= half_width + margin and -margin <= f <= depth + margin:
            px[n], py[n] = l, f
            n += 1
    used = np.zeros(n, dtype=np.bool_)
    fa, ax1, ay1, ax2, ay2, ma = line_piece(
        px, py, used, n, min_cells, min_length, inlier, d_theta, d_bin, along, shift
    )
    if not fa:
        last[:] = math.nan
        return 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    fb, bx1, by1, bx2, by2, mb = line_piece(
        px, py, used, n, min_cells, min_length, inlier, d_theta, d_bin, along, shift
    )
    ux, uy = ax1 - ax2, ay1 - ay2
    vx, vy = bx1 - bx2, by1 - by2
    la, lb = math.hypot(ux, uy), math.hypot(vx, vy)
    two = False
    if fb and la > 0.0 and lb > 0.0:
        cross = (ux * vy - uy * vx) / (la * lb)
        if abs(cross) >= math.sin(bend):
            # the lines' crossing: a + s u = b + t v
            s_ = ((bx2 - ax2) * vy - (by2 - ay2) * vx) / (ux * vy - uy * vx)
            cx, cy = ax2 + s_ * ux, ay2 + s_ * uy
            da = _to_segment(cx, cy, ax1, ay1, ax2, ay2)
            db = _to_segment(cx, cy, bx1, by1, bx2, by2)
            two = da <= link and db <= link
    if two:
        # the leg nearer the last near end (else the AUV's centre) is the near one; each leg's end
        # away from the corner
        ox, oy = 0.0, 0.0
        if last[2] == last[2]:
            ox, oy = to_camera(last[2], last[3], x, y, psi)
        if _to_segment(ox, oy, bx1, by1, bx2, by2) < _to_segment(ox, oy, ax1, ay1, ax2, ay2):
            ax1, ay1, ax2, ay2, bx1, by1, bx2, by2 = bx1, by1, bx2, by2, ax1, ay1, ax2, ay2
        if math.hypot(ax1 - cx, ay1 - cy) > math.hypot(ax2 - cx, ay2 - cy):
            nx, ny = ax1, ay1
        else:
            nx, ny = ax2, ay2
        if math.hypot(bx1 - cx, by1 - cy) > math.hypot(bx2 - cx, by2 - cy):
            fx, fy = bx1, by1
        else:
            fx, fy = bx2, by2
    else:
        if fb and la > 0.0 and lb > 0.0 and last[2] != last[2]:
            # no last view (the first, or after one without the pipe): the pipe the AUV is on passes
            # nearest its centre; the strongest line can be another leg (a hook's, beyond the corner)
            if _to_segment(0.0, 0.0, bx1, by1, bx2, by2) < _to_segment(0.0, 0.0, ax1, ay1, ax2, ay2):
                ax1, ay1, ax2, ay2 = bx1, by1, bx2, by2
        nx, ny, fx, fy = ax2, ay2, ax1, ay1
        if math.hypot(ax2, ay2) > math.hypot(ax1, ay1):  # the end nearer the AUV's centre is the near end ...
            nx, ny, fx, fy = ax1, ay1, ax2, ay2
        if last[0] == last[0]:  # ... unless that turns the last view's way round
            gl, gf = -sn * last[0] + cs * last[1], cs * last[0] + sn * last[1]  # the last way in this frame
            if (fx - nx) * gl + (fy - ny) * gf < 0.0:
                nx, ny, fx, fy = fx, fy, nx, ny
    # each end clipped to the footprint along its own leg (towards the corner) or the line
    if two:
        nx, ny = _clip_end(nx, ny, cx, cy, half_width, depth)
        fx, fy = _clip_end(fx, fy, cx, cy, half_width, depth)
    else:
        near = _clip_end(nx, ny, fx, fy, half_width, depth)
        fx, fy = _clip_end(fx, fy, nx, ny, half_width, depth)
        nx, ny = near
    el, ef = fx - nx, fy - ny  # the way near → far, and the near end, in the earth frame
    last[0], last[1] = cs * ef - sn * el, sn * ef + cs * el
    last[2], last[3] = x + cs * ny - sn * nx, y + sn * ny + cs * nx
    angle = math.atan2(fx - nx, fy - ny)
    lateral = nx - ny * (fx - nx) / (fy - ny) if abs(fy - ny) > 1e-9 else nx
    return n, fx, fy, nx, ny, lateral, angle


@njit(cache=True)
def _clip_end(px, py, qx, qy, half_width, depth):
    """The end ``p`` of the segment ``q``–``p`` clipped to the footprint |x| ≤ half_width, 0 ≤ y ≤ depth.

    ``p`` if it lies inside; else where the segment, followed from ``q``, last leaves the footprint;
    ``p`` clamped coordinate by coordinate if the segment misses the footprint (a line within the
    margin only).
    """
    t0, t1 = clip_segment(qx, qy, px, py, -half_width, half_width, 0.0, depth)
    if t0 > t1:
        return min(max(px, -half_width), half_width), min(max(py, 0.0), depth)
    return qx + t1 * (px - qx), qy + t1 * (py - qy)


@njit(cache=True)
def _to_segment(px, py, ax, ay, bx, by):
    """The distance from point p to the segment a–b."""
    ux, uy = bx - ax, by - ay
    uu = ux * ux + uy * uy
    t = 0.0 if uu == 0.0 else min(max(((px - ax) * ux + (py - ay) * uy) / uu, 0.0), 1.0)
    return math.hypot(ax + t * ux - px, ay + t * uy - py)


# detect_image's settings an ImagingSensor takes (``detect=``): its arguments but those the sensor passes
DETECT_SETTINGS = tuple(
    k
    for k in inspect.signature(detect_image).parameters
    if k not in ("image", "diameter", "angles", "ranges")
)


class ImagingSensor:
    """The forward-looking imaging sonar of one vehicle: render, detect and map once per decision.

    ``burial`` is the buried share of the pipe's diameter everywhere; the buried stretches of
    :meth:`step` bury the pipe fully. The sensor draws from the generator it is given only
    (:func:`~pipefollow.perception.imaging_sonar.render_image` says what). :attr:`fix` is the
    ping's piece's middle as a :class:`~pipefollow.perception.sonar_detect.SonarFix` (the point
    the fused sensor puts on its tracked line), :attr:`view` the map's piece in the footprint.
    """

    def __init__(
        self,
        sonar: ImagingSonar = FLS,
        diameter: float = 0.25,
        burial: float = 0.0,
        camera: CameraParams = PAPER_CAMERA,
        memory: int = MEMORY,
        detect: dict | None = None,
    ) -> None:
        self.sonar = check_imaging_sonar(sonar)
        check_pipe(diameter, burial)
        self.diameter, self.burial = float(diameter), float(burial)
        self.track = ImagingMap(memory, camera, diameter, self.sonar.along)
        self.detect = dict(detect or {})  # detect_image's settings
        unknown = sorted(set(self.detect) - set(DETECT_SETTINGS))
        if unknown:
            raise ValueError(f"unknown detect setting(s) {unknown}; allowed: {', '.join(DETECT_SETTINGS)}")
        self._angles, self._ranges = bearings(self.sonar), bin_ranges(self.sonar)
        self._mean = np.empty((self.sonar.n_beams, self._ranges.size))
        self.image = None
        self.piece = ImageFix(False)
        self.fix = SonarFix(False)
        self.view = NO_VIEW

    def reset(self) -> None:
        """A new episode: forget the map."""
        self.track.reset()
        self.image, self.piece, self.fix, self.view = None, ImageFix(False), SonarFix(False), NO_VIEW

    def step(
        self, points, cum, pose, rng: np.random.Generator, buried_from=NO_BURIAL, buried_to=NO_BURIAL
    ) -> SonarView:
        """One ping from ``pose`` over the pipeline; returns the camera-frame view (also ``self.view``)."""
        self.image = render_image(
            points, cum, pose, rng, self.sonar, self.diameter, self.burial, buried_from, buried_to,
            angles=self._angles, out=self._mean,
        )  # fmt: skip
        p = self.piece = detect_image(self.image, self.diameter, angles=self._angles, ranges=self._ranges,
                                          **self.detect)  # fmt: skip
        v = self.view = self.track.update(pose, p)
        if p.found:  # the strongest piece's middle
            self.fix = SonarFix(
                True, lateral=0.5 * (p.x1 + p.x2), forward=0.5 * (p.y1 + p.y2), confidence=p.confidence
            )
        else:
            self.fix = SonarFix(False)
        return v


__all__ = ["ImagingMap", "ImagingSensor"]
