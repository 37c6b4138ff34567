"""The pipe's line in the camera frame from successive sonar pings, and the sonar as one sensor.

:class:`SonarTrack` remembers the detections of the last pings in the earth frame and fits a
straight line through them in the current camera frame, which gives the camera's observation
``(x1, y1, x2, y_near)`` (:mod:`pipefollow.sim.camera`): the line clipped to the camera's
footprint. The direction comes from the pings behind the AUV, so at a bend it lags the camera
(which sees 3 m ahead); with one ping only the pipe is taken parallel to the track. After a ping
without a detection the remembered line, drawn from the new pose, still counts as in view for
``carry`` pings (:data:`CARRY` for the sonar alone).

:class:`SonarSensor` is one decision's work for an environment: render a ping from the pose
(:func:`~pipefollow.perception.sonar.render_ping`), detect the pipe
(:func:`~pipefollow.perception.sonar_detect.detect_profile`), update the track and, with
:meth:`SonarSensor.look`, write the observation slots of the simulation state.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.perception.slots import Sighting, sighting_of, write_sighting
from pipefollow.perception.sonar import (
    LOOK_AHEAD_SONAR,
    Ping,
    Sonar,
    beam_angles,
    check_pipe,
    check_sonar,
    fan_line,
    render_ping,
)
from pipefollow.perception.sonar_detect import THRESHOLD, SonarFix, detect_profile
from pipefollow.sim import decision as sim
from pipefollow.sim.camera import PAPER_CAMERA, CameraParams, clip_segment
from pipefollow.sim.disturbance import NO_BURIAL

# Pings after a ping without a detection during which the sonar alone still shows the remembered
# line (drawn from the new pose) if it crosses the footprint: measured on the training suites with
# every controller (docs/decisions.md, "The sonar's line carried one ping"); the fused sensor's
# sonar carries none (its tracker carries the line instead).
CARRY = 1


class SonarView(NamedTuple):
    """The camera's observation from the sonar track (camera metres; see :class:`SonarTrack`)."""

    in_view: bool  # the line crosses the camera's footprint, found by this ping or carried (``carry``)
    x1: float  # the line's far end in the footprint ...
    y1: float
    x2: float  # ... and its near end
    y_near: float
    lateral: float  # the line's lateral offset at the AUV's centre (forward 0), even outside the footprint
    angle: float  # its angle to the track (rad, positive turning to starboard ahead)
    detected: bool  # the current ping found the pipe (anywhere in the swath)
    pings: int  # detections the line was fitted to (the imaging sonar's map: highlights in the footprint)


NO_VIEW = SonarView(False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, 0)


