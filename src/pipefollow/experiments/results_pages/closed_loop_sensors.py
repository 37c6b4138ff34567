"""The perception page's section on every controller through every sensor, water and suite.

Source: ``docs/vision/closed_loop_sensors/table.csv`` (``examples/closed_loop_table.py``, with its
``provenance.json``): one row per suite × sensor × water × controller, the ideal camera once per
suite (water ``any``). Per suite three tables with a row per water and controller and a column per
sensor: the mean return with the success rate and the lost pipes, and the paired difference to the
heuristic through the same sensor in the same water (the heuristic's own row: to the heuristic on
the ideal camera); and for every water but clear, the paired difference to the same controller
through the same sensor in clear water. A difference whose 95 % interval excludes 0 is bold.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from pipefollow.experiments.results_pages.markdown import PageError, ci, fill, num, pct, read_csv, table

SOURCE = "vision/closed_loop_sensors/table.csv"
SENSORS = {  # the CSV's sensor → the column's head
    "ideal": "ideal camera",
    "raw": "camera, detector alone",
    "tracker": "camera + tracker",
    "sonar": "sonar",
    "fused": "camera + tracker + sonar",
    "fls": "imaging sonar",
    "fused-fls": "camera + tracker + imaging sonar",
}
WATERS = {"clear": "clear", "moderate": "moderate", "turbid": "turbid", "half-buried": "half buried"}
ANY_WATER = "any"
CLEAR = "clear"  # the water the others are compared with (``vs_clear``)
NEED = (
    "suite", "sensor", "water", "controller", "label", "n_pipes", "mean_return", "ci95_low", "ci95_high",
    "success_rate", "pipe_in_view", "turned_back", "lost_pipes", "vs_same", "vs_same_low", "vs_same_high",
    "vs_ideal", "vs_ideal_low", "vs_ideal_high", "vs_clear", "vs_clear_low", "vs_clear_high",
)  # fmt: skip

TEXT = """\
## Every controller through every sensor

`python examples/closed_loop_table.py --policies FOLDER --out docs/vision/closed_loop_sensors`
({n_rows} rows): the heuristic, LOS and the learned controllers (CACLA and supervised CACLA,
5,000 episodes on `random:mixed`; PPO, 100,000 steps; all on the ideal camera; and PPO trained
the same way through the fused sensor in turbid water, `pipefollow train --algorithm ppo --camera
vision --sensor fused --water turbid`) on {suites}, {pipes} pipes × 60 s each,
noise seed 0, through each sensor: the ideal camera, the rendered camera's detector alone
(`--camera vision-raw`), the detector and the tracker (`--camera vision`), the look-ahead sonar
alone (`--sensor sonar`) and both fused (`--sensor fused --camera vision`), and the same two with
the forward-looking imaging sonar and its map (`--sensor fls`, `--sensor fused-fls --camera
vision`); in clear, moderate and turbid water and with the pipe half buried in clear water
(`--burial 0.5`: half the pipe's width
under sand for the camera, half its diameter for the sonar). The ideal camera sees through any
water: its column repeats in every water.

The first table of each suite: mean return (success, pipes lost: in view at < 80 % of the
decisions). The second: each controller against **the heuristic through the same sensor in the
same water** (paired per pipe, 95 % bootstrap interval; **bold**: the interval excludes 0); the
heuristic's own rows against the heuristic on the ideal camera (the second reference). The third:
each controller in murky water or with the pipe half buried against **the same controller through
the same sensor in clear water** (paired per pipe): what the water, or the sand, costs it.
`pipefollow benchmark --sensor S --camera C --water W` prints the second table's two references for one
cell. In the third table the sonars' columns in moderate and turbid water are 0: turbidity does not
reach them.

* **Against the heuristic through the same sensor**, of {n_cells} learned or LOS cells:
  {n_better} better (interval above 0), {n_worse} worse (below 0), the rest undecided.
* **The heuristic's loss to the ideal camera** (mean, over the waters; per suite): {heuristic_loss}.
* **With the pipe half buried against clear water** (the same controller through the same sensor,
  paired per pipe), of {n_buried} cells: {buried_worse} worse half buried (interval below 0),
  {buried_better} better, the rest undecided; through the camera fused with the multibeam sonar
  {fused_buried}.
* **The best controller per sensor** (the highest mean return over the suites and waters):
  {best}.

