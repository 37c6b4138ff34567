"""A map of the pipe pieces a forward-looking sonar found, and the piece of it in the camera's footprint.

The imaging sonar (:mod:`pipefollow.perception.imaging_sonar`) sees a strip of seabed 1.4–2.9 m
ahead; the camera's footprint reaches from under the AUV's nose to 3 m ahead. What the sonar found
a few pings ago lies in the footprint now: :class:`ImagingTrack` keeps the pieces of the last
``memory`` pings that found one (:func:`~pipefollow.perception.imaging_detect.detect_image`) in the
earth frame, placed by the pose of their ping, and shows from a pose the pipe in the footprint as
the camera would (:mod:`pipefollow.sim.camera`): the near end where the oldest remembered piece
that crosses the footprint enters it, the far end where the newest one leaves it.

Each piece's way (which end is further along the pipe) follows the piece before it: a piece along
the same line (directions within :data:`SAME_LINE_DEG`, the new piece's middle within
:data:`SAME_LINE_M` of the old piece's line) keeps its direction; another (a new leg after a bend)
starts at the end nearer the old piece's far end; the first piece of an episode runs away from
the AUV (its far end the one further forward).

:class:`ImagingSensor` is one decision's work for an environment, with the profiler's
:class:`~pipefollow.perception.sonar_track.SonarSensor`'s interface (``reset``, ``step``,
``fix``, ``view``): render a ping, detect the pipe, update the map, show it.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pipefollow.perception.imaging_detect import MAX_PIECES, ImageFix, detect_image
from pipefollow.perception.imaging_sonar import (
    FLS,
    ImagingSonar,
    bearings,
    bin_ranges,
    check_imaging_sonar,
    render_image,
)
from pipefollow.perception.sonar_detect import SonarFix
from pipefollow.perception.sonar_track import NO_VIEW, SonarView
from pipefollow.sim.camera import PAPER_CAMERA, CameraParams, clip_segment
from pipefollow.sim.disturbance import NO_BURIAL

MEMORY = 8  # pings whose pieces the map keeps
SAME_LINE_DEG = 30.0  # a piece within this of the one before ...
SAME_LINE_M = 0.25  # ... and its middle this near its line keeps its direction


class ImagingTrack:
    """The map of the pieces found (module docstring); :meth:`update` adds one, :meth:`view` shows it."""

    def __init__(self, memory: int = MEMORY, camera: CameraParams = PAPER_CAMERA) -> None:
        if isinstance(memory, bool) or not isinstance(memory, int) or memory < 1:
            raise ValueError(f"memory must be a whole number of pings ≥ 1, got {memory!r}")
        self.memory, self.camera = memory, camera
        # earth x, y of one end and of the other, the ping's index; the newest at (count − 1) % len
        self._pieces = np.zeros((memory * MAX_PIECES, 5))
        self._count = 0
        self._ping = 0
        self.last = NO_VIEW

    def reset(self) -> None:
        """Forget every piece (a new episode)."""
        self._count = 0
        self._ping = 0
        self.last = NO_VIEW

    def update(self, pose: tuple[float, float, float], fix: ImageFix) -> SonarView:
        """Add the ping's pieces (if any) seen from ``pose``; returns :meth:`view` from ``pose``."""
        x, y, psi = pose
        self._ping += 1
        cs, sn = math.cos(psi), math.sin(psi)
        for x1, y1, x2, y2, _ in fix.pieces if fix.found else ():
            # camera (lateral l, forward f) to earth: x + f cos ψ - l sin ψ, y + f sin ψ + l cos ψ
            far = x + cs * y1 - sn * x1, y + sn * y1 + cs * x1
            near = x + cs * y2 - sn * x2, y + sn * y2 + cs * x2
            if self._count > 0:
                far, near = _oriented(self._pieces[(self._count - 1) % self._pieces.shape[0]], far, near)
            k = self._count % self._pieces.shape[0]
            self._pieces[k] = (*far, *near, self._ping)
            self._count += 1
        self.last = self.view(pose, fix.found)
        return self.last

    def view(self, pose: tuple[float, float, float], detected: bool = True) -> SonarView:
        """The remembered pipe in the camera's footprint from ``pose`` (module docstring)."""
        x, y, psi = pose
        cam = self.camera
        r = _span(self._pieces, self._count, self._ping - self.memory, float(x), float(y), float(psi),
                      cam.half_width, cam.depth)  # fmt: skip
        n, x1, y1, x2, yn, lateral, angle = r
        if n == 0:
            return SonarView(False, 0.0, 0.0, 0.0, 0.0, lateral, angle, detected, 0)
        return SonarView(True, x1, y1, x2, yn, lateral, angle, detected, n)


def _oriented(prev, far, near):
    """The new piece's ends, far first, its way following the previous piece's."""
    (fx, fy), (nx, ny) = far, near
    pfx, pfy, pnx, pny = prev[0], prev[1], prev[2], prev[3]
    px, py = pfx - pnx, pfy - pny
    qx, qy = fx - nx, fy - ny
    lp, lq = math.hypot(px, py), math.hypot(qx, qy)
    if lp > 0.0 and lq > 0.0:
        cos_a = (px * qx + py * qy) / (lp * lq)
        mx, my = 0.5 * (fx + nx), 0.5 * (fy + ny)
        off = abs((mx - pnx) * py - (my - pny) * px) / lp  # the new middle's distance from the old line
        if abs(cos_a) >= math.cos(math.radians(SAME_LINE_DEG)) and off <= SAME_LINE_M:
            return (far, near) if cos_a >= 0.0 else (near, far)
    # a new leg: it starts at the end nearer the previous piece's far end
    if math.hypot(fx - pfx, fy - pfy) < math.hypot(nx - pfx, ny - pfy):
        return near, far
    return far, near


@njit(cache=True)
def _span(P, count, oldest_ping, x, y, psi, half_width, depth):
    """``(pieces crossing, x1, y1, x2, y_near, lateral, angle)`` (module docstring)."""
    m = P.shape[0]
    cs, sn = math.cos(psi), math.sin(psi)
    n = 0
    x1 = y1 = x2 = yn = 0.0
    lateral = angle = 0.0
    have_line = False
    for i in range(min(count, m)):
        k = (count - 1 - i) % m  # newest first
        if P[k, 4] <= oldest_ping:
            break
        dx, dy = P[k, 0] - x, P[k, 1] - y
        fl, ff = -sn * dx + cs * dy, cs * dx + sn * dy
        dx, dy = P[k, 2] - x, P[k, 3] - y
        nl, nf = -sn * dx + cs * dy, cs * dx + sn * dy
        if not have_line:  # the newest piece's line: its lateral offset at the AUV, its angle to the track
            have_line = True
            angle = math.atan2(fl - nl, ff - nf)
            if abs(ff - nf) > 1e-9:
                lateral = nl - nf * (fl - nl) / (ff - nf)
        t0, t1 = clip_segment(nl, nf, fl, ff, -half_width, half_width, 0.0, depth)
        if t0 > t1:
            continue
        if n == 0:  # the newest crossing piece: its far end in the footprint
            x1, y1 = nl + t1 * (fl - nl), nf + t1 * (ff - nf)
        x2, yn = nl + t0 * (fl - nl), nf + t0 * (ff - nf)  # the oldest so far: its near end
        n += 1
    return n, x1, y1, x2, yn, lateral, angle


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
        self.diameter, self.burial = float(diameter), float(burial)
        self.track = ImagingTrack(memory, camera)
        self.detect = dict(detect or {})  # detect_image's settings
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


__all__ = ["ImagingSensor", "ImagingTrack"]
