"""The perception results page: the water presets, the pipe detector, its camera model, the closed loop.

Sources: the code's water presets (:data:`pipefollow.perception.water.WATER_PRESETS`) and
``docs/vision/`` (``pipefollow vision report``: ``report.csv``; ``pipefollow vision calibrate``:
``calibration.json``; ``examples/vision_table.py``: ``closed_loop.csv`` and, with ``--suites``,
``closed_loop_suites.csv``, both with the raw detector and with the tracker and today's success;
``examples/ppo_pixels.py``: ``ppo_pixels.json`` with the tracker and ``ppo_pixels_raw.json`` with
the detector alone; each file says which camera and success it was measured with;
``examples/closed_loop_table.py``: ``closed_loop_sensors/table.csv``, the section of
:mod:`~pipefollow.experiments.results_pages.closed_loop_sensors`).
"""

from __future__ import annotations

from pathlib import Path

from pipefollow.experiments.results_pages import closed_loop_sensors
from pipefollow.experiments.results_pages.markdown import (
    PageError,
    ci,
    count,
    fill,
    num,
    page,
    pct,
    read_csv,
    read_json,
    stored_provenance,
    table,
)
from pipefollow.experiments.results_pages.water_presets import presets_table
from pipefollow.perception.water import WATER_PRESETS

TITLE = "Results: perception in the loop"
SOURCES = (
    "vision/report.csv",
    "vision/calibration.json",
    "vision/closed_loop.csv",
    "vision/closed_loop_suites.csv",
    "vision/ppo_pixels.json",
    "vision/ppo_pixels_raw.json",
    closed_loop_sensors.SOURCE,
)
PIXELS = "PPO on pixels"
PIXELS_NOW = "in view and followed forward"  # examples/ppo_pixels.py's SUCCESS; older files lack the key

