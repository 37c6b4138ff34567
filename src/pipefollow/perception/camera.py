"""The vision camera of the environments: render the footprint, detect the pipe, write the observation.

With ``camera="vision"`` the observation slots of the simulation state (``x1, y1, x2, y_near``,
``e_dist``, ``e_angl``, the in-view flag and the side of the last sighting) come from
:func:`~pipefollow.perception.detector.detect_pipe` on the rendered image, through the pipe tracker
(:mod:`pipefollow.perception.tracker`: the pipe carried from frame to frame by the vehicle's
navigation, detections gated), instead of from the exact geometry; ``camera="vision-raw"`` takes
each frame's detection as it is. A pipe out of the tracked (or raw) view is a lost pipe, so the
next decision runs the search behaviour and this one gets the lost reward. The reward (eq. 19)
stays computed from the true geometry (``reward_from="truth"``, docs/design.md says why) unless
``reward_from="detected"``.
``observation="image"`` hands the image itself to the agent, with either camera.

The environments call :meth:`VisionCamera.reset` after their reset and :meth:`VisionCamera.step`
after each decision; both draw from the environment's seeded generator only.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from pipefollow.perception.detector import NOT_FOUND, Detection, detect_pipe, require_cv2
from pipefollow.perception.image import Renderer
from pipefollow.perception.pixels import column_at, pixel_grid, row_at
from pipefollow.perception.slots import Sighting, observed, sighting_of, write_sighting
from pipefollow.perception.textures import SCENES, Textures
from pipefollow.perception.track_step import (
    CLEAR_FRAME,
    MURKY_FRAME,
    OUT_IN_VIEW,
    OUT_SIDE,
    OUT_X1,
    OUT_X2,
    OUT_Y1,
    OUT_Y_NEAR,
    UNSEARCHED_FRAME,
)
from pipefollow.perception.tracker import PipeTracker
from pipefollow.perception.visibility import EDGE_CONTRAST, clear_enough, contrast_to_noise
from pipefollow.perception.water import Water, water_from
from pipefollow.sim import decision as sim
from pipefollow.sim.camera import CameraParams
from pipefollow.sim.reward import reward

CAMERAS = ("ideal", "vision", "vision-raw")
# what writes the observation: the camera, a sonar alone or the camera and a sonar in one track; the
# sonar the look-ahead profiler ("sonar", "fused") or the forward-looking imaging sonar ("fls", "fused-fls")
SENSORS = ("camera", "sonar", "fused", "fls", "fused-fls")
SONAR_ALONE = ("sonar", "fls")
FUSED = ("fused", "fused-fls")
IMAGING = ("fls", "fused-fls")
VISION_CAMERAS = ("vision", "vision-raw")  # the cameras that detect the pipe in the image
OBSERVATIONS = ("state", "image")
REWARD_FROM = ("truth", "detected")


@dataclass(frozen=True)
class CameraSettings:
    """How the environment sees: the camera, what the agent observes, the reward's source, the water."""

    camera: str = "ideal"  # "ideal" (the paper's exact piece), "vision" (detector + tracker), "vision-raw"
    observation: str = "state"  # "state" (x1, y1, x2, v_x) or "image" (the camera image, (H, W, 1))
    reward_from: str = "truth"  # eq. 19 from the true geometry, or from the detection
    water: Water = Water()  # water and camera settings of the image
    sensor: str = (
        "camera"  # "camera", "sonar" / "fls" (a sonar alone) or "fused" / "fused-fls" (both, one track)
    )

    @property
    def renders(self) -> bool:
        """Whether the environment renders camera images at all."""
        return self.detects or self.observation == "image"

    @property
    def detects(self) -> bool:
        """Whether the observation comes from the detector (``vision`` or ``vision-raw``)."""
        return self.camera in VISION_CAMERAS

    @property
    def tracks(self) -> bool:
        """Whether the detections go through the pipe tracker (``vision``)."""
        return self.camera == "vision"


