"""The perception results page: the water presets, the pipe detector, its camera model, the closed loop.

Sources: the code's water presets (:data:`pipefollow.perception.water.WATER_PRESETS`) and
``docs/vision/`` (``pipefollow vision report``: ``report.csv``; ``pipefollow vision calibrate``:
``calibration.json``; ``examples/vision_table.py``: ``closed_loop.csv`` and
``closed_loop_suites.csv``; ``examples/ppo_pixels.py``: ``ppo_pixels.json``).
"""

from __future__ import annotations

from pathlib import Path

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
from pipefollow.perception.water import CLEAR, RANGES, WATER_PRESETS, Water

TITLE = "Results: perception in the loop"
SOURCES = (
    "vision/report.csv",
    "vision/calibration.json",
    "vision/closed_loop.csv",
    "vision/closed_loop_suites.csv",
    "vision/ppo_pixels.json",
)
UNITS = {
    "turbidity": "1/m",
    "light_falloff": "share",
    "blur": "px",
    "noise": "grey levels",
    "snow": "per frame",
    "burial": "share",
    "growth": "share",
    "width": "px",
    "height": "px",
    "pipe_diameter": "m",
    "altitude": "m",
}
PIXELS = "PPO on pixels"

TEXT = """\
Regenerate the stored outputs with `pipefollow vision report --out FOLDER`, `pipefollow vision
calibrate`, `python examples/vision_table.py` and `python examples/ppo_pixels.py` (the how-to:
[Perception in the loop](../guides/vision.md)) and copy them to `docs/vision/`.

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

## What imperfect detection does to every controller

`heldout` (noise seed 0) through the detector, each controller against the
heuristic on the *ideal* camera (paired per-pipe difference, 95 % bootstrap interval); success =
the true pipe in view at ≥ 95 % of the decisions (measured before success also asked that the
pipe be followed forward). "{pixels}" sees only the camera image
({pixel_steps} steps of PPO, seed {pixel_seed}; its training took {pixel_train} s as stored).

{closed_loop}

* **Clear water against the ideal camera**: {clear_vs_ideal}; moderate water:
  {moderate_vs_ideal}.
* **The heuristic pays more**: {h_clear} in clear water against {h_ideal} on the ideal camera
  ({h_clear_diff} {h_clear_ci}), {h_moderate} in moderate water. Its success rate is {h_succ_clear}
  with the detector in clear water against {h_succ_ideal} on the ideal camera; LOS's {los_succ_ideal}
  → {los_succ_clear} (clear), {los_succ_moderate} (moderate), while its return falls from
  {los_ideal} to {los_clear} and {los_moderate}.
* **Turbid water breaks every controller**: from the ideal camera to turbid water the returns fall
  by {turbid_drop_lo} to {turbid_drop_hi} points, while the true pipe stays in view
  {turbid_view_lo}–{turbid_view_hi} of the time.
* **{pixels}**: in clear water {px_clear} with {px_succ_clear} success ({px_clear_diff} {px_clear_ci}
  against the heuristic on the ideal camera), {px_gap} points below PPO on the detector's four
  numbers; moderate water costs it {px_moderate_cost} points against PPO's {ppo_moderate_cost}; in
  turbid water {px_turbid} and {px_succ_turbid}.
* **Training under the calibrated camera model** ({calibrated}): against the same recipe without it,
  {calibrated_diffs}.

## On suites the detector was not tuned on

{suite_names}, clear water, noise seed 0:

{suites}
"""


def presets_table() -> str:
    """Every field of :class:`Water` per preset, with the field's unit and range; generated from the code."""
    rows = []
    for field in Water._fields:
        lo, hi, closed = RANGES[field]
        values = []
        for w in WATER_PRESETS.values():
            v = getattr(w, field)
            text = f"{v:g}"
            values.append(f"**{text}**" if v != getattr(CLEAR, field) and w is not CLEAR else text)
        rows.append(
            (
                f"`{field}`",
                UNITS.get(field, ""),
                f"{'[' if closed else '('}{lo:g}, {hi:g}]",
                f"{getattr(Water(), field):g}",
                *values,
            )
        )
    return table(("field", "unit", "range", "default", *(f"`{p}`" for p in WATER_PRESETS)), rows)