{tables}
"""


def _f(text: str) -> float | None:
    return float(text) if text != "" else None


def _rows(docs: Path) -> list[dict[str, str]]:
    rows = read_csv(docs / SOURCE)
    if not rows or any(k not in rows[0] for k in NEED):
        raise PageError(
            f"{docs / SOURCE}: not a table of examples/closed_loop_table.py (columns {list(NEED)})"
        )
    return rows


def _diff(r: dict, key: str) -> str:
    d, lo, hi = _f(r[key]), _f(r[key + "_low"]), _f(r[key + "_high"])
    if d is None:
        return "—"
    text = f"{num(d, 1, True)} {ci(lo, hi, sign=True)}"
    return f"**{text}**" if lo > 0.0 or hi < 0.0 else text


def _cell(r: dict | None) -> str:
    if r is None:
        return "·"
    return f"{num(_f(r['mean_return']))} ({pct(_f(r['success_rate']))}, {int(float(r['lost_pipes']))} lost)"


def suite_tables(rows: Sequence[dict], suite: str) -> str:
    """The tables of one suite (module docstring): the third only with a water other than clear."""
    at = {(r["sensor"], r["water"], r["controller"]): r for r in rows if r["suite"] == suite}
    controllers = list(dict.fromkeys(r["controller"] for r in rows if r["suite"] == suite))
    labels = {r["controller"]: r["label"] for r in rows}
    sensors = [s for s in SENSORS if any(k[0] == s for k in at)]
    waters = [w for w in WATERS if any(k[1] == w for k in at)]

    def get(sensor, water, c):
        return at.get((sensor, ANY_WATER if sensor == "ideal" else water, c))

    def diff(r):
        if r is None:
            return "·"
        return _diff(r, "vs_ideal" if r["controller"] == "heuristic" else "vs_same")

    head = ("water", "controller", *(SENSORS[s] for s in sensors))
    returns = [
        (WATERS[w], labels[c], *(_cell(get(s, w, c)) for s in sensors)) for w in waters for c in controllers
    ]
    diffs = [
        (WATERS[w], labels[c] + (" (vs the ideal camera)" if c == "heuristic" else ""),
         *(diff(get(s, w, c)) for s in sensors))
        for w in waters for c in controllers
    ]  # fmt: skip
    others = [s for s in sensors if s != "ideal"]  # the ideal camera sees through any water
    costs = [
        (WATERS[w], labels[c], *(_diff(r, "vs_clear") if (r := get(s, w, c)) else "·" for s in others))
        for w in waters if w != CLEAR for c in controllers
    ]  # fmt: skip
    text = (
        f"### `{suite}`: mean return (success, pipes lost)\n\n{table(head, returns)}\n\n"
        f"### `{suite}`: against the heuristic through the same sensor\n\n{table(head, diffs)}"
    )
    if costs and others:
        head3 = ("water", "controller", *(SENSORS[s] for s in others))
        text += f"\n\n### `{suite}`: against the same controller in clear water\n\n{table(head3, costs)}"
    return text


def section(docs: Path) -> str:
    """The section's Markdown from the stored table under ``docs``."""
    rows = _rows(docs)
    suites = list(dict.fromkeys(r["suite"] for r in rows))
    others = [r for r in rows if r["controller"] != "heuristic"]
    better = sum(1 for r in others if r["vs_same_low"] != "" and float(r["vs_same_low"]) > 0.0)
    worse = sum(1 for r in others if r["vs_same_high"] != "" and float(r["vs_same_high"]) < 0.0)
    loss = []
    for s in suites:
        parts = []
        for sensor in SENSORS:
            v = [
                float(r["vs_ideal"])
                for r in rows
                if (r["suite"], r["sensor"], r["controller"]) == (s, sensor, "heuristic")
                and r["vs_ideal"] != ""
            ]
            if v:
                parts.append(f"{SENSORS[sensor]} {num(sum(v) / len(v), 1, True)}")
        loss.append(f"`{s}`: " + ", ".join(parts))
    buried = [r for r in rows if r["water"] == "half-buried" and r["vs_clear"] != ""]
    fused = []
    for s in suites:
        cells = [r for r in buried if (r["suite"], r["sensor"]) == (s, "fused")]
        if cells:
            n_worse = sum(1 for r in cells if float(r["vs_clear_high"]) < 0.0)
            fused.append(f"`{s}` {n_worse} of {len(cells)} worse")
    best = []
    labels = {r["controller"]: r["label"] for r in rows}
    for sensor in SENSORS:
        means: dict[str, list[float]] = {}
        for r in rows:
            if r["sensor"] == sensor:
                means.setdefault(r["controller"], []).append(float(r["mean_return"]))
        if means:
            c = max(means, key=lambda k: sum(means[k]) / len(means[k]))
            best.append(f"{SENSORS[sensor]}: {labels[c]} ({num(sum(means[c]) / len(means[c]))})")
    return fill(
        TEXT,
        n_rows=len(rows),
        suites=", ".join(f"`{s}`" for s in suites),
        pipes=", ".join(sorted({r["n_pipes"] for r in rows})),
        n_cells=len(others),
        n_better=better,
        n_worse=worse,
        heuristic_loss="; ".join(loss) or "—",
        n_buried=len(buried),
        buried_worse=sum(1 for r in buried if float(r["vs_clear_high"]) < 0.0),
        buried_better=sum(1 for r in buried if float(r["vs_clear_low"]) > 0.0),
        fused_buried="; ".join(fused) or "—",
        best="; ".join(best),
        tables="\n\n".join(suite_tables(rows, s) for s in suites),
    )
