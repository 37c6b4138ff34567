"""The sensor of the environments: the camera, the multibeam sonar, or both into one estimate.

``sensor="camera"`` (the default) is the camera of ``camera=`` alone: the environments then hold
a :class:`~pipefollow.perception.camera.VisionCamera` (or nothing for the ideal camera's state),
exactly as before this module existed. ``sensor="sonar"`` and ``sensor="fused"`` hold a
:class:`SonarSensors`, which has the vision camera's interface (``reset``, ``step``,
``observation``, ``info``, ``panel``):

* ``"sonar"``: the observation slots (``x1, y1, x2, y_near``, ``e_dist``, ``e_angl``, in view, the
  side of the last sighting) come from :class:`~pipefollow.perception.sonar_track.SonarSensor`
  (the look-ahead fan): the water's turbidity does not reach it. After a ping that misses the
  pipe, the line through the remembered detections still shows it for
  :data:`~pipefollow.perception.sonar_track.CARRY` ping(s) if it crosses the footprint (not when
  it feeds a rendered camera's measurements, below: the tracker carries the line). A lost pipe keeps the last
  sighting, is a lost decision (−10) and the next decision searches, as with the vision camera.
* ``"fused"``: one estimate from both sensors. Each decision the camera's own measurement comes
  first; when it finds no pipe the sonar's view of the pipe is the measurement instead
  (:attr:`VisionCamera.fallback`): with ``camera="vision"`` that measurement feeds the same pipe
  tracker (:mod:`pipefollow.perception.tracker`) with its gates, and in a frame whose detection the
  tracker did not take the ping's fix then corrects the tracked line as a point on the pipe with
  its own error (:data:`FIX_SD`; :attr:`VisionCamera.aid`, :meth:`PipeTracker.point`); with
  ``"vision-raw"`` the measurement is the observation, and with the ideal camera the sonar's view
  fills the slots while the exact camera does not see the pipe. A frame whose contrast over its
  noise is below :data:`~pipefollow.perception.visibility.MIN_CONTRAST`
  (:func:`~pipefollow.perception.visibility.clear_enough`; murky water) is not searched: the
  sonar alone feeds the track then, which carries its line
  :attr:`~pipefollow.perception.track_step.TrackParams.unsearched_misses` frames without a
  sighting. The first ping feeds the first frame. In such a murky frame, and while the track
  shows no pipe, the sonar's own view is the observation if it has the pipe in the footprint (the
  track, fed all the same, is shown when the ping misses), and a fix outside the footprint turns
  the search towards it.

``"fls"`` and ``"fused-fls"`` are ``"sonar"`` and ``"fused"`` with the forward-looking imaging sonar
(:class:`~pipefollow.perception.imaging_track.ImagingSensor`: a sector image ahead, its highlights
kept in a map of the last pings) in the profiler's place, everything else as above, but for three
things: the map's view is the camera's measurement only after a ping that found the pipe (after a
miss the map still shows what earlier pings saw, which is no new measurement); in a murky
frame that remembered view is still the observation while it crosses the footprint (the profiler's
view, fed without carry, shows nothing after a miss); and in a murky frame whose measurement, the
map's view, the tracker rejected, the ping's fix does not correct the line (docs/decisions.md, "The
imaging sonar's fix after its view was rejected"). Its view is shown the way of the tracked line
in a murky frame as the profiler's is (docs/decisions.md, "A forward-looking imaging sonar").

The sonar draws its noise (128 normals a ping; the imaging sonar an exponential a cell) from a
generator of its own, spawned from the environment's at each reset (:func:`spawn`, which draws
nothing from it): after the camera's reset with ``"sonar"`` and the ideal camera's ``"fused"``,
before it with a vision camera's ``"fused"`` (whose first frame the first ping feeds; the tracker's
navigation is then the second child). The camera's frames and every other draw stay what they are
without the sonar.

Burial: the image's ``Water.burial`` (the share of the pipe's width covered by sand, from its
starboard edge: pixels more than ``R(1 − 2b)`` across from the axis) and the sonar's (the share
of the diameter below the seabed: the axis ``R(1 − 2b)`` above it) are the same number
(:func:`sonar_burial`): the same share of the pipe's section hidden, measured along each sensor's
line of sight. The buried stretches of the disturbance bury the pipe fully for both.
"""