class SonarTrack:
    """The pipe's line from the detections of successive pings (earth-frame memory).

    Each :meth:`update` stores the detection's earth position (from the pose of its ping and the
    fix's ``lateral`` and ``forward``); :meth:`view` fits ``lateral = c0 + c1·forward`` by least
    squares to the stored detections that lie within ``memory_m`` of ``along`` (the fan's line on
    the seabed, :func:`~pipefollow.perception.sonar.fan_line`) along the track in the current
    camera frame (at most ``memory`` of them, the newest) and clips the line from forward 0 to the
    footprint's depth to the footprint, as :func:`pipefollow.sim.camera.observe` clips the pipe.
    With detections spread less than ``min_spread`` m along the track the line is the newest
    detection's, parallel to the track. A ping without a detection keeps the memory; the line
    through it, drawn from the ping's pose, is still the view for ``carry`` such pings in a row
    (``detected`` False, ``in_view`` if it crosses the footprint), after which the pipe counts as
    not seen until a ping finds it again.
    """

    def __init__(
        self,
        along: float = 0.0,
        memory: int = 6,
        memory_m: float = 4.0,
        min_spread: float = 0.3,
        camera: CameraParams = PAPER_CAMERA,
        carry: int = 0,
    ) -> None:
        if isinstance(memory, bool) or not isinstance(memory, int) or memory < 1:
            raise ValueError(f"memory must be a whole number of pings ≥ 1, got {memory!r}")
        if isinstance(carry, bool) or not isinstance(carry, int) or carry < 0:
            raise ValueError(f"carry must be a whole number of pings ≥ 0, got {carry!r}")
        for name, value in (("memory_m", memory_m), ("min_spread", min_spread), ("along", along)):
            if not (isinstance(value, int | float) and math.isfinite(value)):
                raise ValueError(f"{name} must be a finite number of metres, got {value!r}")
        if memory_m <= 0.0:
            raise ValueError(f"memory_m must be a positive distance (m), got {memory_m!r}")
        if min_spread < 0.0:
            raise ValueError(f"min_spread must be ≥ 0 (m), got {min_spread!r}")
        self.along, self.memory_m, self.min_spread, self.camera = along, memory_m, min_spread, camera
        self.carry = carry
        self._ring = np.zeros((memory, 2))  # earth positions, the newest at index (count − 1) % memory
        self._count = 0
        self._misses = 0  # pings without a detection since the last one
        self.last = NO_VIEW

    def reset(self) -> None:
        """Forget every detection (a new episode)."""
        self._count = 0
        self._misses = 0
        self.last = NO_VIEW

    def update(self, pose: tuple[float, float, float], fix: SonarFix) -> SonarView:
        """Add the ping's detection (if found) taken at ``pose``; returns :meth:`view` from ``pose``."""
        self._misses = 0 if fix.found else self._misses + 1
        if fix.found:
            x, y, psi = pose
            cs, sn = math.cos(psi), math.sin(psi)
            k = self._count % self._ring.shape[0]
            self._ring[k, 0] = x + cs * fix.forward - sn * fix.lateral
            self._ring[k, 1] = y + sn * fix.forward + cs * fix.lateral
            self._count += 1
        self.last = self.view(pose, fix.found, fix.found or self._misses <= self.carry)
        return self.last

    def view(
        self, pose: tuple[float, float, float], detected: bool = True, shown: bool | None = None
    ) -> SonarView:
        """The line through the remembered detections, in the camera frame of ``pose``.

        ``shown`` (``detected`` if None): whether the line may count as in view at all.
        """
        x, y, psi = pose
        cam = self.camera
        r = _track_line(
            self._ring, self._count, float(x), float(y), float(psi),
            self.along, self.memory_m, self.min_spread, cam.half_width, cam.depth,
        )  # fmt: skip
        pings, c0, angle, clipped, x1, y1, x2, yn = r
        if pings == 0:
            return NO_VIEW
        if not (detected if shown is None else shown) or not clipped:
            return SonarView(False, 0.0, 0.0, 0.0, 0.0, c0, angle, detected, pings)
        return SonarView(True, x1, y1, x2, yn, c0, angle, detected, pings)


@njit(cache=True)
def _track_line(ring, count, x, y, psi, along, memory_m, min_spread, half_width, depth):
    """:meth:`SonarTrack.view`'s arithmetic: ``(pings, c0, angle, in footprint, x1, y1, x2, y_near)``."""
    m = ring.shape[0]
    cs, sn = math.cos(psi), math.sin(psi)
    lat = np.empty(m)
    fwd = np.empty(m)
    n = 0
    for i in range(min(count, m)):
        k = (count - 1 - i) % m  # newest first
        dx, dy = ring[k, 0] - x, ring[k, 1] - y
        lc, fc = -sn * dx + cs * dy, cs * dx + sn * dy  # sim.camera.to_camera
        if abs(fc - along) <= memory_m:
            lat[n], fwd[n] = lc, fc
            n += 1
    if n == 0:
        return 0, 0.0, 0.0, False, 0.0, 0.0, 0.0, 0.0
    mf, ml = fwd[:n].mean(), lat[:n].mean()
    if fwd[:n].max() - fwd[:n].min() < min_spread:
        c0, c1 = lat[0], 0.0  # the newest detection, along the track
    else:
        sff = sfl = 0.0
        for i in range(n):
            sff += (fwd[i] - mf) ** 2
            sfl += (fwd[i] - mf) * (lat[i] - ml)
        c1 = sfl / sff
        c0 = ml - c1 * mf
    t0, t1 = clip_segment(c0, 0.0, c0 + c1 * depth, depth, -half_width, half_width, 0.0, depth)
    if t0 > t1:
        return n, c0, math.atan(c1), False, 0.0, 0.0, 0.0, 0.0
    return n, c0, math.atan(c1), True, c0 + t1 * c1 * depth, t1 * depth, c0 + t0 * c1 * depth, t0 * depth


