"""How good the pipe detector is, and a camera model calibrated from it.

* :func:`detector_report` renders frames at poses taken along the held-out suite's trajectories
  (the heuristic on the ideal camera, one 60-s episode per pipe), for each turbidity and burial
  level, and runs :func:`~pipefollow.perception.detector.detect_pipe` on each: the detection rate on
  frames with the pipe in view, false detections on the same frames rendered without the pipe, and
  the end-point error against the exact camera's visible piece.
* :func:`calibrate` fits the simulator's camera model (:mod:`pipefollow.sim.disturbance`: Gaussian
  noise of s.d. ``camera_noise`` on the four end coordinates, and a missed detection with
  probability ``miss_prob``) to the report, per turbidity: ``miss_prob`` is the share of frames
  with the pipe in view that the detector misses, ``camera_noise`` the RMS of the end coordinates'
  errors below :data:`GROSS_M` (the median is no use: ends on the footprint's border are often
  exact for both); gross errors (the detector's line on one leg of a bend, where the exact camera
  reports the chord to the far end) are counted apart, since the Gaussian model has none.
* :func:`closed_loop` runs controllers with a rendered camera (the tracker or the raw detector) on a suite
  (:func:`~pipefollow.evaluation.benchmark.benchmark`, compared with the heuristic through the same
  camera and with the heuristic on the ideal camera).

Every frame draws from ``default_rng(SeedSequence([seed, condition, pipe]))``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pipefollow.files.paper_training import TEST_EPISODE_SECONDS
from pipefollow.learners.heuristic import heuristic_action
from pipefollow.perception.detector import detect_pipe
from pipefollow.perception.image import Renderer
from pipefollow.perception.textures import make_textures
from pipefollow.perception.water import CLEAR, WATER_PRESETS, Water, check
from pipefollow.sim import decision as sim
from pipefollow.sim.suites import Suite, min_length_for

TURBIDITIES = (0.0, 0.1, 0.15, 0.2, 0.25, 0.3)  # beam attenuation levels of the report (1/m)
BURIALS = (0.0, 0.25, 0.5)  # burial levels of the report (share of the pipe's width)
GROSS_M = 0.3  # an end-point error above this is a gross error (another piece, a false line)
EMPTY = np.zeros((0, 2))


@dataclass(frozen=True)
class Frame:
    """A pose along a trajectory and what the exact camera sees from it."""

    pipe: int  # index in the suite
    pose: tuple[float, float, float]
    in_view: bool
    truth: tuple[float, float, float, float]  # x1, y1, x2, y_near


def trajectory_frames(
    suite: Suite, n_pipes: int, seconds: float = TEST_EPISODE_SECONDS
) -> tuple[list, list[Frame]]:
    """The suite's first ``n_pipes`` pipes and the poses of the heuristic's episodes (ideal camera)."""
    pipes = suite.pipes(n_pipes, min_length_for(seconds))
    frames: list[Frame] = []
    n_dec = int(round(seconds))
    for k, pipe in enumerate(pipes):
        s = np.zeros(sim.STATE_SIZE)
        packed = sim.pack_params(sim.PAPER_SIM)
        p0, h = pipe.points[0], pipe.start_heading
        sim.init_state_packed(s, pipe.points, pipe.cumulative, p0[0], p0[1], h, packed)
        for _ in range(n_dec):
            frames.append(_frame(k, s))
            a = heuristic_action(s[sim.X1], s[sim.Y1]) if s[sim.IN_VIEW] else 0.0
            sim.decide_packed(s, a, pipe.points, pipe.cumulative, packed)
    return pipes, frames


def _frame(k: int, s: np.ndarray) -> Frame:
    return Frame(
        k,
        (s[sim.X], s[sim.Y], s[sim.PSI]),
        bool(s[sim.IN_VIEW]),
        (s[sim.X1], s[sim.Y1], s[sim.X2], s[sim.Y_NEAR]),
    )


def measure(water: Water, pipes, frames: Sequence[Frame], seed: int, condition: int) -> dict:
    """Detector statistics of one water condition over ``frames`` (module docstring)."""
    renderer = Renderer(check(water))
    det_in, n_in, false, n_empty = 0, 0, 0, 0
    errors, coord_errors = [], []
    rngs: dict[int, tuple] = {}
    for f in frames:
        if f.pipe not in rngs:
            rng = np.random.default_rng(np.random.SeedSequence([seed, condition, f.pipe]))
            rngs[f.pipe] = (rng, make_textures(rng))
        rng, tex = rngs[f.pipe]
        pipe = pipes[f.pipe]
        empty = renderer.render(EMPTY, EMPTY[:, 0], f.pose, tex, rng)
        false += detect_pipe(empty, pipe_diameter=water.pipe_diameter).found
        n_empty += 1
        if not f.in_view:
            continue
        image = renderer.render(pipe.points, pipe.cumulative, f.pose, tex, rng)
        det = detect_pipe(image, pipe_diameter=water.pipe_diameter)
        n_in += 1
        if det.found:
            det_in += 1
            x1, y1, x2, yn = f.truth
            errors += [math.hypot(det.x1 - x1, det.y1 - y1), math.hypot(det.x2 - x2, det.y_near - yn)]
            coord_errors += [det.x1 - x1, det.y1 - y1, det.x2 - x2, det.y_near - yn]
    e = np.array(errors)
    c = np.array(coord_errors)
    fine = c[np.abs(c) < GROSS_M] if c.size else c
    return {
        "frames_in_view": n_in,
        "frames_without_pipe": n_empty,
        "detection_rate": det_in / n_in if n_in else math.nan,
        "false_detection_rate": false / n_empty if n_empty else math.nan,
        "median_error_cm": float(np.median(e) * 100) if e.size else math.nan,
        "p90_error_cm": float(np.percentile(e, 90) * 100) if e.size else math.nan,
        "gross_error_rate": float(np.mean(e > GROSS_M)) if e.size else math.nan,
        "rms_m": float(np.sqrt(np.mean(fine**2))) if fine.size else math.nan,
    }


def detector_report(
    suite: Suite,
    n_pipes: int = 100,
    n_frames: int = 2000,
    turbidities: Sequence[float] = TURBIDITIES,
    burials: Sequence[float] = BURIALS,
    seed: int = 0,
    base: Water = CLEAR,
) -> tuple[list[dict], list, list[Frame]]:
    """Rows of detector statistics per (turbidity, burial) over ``n_frames`` poses along the suite.

    Burial levels are measured at the base water's turbidity; turbidity levels without burial. The
    other water settings (blur, noise, snow) follow the nearest preset of :data:`WATER_PRESETS`.
    """
    pipes, all_frames = trajectory_frames(suite, n_pipes)
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0]))
    pick = np.sort(rng.choice(len(all_frames), size=min(n_frames, len(all_frames)), replace=False))
    frames = [all_frames[i] for i in pick]
    rows = []
    conditions = [(t, 0.0) for t in turbidities] + [(base.turbidity, b) for b in burials if b > 0.0]
    for c, (t, b) in enumerate(conditions, start=1):
        water = water_for(t, base)._replace(burial=b)
        row = {"turbidity": t, "burial": b, "blur": water.blur, "noise": water.noise, "snow": water.snow}
        row.update(measure(water, pipes, frames, seed, c))
        rows.append(row)
    return rows, pipes, frames


def water_for(turbidity: float, base: Water = CLEAR) -> Water:
    """The water of a turbidity level: blur, noise and snow of the preset of nearest turbidity."""
    nearest = min(WATER_PRESETS.values(), key=lambda w: abs(w.turbidity - turbidity))
    return base._replace(turbidity=turbidity, blur=nearest.blur, noise=nearest.noise, snow=nearest.snow)


def calibrate(rows: Sequence[dict]) -> list[dict]:
    """The camera model per turbidity (burial 0): ``camera_noise`` (m), ``miss_prob``, gross errors."""
    out = []
    for r in rows:
        if r["burial"] != 0.0:
            continue
        out.append(
            {
                "turbidity": r["turbidity"],
                "camera_noise": round(r["rms_m"], 4),
                "miss_prob": round(1.0 - r["detection_rate"], 4),
                "gross_error_rate": round(r["gross_error_rate"], 4),
            }
        )
    return out


def sample_figure(
    pipes, frames: Sequence[Frame], path, turbidities=(0.1, 0.2, 0.25, 0.3), per_row: int = 6, seed: int = 0
):
    """A figure of sample frames per turbidity with the exact piece (green) and the detection (red)."""
    from pipefollow.envs.render import new_figure, save_figure

    rng = np.random.default_rng(seed)
    in_view = [i for i, f in enumerate(frames) if f.in_view]
    shown = [frames[i] for i in rng.choice(in_view, per_row, replace=False)]
    fig = new_figure((1.4 * per_row, 2.2 * len(turbidities)))
    axes = fig.subplots(len(turbidities), per_row, squeeze=False)
    for r, t in enumerate(turbidities):
        renderer = Renderer(water_for(t))
        for c, f in enumerate(shown):
            frng = np.random.default_rng(np.random.SeedSequence([seed, 99, r, c]))
            pipe = pipes[f.pipe]
            img = renderer.render(pipe.points, pipe.cumulative, f.pose, make_textures(frng), frng)
            det = detect_pipe(img)
            ax = axes[r, c]
            cam = renderer.camera  # the image spans the footprint, row 0 at its far edge
            footprint = (-cam.half_width, cam.half_width, 0.0, cam.depth)
            ax.imshow(img, cmap="gray", vmin=0, vmax=255, extent=footprint)
            x1, y1, x2, yn = f.truth
            ax.plot([x2, x1], [yn, y1], color="lime", lw=1.0)
            if det.found:
                ax.plot([det.x2, det.x1], [det.y_near, det.y1], color="red", lw=1.0, ls="--")
            ax.set_xticks([])
            ax.set_yticks([])
            if c == 0:
                ax.set_ylabel(f"c = {t:g}/m")
    fig.suptitle("camera frames along held-out trajectories: truth (green), detection (red)", fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)


def closed_loop(
    agent, suite: Suite, water: Water, controller: str, n_pipes=None, seconds=60.0, seed=0, camera="vision"
):
    """:func:`~pipefollow.evaluation.benchmark.benchmark` of ``agent`` with a rendered camera in ``water``.

    ``camera`` is ``"vision"`` (the detector and the pipe tracker) or ``"vision-raw"`` (the detector
    alone, frame by frame).
    """
    from pipefollow.evaluation.benchmark import benchmark

    if camera not in ("vision", "vision-raw"):
        raise ValueError(f"camera must be 'vision' or 'vision-raw', got {camera!r}")
    return benchmark(
        agent, suite, controller=controller, seconds=seconds, n_pipes=n_pipes, seed=seed, noise_seed=seed,
        camera={"camera": camera, "water": water},
    )  # fmt: skip