class TrueView(NamedTuple):
    """What the exact camera sees from the same pose (the simulation state's slots)."""

    in_view: bool
    x1: float
    y1: float
    x2: float
    y_near: float


def camera_settings(
    camera: str = "ideal",
    observation: str = "state",
    reward_from: str = "truth",
    water: Water | str | dict[str, Any] | None = None,
    sensor: str = "camera",
) -> CameraSettings:
    """Checked settings; a one-line ``ValueError`` naming the argument otherwise.

    ``sensor="sonar"`` or ``"fls"`` observes with a sonar alone, so it takes the ideal camera only
    (whose exact view then serves the reward and the info's ``true_*``).

    The vision camera needs OpenCV (the extra ``vision``); without it this raises the one-line
    ``ImportError`` of :func:`~pipefollow.perception.detector.require_cv2`.
    """
    for name, value, allowed in (
        ("camera", camera, CAMERAS),
        ("observation", observation, OBSERVATIONS),
        ("reward_from", reward_from, REWARD_FROM),
        ("sensor", sensor, SENSORS),
    ):
        if value not in allowed:
            raise ValueError(f"{name} must be one of {', '.join(allowed)}; got {value!r}")
    if reward_from == "detected" and camera not in VISION_CAMERAS:
        raise ValueError(
            "reward_from='detected' needs camera='vision' or 'vision-raw' (the ideal camera detects nothing)"
        )
    if sensor in SONAR_ALONE and camera != "ideal":
        raise ValueError(
            f"sensor={sensor!r} observes with the sonar alone: camera must be 'ideal', got {camera!r}"
        )
    settings = CameraSettings(camera, observation, reward_from, water_from(water), sensor)
    if water is not None and not settings.renders and sensor == "camera":
        raise ValueError(
            f"water={water!r} has no effect on the ideal camera's state observation: it needs "
            "camera='vision' or 'vision-raw', observation='image', or a sonar sensor"
        )
    if camera in VISION_CAMERAS:
        require_cv2()
    return settings


def camera_record(camera: dict[str, Any] | None) -> dict[str, Any]:
    """A result's record of the environment's camera arguments ``camera`` (``camera``, ``water``, ``sensor``).

    ``camera`` and ``water`` (the resolved record's fields: a preset name or a mapping counts as the
    water it names), and ``sensor`` unless it is the camera alone; ``{}`` for None or ``{}`` (the
    ideal camera alone).
    """
    if not camera:
        return {}
    out: dict[str, Any] = {"camera": camera.get("camera", "ideal")}
    if camera.get("sensor", "camera") != "camera":
        out["sensor"] = camera["sensor"]
    out["water"] = water_from(camera.get("water"))._asdict()
    return out


def _spawn(rng: np.random.Generator) -> np.random.Generator:
    """A child generator of ``rng``, leaving ``rng``'s stream as it is (one draw if it cannot spawn)."""
    try:
        return rng.spawn(1)[0]
    except (TypeError, ValueError):  # a bit generator without a seed sequence
        return np.random.default_rng(int(rng.integers(2**63)))