class SonarSensor:
    """The multibeam sonar of one vehicle: render, detect and track once per decision.

    ``burial`` is the buried share of the pipe's diameter everywhere; the buried stretches of
    :meth:`step` bury the pipe fully. The sensor draws from the generator it is given only
    (:func:`~pipefollow.perception.sonar.render_ping` says what).
    """

    def __init__(
        self,
        sonar: Sonar = LOOK_AHEAD_SONAR,
        diameter: float = 0.25,
        burial: float = 0.0,
        threshold: float = THRESHOLD,
        camera: CameraParams = PAPER_CAMERA,
        memory: int = 6,
        memory_m: float = 4.0,
        carry: int = CARRY,
    ) -> None:
        self.sonar = check_sonar(sonar)
        check_pipe(diameter, burial)
        self.diameter, self.burial, self.threshold = float(diameter), float(burial), float(threshold)
        self.track = SonarTrack(fan_line(self.sonar), memory, memory_m, camera=camera, carry=carry)
        self._angles = beam_angles(self.sonar)
        self._ranges = np.empty(self.sonar.n_beams)
        self.ping: Ping | None = None
        self.fix = SonarFix(False)
        self.view = NO_VIEW
        self._last = Sighting()  # the last sighting's slots (starboard if none)

    def reset(self) -> None:
        """A new episode: forget the track."""
        self.track.reset()
        self.ping, self.fix, self.view = None, SonarFix(False), NO_VIEW
        self._last = Sighting()

    def step(
        self,
        points: np.ndarray,
        cum: np.ndarray,
        pose: tuple[float, float, float],
        rng: np.random.Generator,
        buried_from=NO_BURIAL,
        buried_to=NO_BURIAL,
    ) -> SonarView:
        """One ping from ``pose`` over the pipeline; returns the camera-frame view (also ``self.view``)."""
        self.ping = render_ping(
            points, cum, pose, rng, self.sonar, self.diameter, self.burial, buried_from, buried_to,
            angles=self._angles, out=self._ranges,
        )  # fmt: skip
        self.fix = detect_profile(self.ping, self.diameter, self.threshold)
        self.view = self.track.update(pose, self.fix)
        return self.view

    def look(
        self,
        state: np.ndarray,
        points: np.ndarray,
        cum: np.ndarray,
        rng: np.random.Generator,
        buried_from=NO_BURIAL,
        buried_to=NO_BURIAL,
    ) -> SonarView:
        """:meth:`step` from the simulation state's pose, then its observation slots from the view.

        As the vision camera does (:class:`~pipefollow.perception.camera.VisionCamera`): while the
        pipe is in view, ``x1, y1, x2, y_near``, the tracking errors and the side of the sighting
        come from the view; otherwise they keep the last sighting's, and ``IN_VIEW`` is 0 (a lost
        pipe: the next decision searches).
        """
        view = self.step(
            points, cum, (state[sim.X], state[sim.Y], state[sim.PSI]), rng, buried_from, buried_to
        )
        if view.in_view:
            self._last = sighting_of(view.x1, view.y1, view.x2, view.y_near)
        write_sighting(state, self._last, view.in_view)
        return view


__all__ = ["CARRY", "NO_VIEW", "SonarSensor", "SonarTrack", "SonarView"]