def render(docs: Path) -> str:
    """The page's Markdown from the stored outputs under ``docs``."""
    v = docs / "vision"
    report = read_csv(v / "report.csv")
    cal = read_json(v / "calibration.json")
    loop = read_csv(v / "closed_loop.csv")
    pixels = read_json(v / "ppo_pixels.json")
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

    rows = [dict(r) for r in loop]
    for p in pixels["rows"]:
        rows.append(
            {
                "water": p["water"],
                "controller": PIXELS,
                "mean_return": p["mean_return"],
                "ci95_low": p["ci95_mean"][0],
                "ci95_high": p["ci95_mean"][1],
                "success_rate": p["success_rate"],
                "pipe_in_view": p["pipe_in_view"],
                "mean_diff": p["mean_diff"],
                "ci95_diff_low": p["ci95_diff"][0],
                "ci95_diff_high": p["ci95_diff"][1],
            }
        )
    cell = {
        (r["controller"], r["water"]): {
            k: (float(x) if k not in ("water", "controller") else x) for k, x in r.items()
        }
        for r in rows
    }
    controllers = list(dict.fromkeys(r["controller"] for r in rows))
    closed = table(
        (
            "controller",
            "camera",
            "mean return [95 % CI]",
            "success",
            "pipe in view",
            "vs heuristic, ideal camera [95 % CI]",
        ),
        (
            (
                c,
                w,
                f"{num(x['mean_return'])} {ci(x['ci95_low'], x['ci95_high'])}",
                pct(x["success_rate"]),
                pct(x["pipe_in_view"], 1),
                "—"
                if (c, w) == ("heuristic", "ideal")
                else num(x["mean_diff"], 1, True)
                + " "
                + ci(x["ci95_diff_low"], x["ci95_diff_high"], sign=True),
            )
            for (c, w), x in cell.items()
        ),
    )

    def g(c: str, w: str, k: str = "mean_return") -> float:
        try:
            return cell[c, w][k]
        except KeyError:
            raise PageError(f"vision: no closed-loop row for {c!r} in {w!r} water") from None

    learned = [
        c
        for c in controllers
        if c not in ("heuristic", PIXELS) and not c.startswith("LOS") and "calibrated" not in c
    ]
    los = next(c for c in controllers if c.startswith("LOS"))
    ppo = next(c for c in controllers if c.startswith("PPO") and c != PIXELS)
    calibrated = next(c for c in controllers if "calibrated" in c)
    base = next(c for c in learned if calibrated.startswith(c))
    waters = list(dict.fromkeys(r["water"] for r in rows))
    drop = [g(c, "ideal") - g(c, "turbid") for c in controllers]
    view = [g(c, "turbid", "pipe_in_view") for c in controllers if c != PIXELS]
    body = fill(
        TEXT,
        presets=presets_table(),
        report=rep,
        calibration=calib,
        preset_models=preset_models,
        frames=count(float(report[0]["frames_without_pipe"])),
        pixels=PIXELS,
        pixel_steps=count(pixels["steps"]),
        pixel_seed=pixels["seed"],
        pixel_train=f"{pixels['train_seconds']:.0f}",
        closed_loop=closed,
        clear_vs_ideal="; ".join(f"{c} {num(g(c, 'clear'))} against {num(g(c, 'ideal'))}" for c in learned),
        moderate_vs_ideal="; ".join(f"{c} {num(g(c, 'moderate'))}" for c in learned),
        h_clear=num(g("heuristic", "clear")),
        h_ideal=num(g("heuristic", "ideal")),
        h_clear_diff=num(g("heuristic", "clear", "mean_diff"), 1, True),
        h_clear_ci=ci(
            g("heuristic", "clear", "ci95_diff_low"), g("heuristic", "clear", "ci95_diff_high"), sign=True
        ),
        h_moderate=num(g("heuristic", "moderate")),
        h_succ_clear=pct(g("heuristic", "clear", "success_rate")),
        h_succ_ideal=pct(g("heuristic", "ideal", "success_rate")),
        los_succ_ideal=pct(g(los, "ideal", "success_rate")),
        los_succ_clear=pct(g(los, "clear", "success_rate")),
        los_succ_moderate=pct(g(los, "moderate", "success_rate")),
        los_ideal=num(g(los, "ideal")),
        los_clear=num(g(los, "clear")),
        los_moderate=num(g(los, "moderate")),
        turbid_drop_lo=num(min(drop)),
        turbid_drop_hi=num(max(drop)),
        turbid_view_lo=pct(min(view), 1),
        turbid_view_hi=pct(max(view), 1),
        px_clear=num(g(PIXELS, "clear")),
        px_succ_clear=pct(g(PIXELS, "clear", "success_rate")),
        px_clear_diff=num(g(PIXELS, "clear", "mean_diff"), 1, True),
        px_clear_ci=ci(g(PIXELS, "clear", "ci95_diff_low"), g(PIXELS, "clear", "ci95_diff_high"), sign=True),
        px_gap=num(g(ppo, "clear") - g(PIXELS, "clear")),
        px_moderate_cost=num(g(PIXELS, "clear") - g(PIXELS, "moderate")),
        ppo_moderate_cost=num(g(ppo, "clear") - g(ppo, "moderate")),
        px_turbid=num(g(PIXELS, "turbid")),
        px_succ_turbid=pct(g(PIXELS, "turbid", "success_rate")),
        calibrated=calibrated,
        calibrated_diffs="; ".join(f"{w} {num(g(calibrated, w) - g(base, w), 1, True)}" for w in waters),
        suite_names=", ".join(f"`{n}`" for n in dict.fromkeys(s["suite"] for s in suites)),
        suites=table(
            (
                "suite",
                "controller",
                "camera",
                "mean return [95 % CI]",
                "success",
                "vs heuristic, ideal camera",
            ),
            (
                (
                    s["suite"],
                    s["controller"],
                    s["camera"],
                    f"{num(float(s['mean_return']))} {ci(float(s['ci95_low']), float(s['ci95_high']))}",
                    pct(float(s["success_rate"])),
                    num(float(s["vs_heuristic_ideal"]), 1, True) if s["vs_heuristic_ideal"] else "—",
                )
                for s in suites
            ),
        ),
    )
    provenance = [(s, stored_provenance(docs / "vision")) for s in SOURCES]
    return page(TITLE, __name__, SOURCES, provenance, body)