class VisionCamera:
    """One environment's camera image and detections (see the module docstring)."""

    def __init__(self, settings: CameraSettings, camera: CameraParams, lost_reward: float) -> None:
        self.settings = settings
        self.camera = camera
        self.lost_reward = lost_reward
        self.renderer = Renderer(settings.water, camera)
        self.image = np.zeros((settings.water.height, settings.water.width), dtype=np.uint8)
        self.detection: Detection = NOT_FOUND
        self.truth = TrueView(False, 0.0, 0.0, 0.0, 0.0)
        self._textures: Textures | None = None
        self._last = Sighting()  # the last detection's slots
        self.tracker = PipeTracker(camera.half_width, camera.depth) if settings.tracks else None
        # a second detector's pipe (sensor="fused": the sonar's), set before each frame by its owner;
        # the tracker (or the raw observation) takes it when the image's detector finds nothing
        self.fallback: Detection | None = None
        # a second sensor's update of the track after each frame's detection (sensor="fused": the
        # sonar's fix), set by its owner: it returns the tracker's output
        self.aid: Callable[[PipeTracker], np.ndarray] | None = None
        # whether a frame too murky for the detector (perception.visibility.clear_enough) is left
        # unsearched (sensor="fused", whose sonar then feeds the track), set by its owner
        self.skips_murky = False
        # what the last frame was to the tracker (track_step's CLEAR_FRAME, MURKY_FRAME or
        # UNSEARCHED_FRAME: too murky to search, with skips_murky)
        self.frame = CLEAR_FRAME

    def reset(self, state: np.ndarray, points: np.ndarray, cum: np.ndarray, rng: np.random.Generator) -> None:
        """A new scene (seabed and growth textures from ``rng``) and its first image.

        The textures come from :data:`~pipefollow.perception.textures.SCENES`: a seed's scene is made
        once (the generator left as drawing it leaves it), and without marine growth its tile stays blank.
        """
        self._textures = SCENES.draw(rng, growth=self.settings.water.growth > 0.0)
        self._last = Sighting()
        self.detection = NOT_FOUND  # no tracking across episodes
        if self.tracker is not None:
            self.tracker.start()
        self._look(state, points, cum, rng)
        if self.tracker is not None:
            # the navigation's errors from a generator of the environment's own, spawned so that
            # the frames draw what they would without the tracker
            self.tracker.navigation.reset(_spawn(rng))

    def step(
        self,
        state: np.ndarray,
        points: np.ndarray,
        cum: np.ndarray,
        rng: np.random.Generator,
        sim_reward: float,
        previous_action: float,
    ) -> float:
        """After a decision: the new image and detection; returns the decision's reward.

        ``sim_reward`` is the simulation's reward from the true geometry; ``previous_action`` the
        executed action before this decision (eq. 19's a_prev).
        """
        self._look(state, points, cum, rng)
        s = state
        if not self.settings.detects:
            return sim_reward
        if s[sim.OVERRIDDEN] != 0.0 or s[sim.IN_VIEW] == 0.0:
            return self.lost_reward
        if self.settings.reward_from == "truth":
            return sim_reward
        return reward(s[sim.VX], s[sim.E_DIST], s[sim.E_ANGL], s[sim.A_PREV], previous_action)

    def _look(self, s: np.ndarray, points: np.ndarray, cum: np.ndarray, rng: np.random.Generator) -> None:
        self.truth = TrueView(bool(s[sim.IN_VIEW]), s[sim.X1], s[sim.Y1], s[sim.X2], s[sim.Y_NEAR])
        self._true_errors = (s[sim.E_DIST], s[sim.E_ANGL])
        pose = (s[sim.X], s[sim.Y], s[sim.PSI])
        self.renderer.render(points, cum, pose, self._textures, rng, out=self.image)
        if not self.settings.detects:
            return
        wt, cam = self.settings.water, self.camera
        frame, searched = CLEAR_FRAME, True
        if self.tracker is not None or self.skips_murky:  # how much the frame shows
            contrast = contrast_to_noise(self.image)
            searched = not self.skips_murky or clear_enough(contrast)
            if not searched:
                frame = UNSEARCHED_FRAME
            elif contrast < EDGE_CONTRAST:
                frame = MURKY_FRAME
        self.frame = frame
        if searched:
            diameter = wt.pipe_diameter
            # a short piece at the border only for the tracker, which orders the ends itself
            det = detect_pipe(
                self.image,
                cam.half_width,
                cam.depth,
                diameter,
                previous=self.detection,
                border_pieces=self.tracker is not None,
            )
        else:  # a frame too murky to look for the pipe in
            det = NOT_FOUND
        self.detection = det
        if not det.found and self.fallback is not None:
            det = self.fallback
        if self.tracker is not None:
            self._track(s, pose, det, frame)
            return
        if det.found:
            self._last = sighting_of(det.x1, det.y1, det.x2, det.y_near)
        # a lost pipe keeps the last detection, as the exact camera keeps its last sighting
        write_sighting(s, self._last, det.found)

    def _track(self, s: np.ndarray, pose: tuple[float, float, float], det: Detection, frame: int) -> None:
        """The observation slots from the tracker fed with this frame's detection (or the fallback's)."""
        own = det is self.detection  # not the fallback's (a second sensor's)
        out = self.tracker.step(pose, det.found, (det.x1, det.y1, det.x2, det.y_near), frame, own)
        if self.aid is not None:
            out = self.aid(self.tracker)
        self._show(s, out)

    def _show(self, s: np.ndarray, out: np.ndarray) -> None:
        """The observation slots from a tracker's output (in view, x1, y1, x2, y_near, side)."""
        seen = out[OUT_IN_VIEW] != 0.0
        if seen:
            ends = out[OUT_X1], out[OUT_Y1], out[OUT_X2], out[OUT_Y_NEAR]
            self._last = sighting_of(*ends, side=out[OUT_SIDE])
        else:  # the last sighting stays; the side is the tracker's (towards a turn it saw)
            self._last = self._last._replace(side=out[OUT_SIDE])
        write_sighting(s, self._last, seen)

    def observation(self, state: np.ndarray, dtype=np.float64, slots: np.ndarray | None = None) -> np.ndarray:
        """The observation: ``state[:4]`` or ``state[slots]`` as ``dtype``, or the image ``(H, W, 1)``."""
        if self.settings.observation == "image":
            return self.image[..., None].copy()
        return observed(state, dtype, slots)

    def info(self) -> dict[str, np.ndarray]:
        """The camera's entries of ``info`` (0-d arrays): the detection and the exact camera's view."""
        out: dict[str, np.ndarray] = {"true_pipe_in_view": np.array(self.truth.in_view)}
        if self.settings.detects:
            out["detected"] = np.array(self.detection.found, dtype=bool)
            out["detection_confidence"] = np.array(float(self.detection.confidence))
            if self.tracker is not None:
                out["track_confidence"] = np.array(self.tracker.confidence)
            out["true_e_dist"] = np.array(float(self._true_errors[0]))
            out["true_e_angl"] = np.array(float(self._true_errors[1]))
        return out

    def panel(self, height: int) -> np.ndarray:
        """The camera image as an RGB panel ``height`` pixels high: detection red, truth green."""
        h, w = self.image.shape
        k = max(1, height // h)
        grey = np.repeat(np.repeat(self.image, k, axis=0), k, axis=1)
        rgb = np.stack([grey] * 3, axis=-1)
        # the footprint as a single pixel: a point's coordinates in it are its shares of the
        # footprint's width and depth, which the panel's w·k × h·k pixels scale
        whole = pixel_grid(float(self.camera.half_width), float(self.camera.depth), 1, 1)

        def draw(x_a, y_a, x_b, y_b, colour):
            t = np.linspace(0.0, 1.0, 4 * k * max(h, w))
            x, y = x_a + t * (x_b - x_a), y_a + t * (y_b - y_a)
            c = (column_at(x, whole) * w * k).astype(np.int64)  # the panel pixels the points lie in
            r = (row_at(y, whole) * h * k).astype(np.int64)
            rgb[np.clip(r, 0, h * k - 1), np.clip(c, 0, w * k - 1)] = colour

        seen, x1, y1, x2, y_near = self.truth
        if seen:
            draw(x2, y_near, x1, y1, (40, 220, 40))
        det = self.detection
        if det.found:
            draw(det.x2, det.y_near, det.x1, det.y1, (230, 30, 30))
        out = np.zeros((height, w * k, 3), dtype=np.uint8)
        out[: min(height, h * k)] = rgb[:height]
        return out