TEXT = """\
Regenerate the stored outputs with `pipefollow vision report --out FOLDER`, `pipefollow vision
calibrate`, `python examples/vision_table.py` (with and without `--suites`), `python
examples/ppo_pixels.py` and `python examples/closed_loop_table.py` (the how-to: [Perception in the
loop](../guides/vision.md)) and copy them to `docs/vision/`, each with the `NAME.provenance.json`
written beside it; the figures with `python examples/perception_figures.py --out docs/vision`.

## The water presets

Every field of `pipefollow.perception.water.Water` as each preset sets it (generated from the code;
**bold**: differs from the default record). The presets change blur, sensor noise and marine snow
with the turbidity; `--water PRESET` selects one, `--turbidity`, `--burial` and `--growth` change
it.

{presets}

## How good is the detector

`pipefollow vision report`: {frames} poses along the heuristic's trajectories on the held-out pipes,
each rendered with the pipe and without it (false detections); end-point error against the exact
camera's visible piece, "gross" = an end more than 30 cm off.

{report}

![sample frames: truth green, detection red](../vision/samples.png)

## The camera model calibrated from it

`pipefollow vision calibrate` fits the simulator's camera noise and miss probability per turbidity
(the Gaussian model has no gross errors; they are listed apart):

{calibration}

At the presets' turbidities: {preset_models}.

## What the sonar and the tracker see

The look-ahead multibeam's profiles (`python examples/perception_figures.py`): the beams' heights
above the mean seabed across the fan, the fitted seabed, the true pipe's section (green) and the
detection (red), for a pipe lying on a flat and a rough seabed and half buried in it:

![sonar profiles: truth green, detection red](../vision/sonar_profiles.png)

The tracker along one episode of the heuristic through the camera and the tracker on a
`heldout-sharp` pipe in moderate water: the top view with the detections (red) and the tracked
line (orange, every third decision), and the pipe's lateral offset 1.5 m ahead, true against
tracked with the tracker's ±2σ (red ticks: frames without a detection):

![the tracker along an episode](../vision/tracker_episode.png)

## What imperfect detection does to every controller

`heldout` (100 pipes × 60 s, noise seed 0) through the rendered camera: **`vision-raw`** is the
detector alone, frame by frame; **`vision`** the detector and the pipe tracker
(`pipefollow.perception.tracker`). Each controller against the heuristic on the *ideal* camera
(paired per-pipe difference, 95 % bootstrap interval). Success is today's: the true pipe in view
at ≥ 95 % of the decisions **and** followed forward (`pipefollow.evaluation.success`).

{closed_loop}

* **The tracker against the detector alone** (mean return, `vision` − `vision-raw`, clear /
  moderate / turbid water): {tracker_vs_raw}.
* **Clear water against the ideal camera** (ideal; raw; tracker): {clear_vs_ideal}.
* **The heuristic**: {h_ideal} on the ideal camera; in clear water {h_clear_raw} with the detector
  alone ({h_clear_raw_diff} {h_clear_raw_ci}) and {h_clear} with the tracker ({h_clear_diff}
  {h_clear_ci}); in moderate water {h_moderate_raw} and {h_moderate}. Its success is {h_succ_ideal}
  on the ideal camera, {h_succ_clear_raw} (raw) and {h_succ_clear} (tracker) in clear water; LOS's
  {los_succ_ideal} → {los_succ_clear_raw} and {los_succ_clear}, while its return goes from
  {los_ideal} to {los_clear_raw} and {los_clear}.
* **Turbid water breaks every controller**: from the ideal camera to turbid water the returns fall
  by {turbid_drop_lo} to {turbid_drop_hi} points with the detector alone and by {turbid_drop_lo_t}
  to {turbid_drop_hi_t} with the tracker, while the true pipe stays in view
  {turbid_view_lo}–{turbid_view_hi} of the time.
* **Training under the calibrated camera model** ({calibrated}): against the same recipe without it,
  {calibrated_diffs}. Each is one training of the same seed: a difference between two trainings,
  not a measured effect of the camera model (retrained under the calibration measured again, which
  had moved by a few percent, the calibrated policy's returns moved by more than this difference;
  docs/decisions.md, "the `vision` preset").

## PPO on pixels

`examples/ppo_pixels.py`: "{pixels}" sees only the camera image (PPO with the project's defaults
on a small convolutional network, `random:mixed` in clear water; {pixel_runs}); "in view or
search" comes from the camera it was trained with, which also judges it: the tracker
(`--camera vision`, the default: `ppo_pixels.json`) or the detector alone (`--camera vision-raw`:
`ppo_pixels_raw.json`). The rows "ideal" are the policy on the image of clear water with the exact
camera's in-view decision. {pixel_success_text} Each row is one training seed: with the tracker,
other seeds and small changes of the code swing it widely, some training runs not learning at all
(docs/decisions.md, "PPO on pixels with the tracker").

{pixel_table}

## The held-out suites by difficulty

{suite_names}, clear water, noise seed 0, 100 pipes each; success is today's. The tracker's
settings were chosen on `heldout`, `heldout-hard` and `heldout-sharp` (docs/decisions.md, "Pipe
tracker, sharp turns and the vision reset"), so its rows there are not unbiased held-out figures.

{suites}

{sensors}

## Which success each stored output uses

* `closed_loop.csv`, `closed_loop_suites.csv` (`examples/vision_table.py`): today's success (in view
  ≥ 95 % and followed forward), today's detector, both rendered cameras.
* `ppo_pixels.json`, `ppo_pixels_raw.json` (`examples/ppo_pixels.py`): {pixel_success}.
* `closed_loop_sensors/table.csv` (`examples/closed_loop_table.py`): today's success, today's
  detector, tracker and sonar.
* `closed_loop_one_leg.csv`: **historical**, not shown here: the detector before it followed bends
  (one straight leg), an earlier renderer, earlier policies and the earlier success.
* `report.csv`, `calibration.json`, `samples.png` (`pipefollow vision report`, `pipefollow vision
  calibrate`): single frames judged by today's detector; no episodes, no success.
"""