from __future__ import annotations

import numpy as np

from pipefollow.perception.camera import FUSED, IMAGING, CameraSettings, TrueView, VisionCamera, _spawn
from pipefollow.perception.detector import Detection
from pipefollow.perception.imaging_track import ImagingSensor
from pipefollow.perception.slots import Sighting, observed, sighting_of, write_sighting
from pipefollow.perception.sonar_track import CARRY, SonarSensor
from pipefollow.perception.track_step import (
    ACCEPTED,
    BEND,
    OUT_IN_VIEW,
    OUT_SIDE,
    OUT_SIZE,
    OUT_X1,
    OUT_X2,
    OUT_Y1,
    OUT_Y_NEAR,
    REJECTED,
    UNSEARCHED_FRAME,
)
from pipefollow.perception.tracker import PipeTracker
from pipefollow.perception.water import Water
from pipefollow.sim import decision as sim
from pipefollow.sim.camera import CameraParams
from pipefollow.sim.disturbance import NO_BURIAL

FIX_SD = 0.03  # m: the error of the ping's fix on the tracked line (docs/decisions.md, fused sensor)


def sonar_burial(water: Water) -> float:
    """The sonar's buried share of the diameter for the image's ``water.burial`` (the same share)."""
    return float(water.burial)


def make_sensor(settings: CameraSettings, camera: CameraParams, lost_reward: float):
    """What an environment observes with: None (the ideal camera's state), a vision camera, or sonar."""
    if settings.sensor != "camera":
        return SonarSensors(settings, camera, lost_reward)
    if settings.renders:
        return VisionCamera(settings, camera, lost_reward)
    return None


def start_sensor(sensor, state, points, cum, rng, disturbance) -> None:
    """:meth:`reset` of an environment's sensor, the sonar told the episode's buried stretches."""
    if isinstance(sensor, SonarSensors):
        sensor.buried = (tuple(disturbance.buried_from), tuple(disturbance.buried_to))
    sensor.reset(state, points, cum, rng)


