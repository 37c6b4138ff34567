"""Figures of the perception page: sonar profiles with truth and detection; the tracker along an episode.

* :func:`sonar_profiles` renders pings of the environments' look-ahead sonar
  (:class:`~pipefollow.perception.sonar_track.SonarSensor`'s) over a straight pipe crossing the
  fan, on a flat and a rough seabed, with the pipe lying on it and half buried: the ranges as
  heights above the mean seabed across the fan, the fitted seabed (its depth under the
  transducer), the true pipe's section and the detection.
* :func:`tracker_episode` runs the heuristic through the rendered camera and the pipe tracker
  (``camera="vision"``) on one pipe, as the benchmark does (the pipe's noise generator), and
  records per decision the pose, the detection and the tracker's line with its covariance;
  :func:`tracker_figure` draws it: a top view (true pipe, path, detections, tracked line) and the
  lateral offset of the pipe at :data:`Y_REF` ahead, true against tracked with the tracker's ±2σ.

The camera frame is :mod:`pipefollow.sim.camera`'s: ``x`` lateral (starboard), ``y`` forward,
origin at the vehicle's centre; a point ``(x, y)`` of it lies at north ``X + y cos ψ − x sin ψ``,
east ``Y + y sin ψ + x cos ψ``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pipefollow.perception.water import WATER_PRESETS
from pipefollow.sim.camera import PAPER_CAMERA, to_camera

Y_REF = 1.5  # m ahead of the vehicle's centre: where the time plot compares the lateral offsets
STEEP = math.cos(math.radians(60.0))  # a tracked line more across the track than 60° has no offset there
SONAR_CASES = (  # (title, seabed roughness RMS (m), burial: buried share of the diameter)
    ("flat seabed, on it", 0.0, 0.0),
    ("flat seabed, half buried", 0.0, 0.5),
    ("rough seabed (2 cm RMS), on it", 0.02, 0.0),
    ("rough seabed (2 cm RMS), half buried", 0.02, 0.5),
)


def to_world(pose, x, y) -> tuple[np.ndarray, np.ndarray]:
    """Camera-frame points ``(x, y)`` seen from ``pose = (X, Y, ψ)`` as (north, east).

    The inverse of :func:`pipefollow.sim.camera.to_camera`.
    """
    X, Y, psi = pose
    c, s = math.cos(psi), math.sin(psi)
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    return X + y * c - x * s, Y + y * s + x * c


def lateral_at(points: np.ndarray, pose, y_ref: float = Y_REF, reach: float = 3.0) -> float:
    """The true pipe's lateral position where it crosses the line ``y = y_ref`` ahead (NaN if nowhere).

    Of several crossings within ``±reach`` m, the one nearest the vehicle's track.
    """
    x, y = to_camera(points[:, 0], points[:, 1], *pose)
    best = math.nan
    for k in range(len(x) - 1):
        y0, y1 = y[k] - y_ref, y[k + 1] - y_ref
        if y0 == y1 or y0 * y1 > 0.0:
            continue
        t = y0 / (y0 - y1)
        xc = x[k] + t * (x[k + 1] - x[k])
        if abs(xc) <= reach and (math.isnan(best) or abs(xc) < abs(best)):
            best = float(xc)
    return best


def line_lateral(theta: float, d: float, cov: np.ndarray, y_ref: float = Y_REF) -> tuple[float, float]:
    """A tracked line's lateral position at ``y = y_ref`` and its standard deviation.

    The line ``d·(cos θ, −sin θ) + t·(sin θ, cos θ)`` crosses ``y_ref`` at ``x = d / cos θ + y_ref tan θ``;
    the s.d. is the first-order propagation of the covariance of ``(θ, d)``.
    """
    c = math.cos(theta)
    x = d / c + y_ref * math.tan(theta)
    j = np.array([(d * math.sin(theta) + y_ref) / c**2, 1.0 / c])
    return x, math.sqrt(max(float(j @ cov @ j), 0.0))


def sonar_profiles(path, seed: int = 0, lateral: float = 0.4, angle: float = 0.3) -> list:
    """The figure of :data:`SONAR_CASES` (module docstring); returns each case's detection."""
    from pipefollow.envs.render import new_figure, save_figure
    from pipefollow.evaluation.sonar import straight_pipe
    from pipefollow.perception.sonar import fan_line, profile_points, render_ping
    from pipefollow.perception.sonar_detect import detect_profile
    from pipefollow.perception.sonar_track import SonarSensor

    sonar = SonarSensor().sonar  # the environments' sonar
    diameter = WATER_PRESETS["clear"].pipe_diameter
    radius = 0.5 * diameter
    fig = new_figure((7.6, 4.6))
    axes = fig.subplots(2, 2, squeeze=False)
    fixes = []
    for i, (title, roughness, burial) in enumerate(SONAR_CASES):
        ax = axes[i // 2, i % 2]
        s = sonar._replace(roughness=roughness)
        rng = np.random.default_rng(np.random.SeedSequence([seed, 5, i]))
        pts, cum = straight_pipe(lateral, angle, forward=fan_line(s))
        ping = render_ping(pts, cum, (0.0, 0.0, 0.0), rng, s, diameter, burial)
        fix = detect_profile(ping, diameter)
        fixes.append(fix)
        x, z = profile_points(ping.ranges, ping.angles, ping.pitch)
        h = z + s.altitude  # height above the mean seabed
        ax.axvspan(-PAPER_CAMERA.half_width, PAPER_CAMERA.half_width, color="0.92", lw=0)
        ax.plot(x, h * 100.0, ".", ms=2.5, color="k", label="beams")
        ax.axhline((s.altitude - fix.seabed_depth) * 100.0, color="tab:blue", lw=0.8, label="fitted seabed")
        t = np.linspace(0.0, 2.0 * math.pi, 100)
        zc = radius * (1.0 - 2.0 * burial)  # the axis above the mean seabed
        # the tilted fan meets the pipe's top short of its seabed line: the truth at the detection's
        # forward position (the axis's lateral there), else where the pipe crosses the seabed line
        forward = fix.forward if fix.found else fan_line(s)
        x0 = lateral + (forward - fan_line(s)) * math.tan(angle)
        ax.plot(x0 + radius * np.cos(t), (zc + radius * np.sin(t)) * 100.0, color="green", lw=1.0,
                label="true section")  # fmt: skip
        if fix.found:
            top = (s.altitude - fix.seabed_depth + fix.height) * 100.0
            ax.plot([fix.lateral], [top], "v", color="red", ms=5, label="detection")
            ax.axvline(fix.lateral, color="red", ls="--", lw=0.8)
            verdict = f"found {100 * (fix.lateral - x0):+.1f} cm off, SNR {fix.snr:.0f}"
        else:
            verdict = f"not found, SNR {fix.snr:.1f}"
        ax.set_title(f"{title}: {verdict}", fontsize=7.5)
        ax.set_xlim(-2.5, 2.5)
        ax.set_ylim(-15.0, 35.0)
        ax.tick_params(labelsize=7)
        if i % 2 == 0:
            ax.set_ylabel("height above the mean seabed (cm)", fontsize=7)
        if i // 2 == 1:
            ax.set_xlabel("lateral (m, starboard +)", fontsize=7)
        if i == 0:
            ax.legend(fontsize=6, loc="upper left")
    fig.suptitle(
        f"look-ahead multibeam profiles ({sonar.n_beams} beams, ±{0.5 * sonar.swath_deg:g}°, tilt "
        f"{sonar.pitch_deg:g}°), a {100 * diameter:g} cm pipe crossing at {math.degrees(angle):.0f}°; "
        "camera footprint grey",
        fontsize=8,
    )
    fig.tight_layout()
    save_figure(fig, path)
    return fixes


@dataclass(frozen=True)
class TrackedEpisode:
    """One episode through the tracked camera, per decision (after it): what :func:`tracker_figure` draws."""

    pipe: object  # the Pipeline
    poses: np.ndarray  # (n, 3) x north, y east, ψ
    detected: np.ndarray  # (n,) bool: the detector found the pipe in the frame
    detection: np.ndarray  # (n, 4) x1, y1, x2, y_near of the detection (camera frame)
    tracked: np.ndarray  # (n,) bool: the tracker holds a line
    line: np.ndarray  # (n, 2) θ, d of the tracked line
    cov: np.ndarray  # (n, 2, 2) its covariance
    in_view: np.ndarray  # (n,) bool: the observation's pipe in view (the tracker's)
    true_in_view: np.ndarray  # (n,) bool: the exact camera's


def tracker_episode(suite: str, index: int, water: str = "clear", seconds: float = 60.0, noise_seed: int = 0):
    """The heuristic through the tracked camera on pipe ``index`` of ``suite`` (module docstring)."""
    from pipefollow.envs.env import PipelineFollowingEnv
    from pipefollow.evaluation.benchmark import _noise_rng
    from pipefollow.learners.heuristic import Heuristic
    from pipefollow.perception import track_step as tr
    from pipefollow.sim import decision as sim
    from pipefollow.sim.suites import get_suite, min_length_for

    pipe = get_suite(suite).pipes(index + 1, min_length_for(seconds))[index]
    env = PipelineFollowingEnv(pipe, seconds, camera="vision", water=water)
    env.np_random = _noise_rng(noise_seed, index)
    agent = Heuristic()
    obs, info = env.reset()
    rows = []
    done = False
    while not done:
        a = agent.act(obs, explore=False) if info["pipe_in_view"] else 0.0
        obs, _, terminated, truncated, info = env.step([a])
        done = terminated or truncated
        s, cam = env.state, env._vision
        T = cam.tracker.state
        det = cam.detection
        p = T[tr.P : tr.P + 3]
        rows.append((
            (s[sim.X], s[sim.Y], s[sim.PSI]), det.found, (det.x1, det.y1, det.x2, det.y_near),
            T[tr.ACTIVE] != 0.0, (T[tr.TH], T[tr.D]), ((p[0], p[1]), (p[1], p[2])),
            bool(info["pipe_in_view"]), bool(info["true_pipe_in_view"]),
        ))  # fmt: skip
    cols = list(zip(*rows, strict=True))
    return TrackedEpisode(pipe, *(np.array(c) for c in cols))


def tracker_figure(run: TrackedEpisode, path, title: str = "", every: int = 3) -> dict:
    """Top view and lateral offsets of a :class:`TrackedEpisode`; returns the offsets' error statistics."""
    from pipefollow.envs.render import new_figure, save_figure

    fig = new_figure((8.0, 4.2))
    top, lat = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.0, 1.5]})
    pts = run.pipe.points
    top.plot(pts[:, 1], pts[:, 0], color="0.5", lw=2.5, label="true pipe")
    top.plot(run.poses[:, 1], run.poses[:, 0], color="tab:blue", lw=1.0, label="vehicle")
    hw, depth = PAPER_CAMERA.half_width, PAPER_CAMERA.depth
    n = len(run.poses)
    for k in range(n):
        pose = run.poses[k]
        if run.detected[k]:
            x1, y1, x2, yn = run.detection[k]
            north, east = to_world(pose, [x2, x1], [yn, y1])
            top.plot(east, north, color="red", lw=0.6, alpha=0.7, label="detection" if k == 0 else None)
        if run.tracked[k] and k % every == 0:  # the tracked line across the footprint
            th, d = run.line[k]
            y = np.array([0.0, depth])
            x = d / math.cos(th) + y * math.tan(th)
            if np.all(np.abs(x) <= 2.0 * hw):
                north, east = to_world(pose, x, y)
                top.plot(east, north, color="orange", lw=1.2, label="tracked line" if k == 0 else None)
    span = np.concatenate([run.poses[:, :2], run.poses[:, :2] + 3.0, run.poses[:, :2] - 3.0])
    top.set_xlim(span[:, 1].min(), span[:, 1].max())
    top.set_ylim(span[:, 0].min(), span[:, 0].max())
    top.set_aspect("equal")
    top.set_xlabel("east (m)", fontsize=7)
    top.set_ylabel("north (m)", fontsize=7)
    top.tick_params(labelsize=7)
    handles, labels = top.get_legend_handles_labels()
    top.legend(dict(zip(labels, handles, strict=False)).values(), dict.fromkeys(labels), fontsize=6)
    t = np.arange(1, n + 1, dtype=float)
    truth = np.array([lateral_at(pts, run.poses[k]) for k in range(n)])
    est = np.full(n, np.nan)
    sd = np.full(n, np.nan)
    for k in range(n):
        if run.tracked[k] and abs(math.cos(run.line[k][0])) >= STEEP:
            est[k], sd[k] = line_lateral(run.line[k][0], run.line[k][1], run.cov[k])
    lat.plot(t, truth, color="green", lw=1.2, label=f"true pipe {Y_REF:g} m ahead")
    lat.plot(t, est, color="orange", lw=1.0, label="tracked line")
    lat.fill_between(t, est - 2.0 * sd, est + 2.0 * sd, color="orange", alpha=0.25, lw=0, label="±2σ")
    missed = t[~run.detected]
    lat.plot(missed, np.full(len(missed), -hw - 0.15), "|", color="red", ms=6, label="no detection")
    lat.axhspan(-hw, hw, color="0.95", lw=0, zorder=0)
    lat.set_ylim(-hw - 0.3, hw + 0.3)
    lat.set_xlabel("decision (s)", fontsize=7)
    lat.set_ylabel("lateral offset (m, starboard +)", fontsize=7)
    lat.tick_params(labelsize=7)
    lat.legend(fontsize=6, loc="upper right")
    both = np.isfinite(est) & np.isfinite(truth)
    err = est[both] - truth[both]
    stats = {
        "decisions": n,
        "detected": int(run.detected.sum()),
        "tracked": int(run.tracked.sum()),
        "compared": int(both.sum()),
        "rms_error_m": float(np.sqrt(np.mean(err**2))) if err.size else math.nan,
        "within_2sd": float(np.mean(np.abs(err) <= 2.0 * sd[both])) if err.size else math.nan,
    }
    fig.suptitle(
        f"{title or run.pipe.name}: the heuristic through the camera and the tracker\noffset error RMS "
        f"{100 * stats['rms_error_m']:.1f} cm, within ±2σ at {stats['within_2sd']:.0%} of the "
        f"{stats['compared']} decisions with both",
        fontsize=8,
    )
    fig.tight_layout()
    save_figure(fig, path)
    return stats