def render(docs: Path) -> str:
    """The page's Markdown from the stored outputs under ``docs``."""
    v = docs / "vision"
    report = read_csv(v / "report.csv")
    cal = read_json(v / "calibration.json")
    loop = read_csv(v / "closed_loop.csv")
    pixel_runs = [read_json(v / "ppo_pixels.json"), read_json(v / "ppo_pixels_raw.json")]
    suites = read_csv(v / "closed_loop_suites.csv")

    rep = table(
        (
            "turbidity (1/m)",
            "burial",
            "frames with the pipe in view",
            "found",
            "false detections",
            "median error (cm)",
            "90th percentile (cm)",
            "gross errors",
        ),
        (
            (
                f"{float(r['turbidity']):g}",
                f"{float(r['burial']):g}",
                count(float(r["frames_in_view"])),
                pct(float(r["detection_rate"]), 1),
                pct(float(r["false_detection_rate"]), 1),
                f"{float(r['median_error_cm']):.2f}",
                f"{float(r['p90_error_cm']):.1f}",
                pct(float(r["gross_error_rate"]), 1),
            )
            for r in report
        ),
    )
    calib = table(
        ("turbidity (1/m)", "camera noise (m)", "miss probability", "gross errors (apart)"),
        (
            (
                f"{c['turbidity']:g}",
                f"{c['camera_noise']:.4f}",
                f"{c['miss_prob']:.4f}",
                pct(c["gross_error_rate"], 1),
            )
            for c in cal
        ),
    )
    by_turb = {round(c["turbidity"], 6): c for c in cal}
    preset_models = "; ".join(
        f"`{name}` ({w.turbidity:g}/m): `--camera-noise {by_turb[round(w.turbidity, 6)]['camera_noise']:.3f} "
        f"--miss-prob {by_turb[round(w.turbidity, 6)]['miss_prob']:.3f}`"
        for name, w in WATER_PRESETS.items()
        if round(w.turbidity, 6) in by_turb
    )

    cell = {(r["controller"], r["camera"], r["water"]): r for r in loop}

    def f(x: str) -> float | None:
        return float(x) if x != "" else None

    def g(c: str, camera: str, w: str, k: str = "mean_return") -> float:
        try:
            x = f(cell[c, camera, w][k])
        except KeyError:
            raise PageError(f"vision: no closed-loop row for {c!r}, camera {camera!r}, water {w!r}") from None
        if x is None:
            raise PageError(
                f"vision: the closed-loop row for {c!r}, camera {camera!r}, water {w!r} has no {k}"
            )
        return x

    def diff(r: dict) -> str:
        if r["mean_diff"] == "":
            return "—"
        return (
            num(f(r["mean_diff"]), 1, True)
            + " "
            + ci(f(r["ci95_diff_low"]), f(r["ci95_diff_high"]), sign=True)
        )

    closed = table(
        (
            "controller",
            "camera",
            "water",
            "mean return [95 % CI]",
            "success",
            "pipe in view",
            "vs heuristic, ideal camera [95 % CI]",
        ),
        (
            (
                r["controller"],
                f"`{r['camera']}`",
                "—" if r["camera"] == "ideal" else r["water"],
                f"{num(f(r['mean_return']))} {ci(f(r['ci95_low']), f(r['ci95_high']))}",
                pct(f(r["success_rate"])),
                pct(f(r["pipe_in_view"]), 1),
                diff(r),
            )
            for r in loop
        ),
    )
    controllers = list(dict.fromkeys(r["controller"] for r in loop))
    learned = [
        c for c in controllers if c != "heuristic" and not c.startswith("LOS") and "calibrated" not in c
    ]
    los = next(c for c in controllers if c.startswith("LOS"))
    calibrated = next(c for c in controllers if "calibrated" in c)
    base = next(c for c in learned if calibrated.startswith(c))
    waters = ("clear", "moderate", "turbid")
    raw, tracked = "vision-raw", "vision"
    drop = {
        cam: [g(c, "ideal", "ideal") - g(c, cam, "turbid") for c in controllers] for cam in (raw, tracked)
    }
    view = [g(c, cam, "turbid", "pipe_in_view") for c in controllers for cam in (raw, tracked)]

    def camera_of(run: dict) -> str:
        now = run.get("success") == PIXELS_NOW and "camera" in run
        return f"`{run['camera']}`" if now else "the detector then (earlier success)"

    pixel_table = table(
        (
            "trained and judged with",
            "camera",
            "mean return [95 % CI]",
            "success",
            "pipe in view",
            "vs heuristic, ideal camera [95 % CI]",
        ),
        (
            (
                camera_of(run),
                "ideal (image of clear water)" if p["water"] == "ideal" else f"{p['water']} water",
                f"{num(p['mean_return'])} {ci(*p['ci95_mean'])}",
                pct(p["success_rate"]),
                pct(p["pipe_in_view"], 1),
                num(p["mean_diff"], 1, True) + " " + ci(*p["ci95_diff"], sign=True),
            )
            for run in pixel_runs
            for p in run["rows"]
        ),
    )
    all_now = all(run.get("success") == PIXELS_NOW and "camera" in run for run in pixel_runs)
    body = fill(
        TEXT,
        presets=presets_table(),
        report=rep,
        calibration=calib,
        preset_models=preset_models,
        frames=count(float(report[0]["frames_without_pipe"])),
        pixels=PIXELS,
        pixel_runs="; ".join(
            f"{camera_of(run)}: {count(run['steps'])} steps, seed {run['seed']}, "
            f"training {run['train_seconds']:.0f} s as stored"
            for run in pixel_runs
        ),
        pixel_table=pixel_table,
        pixel_success_text=(
            "Success is today's."
            if all_now
            else "A file without its camera and success was measured with the detector before it "
            "joined hooks, without the tracker, and the earlier success (in view ≥ 95 % only): not "
            "comparable row by row with the table above."
        ),
        pixel_success=(
            "today's success, each with the camera it names"
            if all_now
            else "a file that names no camera and success: the earlier success (in view ≥ 95 % only) and "
            "the detector before it joined hooks, without the tracker"
        ),
        closed_loop=closed,
        tracker_vs_raw="; ".join(
            f"{c} " + " / ".join(num(g(c, tracked, w) - g(c, raw, w), 1, True) for w in waters)
            for c in controllers
        ),
        clear_vs_ideal="; ".join(
            f"{c} {num(g(c, 'ideal', 'ideal'))}; {num(g(c, raw, 'clear'))}; {num(g(c, tracked, 'clear'))}"
            for c in learned
        ),
        h_ideal=num(g("heuristic", "ideal", "ideal")),
        h_clear_raw=num(g("heuristic", raw, "clear")),
        h_clear_raw_diff=num(g("heuristic", raw, "clear", "mean_diff"), 1, True),
        h_clear_raw_ci=ci(
            g("heuristic", raw, "clear", "ci95_diff_low"),
            g("heuristic", raw, "clear", "ci95_diff_high"),
            sign=True,
        ),
        h_clear=num(g("heuristic", tracked, "clear")),
        h_clear_diff=num(g("heuristic", tracked, "clear", "mean_diff"), 1, True),
        h_clear_ci=ci(
            g("heuristic", tracked, "clear", "ci95_diff_low"),
            g("heuristic", tracked, "clear", "ci95_diff_high"),
            sign=True,
        ),
        h_moderate_raw=num(g("heuristic", raw, "moderate")),
        h_moderate=num(g("heuristic", tracked, "moderate")),
        h_succ_ideal=pct(g("heuristic", "ideal", "ideal", "success_rate")),
        h_succ_clear_raw=pct(g("heuristic", raw, "clear", "success_rate")),
        h_succ_clear=pct(g("heuristic", tracked, "clear", "success_rate")),
        los_succ_ideal=pct(g(los, "ideal", "ideal", "success_rate")),
        los_succ_clear_raw=pct(g(los, raw, "clear", "success_rate")),
        los_succ_clear=pct(g(los, tracked, "clear", "success_rate")),
        los_ideal=num(g(los, "ideal", "ideal")),
        los_clear_raw=num(g(los, raw, "clear")),
        los_clear=num(g(los, tracked, "clear")),
        turbid_drop_lo=num(min(drop[raw])),
        turbid_drop_hi=num(max(drop[raw])),
        turbid_drop_lo_t=num(min(drop[tracked])),
        turbid_drop_hi_t=num(max(drop[tracked])),
        turbid_view_lo=pct(min(view), 1),
        turbid_view_hi=pct(max(view), 1),
        calibrated=calibrated,
        calibrated_diffs="; ".join(
            f"{w} {num(g(calibrated, raw, w) - g(base, raw, w), 1, True)} (raw), "
            f"{num(g(calibrated, tracked, w) - g(base, tracked, w), 1, True)} (tracker)"
            for w in waters
        ),
        sensors=closed_loop_sensors.section(docs),
        suite_names=", ".join(f"`{n}`" for n in dict.fromkeys(s["suite"] for s in suites)),
        suites=table(
            (
                "suite",
                "controller",
                "camera",
                "mean return [95 % CI]",
                "success",
                "pipe in view",
                "vs heuristic, ideal camera [95 % CI]",
            ),
            (
                (
                    s["suite"],
                    s["controller"],
                    f"`{s['camera']}`",
                    f"{num(f(s['mean_return']))} {ci(f(s['ci95_low']), f(s['ci95_high']))}",
                    pct(f(s["success_rate"])),
                    pct(f(s["pipe_in_view"]), 1),
                    "—"
                    if s["vs_heuristic_ideal"] == ""
                    else num(f(s["vs_heuristic_ideal"]), 1, True)
                    + " "
                    + ci(f(s["ci95_diff_low"]), f(s["ci95_diff_high"]), sign=True),
                )
                for s in suites
            ),
        ),
    )
    provenance = [(s, stored_provenance(docs / s)) for s in SOURCES]
    return page(TITLE, __name__, SOURCES, provenance, body)