class SonarSensors:
    """``sensor="sonar"``, ``"fused"``, ``"fls"`` or ``"fused-fls"`` of one environment (module docstring)."""

    def __init__(self, settings: CameraSettings, camera: CameraParams, lost_reward: float) -> None:
        self.settings = settings
        self.camera = camera
        self.lost_reward = lost_reward
        self.fused = settings.sensor in FUSED
        self.imaging = settings.sensor in IMAGING
        # the camera: its image (observation="image"), and with "fused" its detections too
        self.vision = VisionCamera(settings, camera, lost_reward) if settings.renders else None
        # the sonar's line shown CARRY pings past a miss, but not as the measurement of a rendered
        # camera (fused): its tracker carries its line itself
        carry = 0 if self.fused and settings.detects else CARRY
        diameter, burial = settings.water.pipe_diameter, sonar_burial(settings.water)
        if self.imaging:  # the forward-looking imaging sonar and its map
            self.sonar = ImagingSensor(diameter=diameter, burial=burial, camera=camera)
        else:
            self.sonar = SonarSensor(diameter=diameter, burial=burial, camera=camera, carry=carry)
        self.buried = (NO_BURIAL, NO_BURIAL)
        self.truth = TrueView(False, 0.0, 0.0, 0.0, 0.0)
        self._true_errors = (0.0, 0.0)
        self._last = Sighting()
        self._rng: np.random.Generator | None = None
        self._shown = np.zeros(OUT_SIZE)  # the sonar's view as a tracker's output (see _aid)

    def reset(self, state: np.ndarray, points: np.ndarray, cum: np.ndarray, rng: np.random.Generator) -> None:
        """A new episode: the sonar's generator spawned and the camera's reset (module docstring)."""
        self.sonar.reset()
        self._last = Sighting()
        if self.fused and self.settings.detects:
            # the first ping before the first frame, which it feeds as it feeds every later one
            self._rng = _spawn(rng)
            self._feed(self._ping(state, points, cum))
            if self.vision.tracker is not None:
                self.vision.aid = self._aid  # each frame's fix a point on the tracked pipe
            self.vision.skips_murky = True  # a murky frame is not searched for the pipe
            self.vision.reset(state, points, cum, rng)
            return
        if self.vision is not None:
            self.vision.reset(state, points, cum, rng)
        self._rng = _spawn(rng)
        self._look(state, points, cum)

    def step(
        self,
        state: np.ndarray,
        points: np.ndarray,
        cum: np.ndarray,
        rng: np.random.Generator,
        sim_reward: float,
        previous_action: float,
    ) -> float:
        """After a decision: ping (and frame); returns the decision's reward (as the vision camera's)."""
        s = state
        if self.fused and self.settings.detects:  # the vision camera writes the slots, fed the ping
            self._feed(self._ping(s, points, cum))
            return self.vision.step(s, points, cum, rng, sim_reward, previous_action)
        if self.vision is not None:  # the image only (observation="image"): the slots are ours
            self.vision.step(s, points, cum, rng, sim_reward, previous_action)
        self._look(s, points, cum)
        if s[sim.OVERRIDDEN] != 0.0 or s[sim.IN_VIEW] == 0.0:
            return self.lost_reward
        return sim_reward

    def _feed(self, view) -> None:
        """The sonar's view as the camera's measurement where the camera finds no pipe (or none yet).

        Only a view of a ping that found the pipe: the imaging sonar's map shows what earlier pings
        saw after a miss too, and the tracker would take that memory as a new measurement each
        frame (the profiler's view, fed without carry, is shown only when its ping found the pipe).
        """
        self.vision.fallback = _as_detection(view) if view.in_view and view.detected else None

    def _aid(self, tracker: PipeTracker) -> np.ndarray:
        """After the camera's frame: the ping's fix on the tracked pipe; the sonar's view if murky or none.

        The fix is a point on the tracked pipe (:data:`FIX_SD`) only in a frame whose camera
        detection the tracker did not take (none, rejected, or one that started a new or replacing
        line; a piece the vehicle crosses that restarts the line counts as taken):
        a detection it took already places the line, and adding the fix there made clear water
        worse (docs/decisions.md). With the imaging sonar, not in a frame too murky to search either
        when the tracker rejected that frame's measurement (the map's view): the ping's fix, the
        middle of its strongest piece, then pulled the line towards a hook's other leg
        (docs/decisions.md, "The imaging sonar's fix after its view was rejected").

        In a frame too murky to search, and while the track shows no pipe, the sonar's own view is
        this decision's observation if it has the pipe in the footprint (the track stays as it is:
        it carries the line through the sonar's misses); else, the track showing none, the search
        turns towards the ping's fix if it found the pipe outside the footprint.
        """
        fix = self.sonar.fix
        out = tracker.out
        # in a frame left to the imaging sonar whose view (the measurement) the line rejected, the same
        # ping's fix is no second opinion: its strongest piece, at a hook as likely the other leg
        view_rejected = self.imaging and self.vision.frame == UNSEARCHED_FRAME and tracker.event == REJECTED
        if fix.found and tracker.event not in (ACCEPTED, BEND) and not view_rejected:
            out = tracker.point(fix.lateral, fix.forward, FIX_SD)
        view = self.sonar.view
        if self.vision.frame == UNSEARCHED_FRAME and view.in_view:  # a frame too murky to search
            return self._as_output(view, tracker)
        if out[OUT_IN_VIEW] != 0.0 or not fix.found:
            return out
        out = tracker.search_towards(fix.lateral)
        if not view.in_view:
            return out
        return self._as_output(view, tracker)

    def _as_output(self, view, tracker: PipeTracker) -> np.ndarray:
        """The sonar's view in the footprint as a tracker's output (in view, the ends, the side).

        Its ends are taken the way of the tracked line (or of the line last tracked), which keeps
        the pipe's way; the view's own far end is the one further forward, which after a bend
        that leaves the pipe across the track is as likely the way back.
        """
        return self._shown_piece(*tracker.ordered(view.x1, view.y1, view.x2, view.y_near))

    def _shown_piece(self, x1: float, y1: float, x2: float, y_near: float) -> np.ndarray:
        """A piece in view (far ``x1, y1``, near ``x2, y_near``) as a tracker's output, its side ``x1``'s."""
        shown = self._shown
        shown[OUT_IN_VIEW], shown[OUT_X1], shown[OUT_Y1] = 1.0, x1, y1
        shown[OUT_X2], shown[OUT_Y_NEAR] = x2, y_near
        shown[OUT_SIDE] = 1.0 if x1 >= 0.0 else -1.0
        return shown

    def _keep_truth(self, s: np.ndarray) -> None:
        self.truth = TrueView(bool(s[sim.IN_VIEW]), s[sim.X1], s[sim.Y1], s[sim.X2], s[sim.Y_NEAR])
        self._true_errors = (s[sim.E_DIST], s[sim.E_ANGL])

    def _ping(self, s: np.ndarray, points: np.ndarray, cum: np.ndarray):
        pose = (s[sim.X], s[sim.Y], s[sim.PSI])
        return self.sonar.step(points, cum, pose, self._rng, *self.buried)

    def _look(self, s: np.ndarray, points: np.ndarray, cum: np.ndarray) -> None:
        """The slots from the sonar (``"sonar"``), or the exact camera's, else the sonar's (ideal, fused)."""
        self._keep_truth(s)
        view = self._ping(s, points, cum)
        if self.fused and s[sim.IN_VIEW] != 0.0:  # the exact camera sees the pipe: its slots stay
            return
        if view.in_view:
            self._last = sighting_of(view.x1, view.y1, view.x2, view.y_near)
        elif self.fused:  # neither sees it: the exact camera's last sighting stays
            return
        write_sighting(s, self._last, view.in_view)

    def observation(self, state: np.ndarray, dtype=np.float64, slots: np.ndarray | None = None) -> np.ndarray:
        """The observation: ``state[:4]`` or ``state[slots]``, or the image with ``observation="image"``."""
        if self.vision is not None:
            return self.vision.observation(state, dtype, slots)
        return observed(state, dtype, slots)

    def info(self) -> dict[str, np.ndarray]:
        """The camera's entries (the vision camera's, if any), ``sonar_detected`` and ``sonar_in_view``."""
        out: dict[str, np.ndarray] = {}
        if self.vision is not None:
            out.update(self.vision.info())
        if not self.settings.detects:
            out["true_pipe_in_view"] = np.array(self.truth.in_view)
            out["true_e_dist"] = np.array(float(self._true_errors[0]))
            out["true_e_angl"] = np.array(float(self._true_errors[1]))
        view = self.sonar.view
        out["sonar_detected"] = np.array(bool(view.detected))
        out["sonar_in_view"] = np.array(bool(view.in_view))
        return out

    def panel(self, height: int) -> np.ndarray:
        """The camera's panel (``observation="image"`` or ``"fused"`` with a vision camera), else none."""
        if self.vision is not None:
            return self.vision.panel(height)
        return np.zeros((height, 0, 3), dtype=np.uint8)


def _as_detection(view) -> Detection:
    """The sonar's view as a detection of the pipe's centre line in the camera's footprint."""
    return Detection(True, view.x1, view.y1, view.x2, view.y_near, 1.0)


__all__ = ["SonarSensors", "make_sensor", "sonar_burial", "start_sensor"]
